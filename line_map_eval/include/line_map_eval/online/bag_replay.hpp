// linemap_batch's replay mode (ROS-free): a bag's scans, transforms and trajectories fed, in bag
// order, to the same online mapper and online evaluator the nodelets drive (extraction -> merging
// nodelet -> evaluator nodelet), so the batch map is the map the nodelets make of the same bag.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "line_map_eval/datasets/bag_reader.hpp"
#include "line_map_eval/online/map_evaluator.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
struct ReplayOptions
{
  linemap::ParamSet params;  ///< every parameter by its config/*.yaml name (as the nodelets read them)
  std::string method = "cae";
  bool trajectories = true;  ///< feed the bag's optimized_trajectory messages
};

struct ReplayResult
{
  std::size_t scans = 0, trajectories = 0;
  std::vector<double> keyframe_stamps;  ///< in the order they were merged
  std::vector<line_map_merging::MapSegment> map;
  std::size_t leaves = 0;
  line_map_merging::MapperCounters counters;
  std::optional<MapMetrics> metrics;  ///< of the final map, as the evaluator nodelet scores it
  std::size_t evaluator_scans = 0;
  double wall_ms = 0.0;
};

/// Replays `bag`: per scan, in bag order, the segments of the extractor, posed by map -> odom (the
/// bag's samples, interpolated; none: the odometry frame is the map frame) -> base -> laser, into
/// the online mapper and evaluator; after a scan, each trajectory message stamped at or before it.
/// Throws linemap::ParameterError naming a bad parameter.
ReplayResult replayBag(const BagContents& bag, const ReplayOptions& options);

/// Writes the result as JSON (keyframe stamps, map segments with ids and endpoints, counters,
/// metrics). Throws std::runtime_error naming the file.
void writeReplayJson(const ReplayResult& result, const std::string& path);

}  // namespace line_map_eval
