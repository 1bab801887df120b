// Mapping in two sessions (ROS-free), the measurement of `linemap_relations --two-sessions`: the recording
// cut at a scan; the SLAM maps the first part and saves its session; the second part, its odometry starting
// again at zero as after a restart, is first localized in the saved session (global localization on the
// saved keyframes' surfaces, no start pose given), then continues the session from there.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"

namespace line_map_eval
{
/// Scans [first, last) of `recording`; `rezero`: their odometry starts again at zero (a restarted robot).
Recording recordingPart(const Recording& recording, std::size_t first, std::size_t last, bool rezero);

/// The saved keyframes' surfaces (scan_surfaces) in the session's map frame: a line map to localize in.
std::vector<linemap::Segment2> sessionSurfaces(const line_map_merging::SlamSession& session);

struct TwoSessionRun
{
  /// Every scan's pose in the first session's map frame (the first part's as the joined graph left them);
  /// none for the second part's scans before it was localized, or where the SLAM rejected a scan.
  std::vector<std::optional<Pose2>> scan_poses;
  std::size_t cut = 0;
  /// The second part's scan at which global localization accepted a pose (0 with a given start); none:
  /// never (then the second part is not mapped).
  std::optional<std::size_t> localized_at;
  std::size_t closures_between = 0;  ///< loop edges joining the two sessions' keyframes
  line_map_merging::SlamCounters first_counters, second_counters;
  double cpu_seconds = 0.0;  ///< both SLAM runs and the localization
};

/// Maps `recording` in two sessions cut at scan `cut` (above); the localization looks for the second part's
/// start in its first `localize_scans` scans. A given `start` (the second part's first base pose in the
/// first's map frame, as from an initial pose) is taken instead. Either is taken as known to 0.1 m and
/// 0.05 rad.
TwoSessionRun runTwoSessions(const Recording& recording, std::size_t cut,
                             const line_map_merging::LaserSlamParams& slam_params,
                             const line_map_merging::LocalizerParams& localizer_params, bool use_odometry,
                             const std::optional<Pose2>& start = std::nullopt,
                             std::size_t localize_scans = 400);

}  // namespace line_map_eval
