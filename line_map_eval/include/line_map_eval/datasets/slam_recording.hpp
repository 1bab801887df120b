// Running the laser SLAM of line_map_merging (laser_slam.hpp) over a whole recording (ROS-free):
// the trajectory source of `linemap_batch --slam` and `linemap_relations --slam`.
#pragma once

#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/slam/laser_slam.hpp"

namespace line_map_eval
{
struct SlamRecordingResult
{
  /// Optimised base pose of every scan of the recording, in scan order.
  std::vector<Pose2> scan_poses;
  /// The keyframes: index into Recording::scans and optimised base pose.
  std::vector<CorrectedKeyframe> keyframes;
  /// Every loop-closure attempt that got as far as a match; `from` and `to` index `keyframes`.
  std::vector<line_map_merging::ClosureAttempt> closures;
  /// The loop-closure edges in the final graph; `from` and `to` index `keyframes`.
  std::vector<line_map_merging::PoseGraphEdge> loop_edges;
  line_map_merging::SlamCounters counters;
  /// What a session file keeps of the run (LaserSlam::session): keyframe and scan indices count the
  /// scans the SLAM accepted.
  line_map_merging::SlamSession session;
  /// Continuing a session: the saved scans' poses in the joined graph, in the session's scan order.
  std::vector<Pose2> continued_scan_poses;
  /// Continuing a session: the scan at which the robot was found (0 with a given start); none: it was not
  /// found, and nothing was mapped (a new run: 0).
  std::optional<std::size_t> placed_at = 0;
  /// Not found in time: the run was mapped apart, and joined the session at this scan, when found later
  /// (none: never found; the run's own map alone).
  std::optional<std::size_t> joined_at;
  /// Continuing a session: places found that could not be told from a look-alike place (refused).
  std::size_t refused_as_ambiguous = 0;
  double seconds = 0.0;  ///< front and back end, the whole recording (wall time)
  double cpu_seconds =
      0.0;  ///< the same in CPU time of this thread, the search for a continuation's start included
  double search_cpu_seconds = 0.0;  ///< of which the search
};

/// A saved session the run goes on from, as the SLAM nodelet's ~session (SessionContinuation): the
/// recording's first scan is at `start` in the session's map frame, or, without one, the robot is first found
/// by global localization in the first `search_scans` scans (then the run starts at the scan it was found
/// at); known to the sigmas.
struct SlamContinuation
{
  line_map_merging::SlamSession session;
  std::optional<Pose2> start;
  double sigma_xy = 0.1, sigma_theta = 0.05;
  line_map_merging::LocalizerParams localizer;
  std::size_t search_scans = 400;
};

/// A front-end slip injected before one scan (LaserSlam::injectFrontEndSlip).
struct FrontEndSlip
{
  std::size_t scan = 0;  ///< index into Recording::scans
  Pose2 slip;
};

/// Feeds every scan (valid beams under its own geometry, in the base frame by the recording's mounting) with
/// its odometry
/// (`use_odometry` false: none, the laser-only case) to a LaserSlam.
SlamRecordingResult runSlam(const Recording& recording, const line_map_merging::LaserSlamParams& params,
                            bool use_odometry = true, const std::optional<FrontEndSlip>& slip = std::nullopt,
                            const SlamContinuation* continuation = nullptr);

/// Scan `index` as the SLAM takes it: its valid beams (under its own geometry) in the base frame by the
/// recording's mounting, with its odometry when `use_odometry`.
line_map_merging::SlamScan slamScan(const Recording& recording, std::size_t index, bool use_odometry = true);

/// The recording with the SLAM keyframes as its corrected keyframes (a loop-closure dataset).
Recording withSlamKeyframes(Recording recording, const SlamRecordingResult& slam);

}  // namespace line_map_eval
