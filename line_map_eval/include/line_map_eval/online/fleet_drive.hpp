// Several robots into one map, offline (ROS-free): the merging nodelet's ~robots on recordings. Each robot's
// scans, posed in its own map frame by its own back end's schedule, go in time order (the robots' scans
// interleaved by stamp) to one OnlineMapper, each robot a lane; the first robot's map frame is the fleet's.
// Every other robot is looked for in the fleet's map (FleetPlacement) until it is placed, its scans held by
// the mapper meanwhile.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "line_map_eval/online/online_drive.hpp"
#include "line_map_merging/localization/fleet_placement.hpp"

namespace line_map_eval
{
/// One robot: its recording, what its back end published (in its own map frame), its segments.
struct FleetRobot
{
  const Recording* recording = nullptr;
  BackEndSchedule schedule;
  SegmentSource segments;
};

struct FleetDrive
{
  /// Per robot: the scan (index into its recording) at which it was placed (0 for the first robot); none:
  /// never.
  std::vector<std::optional<std::size_t>> placed_at;
  /// Per robot: its map frame in the fleet's.
  std::vector<std::optional<Pose2>> placements;
};

/// Feeds every robot's scans and trajectories to `mapper` in time order, placing robots 1... by `placement`.
FleetDrive driveFleet(line_map_merging::OnlineMapper& mapper, line_map_merging::FleetPlacement& placement,
                      const std::vector<FleetRobot>& robots);

}  // namespace line_map_eval
