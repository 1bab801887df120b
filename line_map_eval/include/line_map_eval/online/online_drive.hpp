// The one online path of line_map_eval: a recording's scans, in time order, fed to the OnlineMapper
// the merging nodelet runs (its keyframe gate, its held scans, its trajectories), with the
// trajectories of a SLAM back end between them. linemap_batch drives every online merger through it,
// by default and with --replay, so its maps are the maps the nodelets make of the same data.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_merging/online/online_mapper.hpp"

namespace line_map_eval
{
/// One trajectory as a back end publishes it (a nav_msgs/Path): its stamp and its nodes.
struct TrajectoryEmission
{
  double stamp = 0.0;
  std::vector<std::pair<double, Pose2>> poses;  ///< (stamp, pose of base_link in map)
};

/// What a back end publishes along a recording: its trajectories and the map -> odom transform.
struct BackEndSchedule
{
  std::vector<TrajectoryEmission> trajectories;       ///< in time order
  std::vector<std::pair<double, Pose2>> map_to_odom;  ///< samples in time order; none: identity
};

/// The stand-in for a back end closing loops (what carmen_to_bag and simulate_world write to a bag):
/// after every `every`-th keyframe of `rec` (0: only the last) and after the last, the trajectory of
/// every keyframe so far at its pose; from then on map -> odom puts base_link at that keyframe's pose.
BackEndSchedule loopClosureSchedule(const Recording& rec, std::size_t every);

/// For a recording whose keyframe poses are the only poses: no trajectory; map -> odom at each
/// keyframe's scan puts base_link at the keyframe's pose.
BackEndSchedule fixedPoseSchedule(const Recording& rec);

/// Pose at `t` from samples sorted by time: interpolated between the two around it, clamped at the
/// ends (tf would wait for a later sample; the schedules carry one at every scan).
Pose2 sampleAt(const std::vector<std::pair<double, Pose2>>& samples, double t);

/// What the caller sees on the way (each optional).
struct OnlineDriveHooks
{
  /// Scan `index` as it goes to the mapper (after the mapper took it: its segments are the scan's).
  std::function<void(std::size_t index, const line_map_merging::StampedScan& scan)> scan;
  /// Before trajectory `index` of the schedule goes to the mapper.
  std::function<void(std::size_t index)> before_trajectory;
  /// After the mapper took trajectory `index`.
  std::function<void(std::size_t index, const TrajectoryEmission& trajectory)> trajectory;
};

/// The segments of scan `index` (laser frame), given its laser pose in the odometry frame. Called once
/// per scan, in order (an extractor with state, e.g. the submap, may run inside).
using SegmentSource = std::function<std::vector<linemap::Segment2>(std::size_t index, const Pose2& odom)>;

/// The beams of scan `index` of `rec`, for the map-level lines.
std::shared_ptr<const line_map_merging::KeyframeScan> keyframeScan(const Recording& rec, std::size_t index);

/// Scan `index` of `rec` as the merging nodelet receives it: its segments (`segments`) posed by map -> odom
/// (the schedule's samples) -> odom -> base_link -> laser.
line_map_merging::StampedScan stampedScan(const Recording& rec, const BackEndSchedule& schedule,
                                          const SegmentSource& segments, std::size_t index);

/// Feeds every scan of `rec` in order: its segments posed by map -> odom (the schedule's samples) ->
/// odom -> base_link -> laser, then each trajectory stamped at or before it. Returns the number of
/// trajectories fed.
std::size_t driveOnline(line_map_merging::OnlineMapper& mapper, const Recording& rec,
                        const BackEndSchedule& schedule, const SegmentSource& segments,
                        const OnlineDriveHooks& hooks = {});

}  // namespace line_map_eval
