// Localizing a whole recording in a saved line map (line_map_merging/localization/line_map_localizer.hpp),
// ROS-free: the trajectory source of `linemap_relations --localize` and of the localization benchmark.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"

namespace line_map_eval
{
/// A scan of the recording as the localizer takes it: valid beams in the base frame, its odometry.
line_map_merging::LocalizerScan localizerScan(const Recording& recording, std::size_t index);

struct LocalizationRunResult
{
  std::vector<Pose2> scan_poses;  ///< base pose of every scan in the map frame, in scan order
  std::vector<double> scan_ms;    ///< time the localizer took per scan
  std::vector<bool> localized;    ///< the pose is tracked, not a global-localization hypothesis
  /// Without an initial pose: the scan at which global localization accepted a pose (the run is then
  /// repeated from the first scan, started at that pose carried back by the odometry).
  std::optional<std::size_t> recovered_at;
  line_map_merging::LocalizerCounters counters;
  double cpu_seconds = 0.0;
};

/// Localizes scans [first, last) of `recording` (last 0: to the end) from `initial` (the base pose of
/// scan `first`), or by global localization without one.
LocalizationRunResult runLocalization(const Recording& recording,
                                      const std::vector<linemap::Segment2>& map_segments,
                                      const line_map_merging::LocalizerParams& params,
                                      const std::optional<Pose2>& initial, std::size_t first = 0,
                                      std::size_t last = 0);

}  // namespace line_map_eval
