// Mapping in several sessions (ROS-free): runs of a robot (or of several robots with the same laser
// mounting) mapped one after another into one pose graph, each later run first localized in the map of
// those before it (global localization on the saved keyframes' surfaces, unless its start is given) and
// then continuing that session (LaserSlam::continueFrom), optionally after a session loaded from a file.
// `linemap_batch RUN1 RUN2 ... --slam [--session F]` and `linemap_relations --two-sessions` (the recording
// cut at a scan, the second part's odometry starting again at zero as after a restart) drive it.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/slam/session_file.hpp"

namespace line_map_eval
{
/// Scans [first, last) of `recording`; `rezero`: their odometry starts again at zero (a restarted robot).
Recording recordingPart(const Recording& recording, std::size_t first, std::size_t last, bool rezero);

/// Several runs in one graph (runSessions).
struct SessionsRun
{
  /// Per run: every scan's base pose in the common map frame as the final, joined graph left it; none for
  /// the scans of a run that was never localized, scans the SLAM rejected, and scans before a run's first
  /// keyframe.
  std::vector<std::vector<std::optional<Pose2>>> scan_poses;
  /// Per run: its keyframes (index into the run's scans) at their final base poses.
  std::vector<std::vector<CorrectedKeyframe>> keyframes;
  /// Per run: the scan at which it was placed in the map (0: the first run of a new map, or a given start);
  /// none: global localization accepted no pose in the run's first `localize_scans` scans.
  std::vector<std::optional<std::size_t>> localized_at;
  /// Per run not placed in time: the scan at which it was found later. It was mapped apart from its first
  /// scan, and the map so far joined it there (the map frame is then this run's). A run neither placed nor
  /// joined is left out of the graph.
  std::vector<std::optional<std::size_t>> joined_at;
  /// Per run: places found for it that could not be told from a look-alike place (refused).
  std::vector<std::size_t> refused_as_ambiguous;
  /// The saved session's scans (if one was continued), in its order, as the joined graph left them.
  std::vector<Pose2> saved_scan_poses;
  /// Per run: the loop edges joining one of its keyframes to a keyframe of an earlier run or of the saved
  /// session.
  std::vector<std::size_t> closures_to_earlier;
  std::vector<line_map_merging::SlamCounters> counters;  ///< per run (zero for a run left out)
  std::vector<double>
      slam_cpu_seconds;  ///< per run: its SLAM alone (CPU time), the search for its start apart
  line_map_merging::SlamSession session;  ///< the joined graph: what --save-session writes
  double cpu_seconds = 0.0;               ///< every SLAM run and localization
};

/// Maps `runs` into one graph, in order: the first starts a new map (or continues `saved`), each later one
/// is localized in the session so far and continues it. `starts[r]`, where given, is run r's first base
/// pose in the map frame (as from an initial pose) in place of the localization; either is taken as known
/// to 0.1 m and 0.05 rad. The localization looks for a run's start in its first `localize_scans` scans.
SessionsRun runSessions(const std::vector<Recording>& runs,
                        const std::optional<line_map_merging::SlamSession>& saved,
                        const line_map_merging::LaserSlamParams& slam_params,
                        const line_map_merging::LocalizerParams& localizer_params, bool use_odometry,
                        const std::vector<std::optional<Pose2>>& starts = {},
                        std::size_t localize_scans = 400);

/// Shifts the stamps of runs that do not follow the one before them in time (the first: `not_before`, e.g.
/// a saved session's last stamp) to start 1 s after it, so that the runs make one time line (the mapper
/// takes a stamp going back for a replay). Returns each run's shift [s], added to its stamps.
std::vector<double> followInTime(std::vector<Recording>& runs,
                                 double not_before = -std::numeric_limits<double>::infinity());

/// The runs as one recording for the merging and the evaluation (linemap_batch): the scans of every placed
/// run in order, with the joined graph's keyframes as its corrected keyframes. Each run's odometry is moved
/// into the map frame where the graph put its first posed scan, so the odometry goes on across runs as
/// map -> odom would. Without `odometry` (the SLAM ran on the laser alone) each scan's odometry is its SLAM
/// pose (the last posed scan's for one without). Throws std::invalid_argument naming the run when the laser
/// mountings differ.
Recording joinedRecording(const std::vector<Recording>& runs, const SessionsRun& run, bool odometry);

/// The line map of a loaded session for its continuation to go on from (BatchDataset::saved_map): the map
/// file's text, the saved keyframes (the first of `joined`'s) at their poses in the joined graph, and the
/// scan points of those the map holds, all moved by `to_world` (the batch's map frame from the SLAM's).
/// Throws std::runtime_error naming `origin` when the session holds no line map, MapFileError for a bad one.
BatchDataset::SavedMap continuedMap(const line_map_merging::Session& loaded,
                                    const line_map_merging::SlamSession& joined, const std::string& origin,
                                    const Pose2& to_world = Pose2());

struct TwoSessionRun
{
  /// Every scan's pose in the first session's map frame (the first part's as the joined graph left them);
  /// none for the second part's scans before it was localized, or where the SLAM rejected a scan.
  std::vector<std::optional<Pose2>> scan_poses;
  std::size_t cut = 0;
  /// The second part's scan at which global localization accepted a pose (0 with a given start); none:
  /// never (then the second part is not mapped).
  std::optional<std::size_t> localized_at;
  /// Not localized in time: the second part's scan at which it was found later and joined (above).
  std::optional<std::size_t> joined_at;
  std::size_t closures_between = 0;      ///< loop edges joining the two sessions' keyframes
  std::size_t refused_as_ambiguous = 0;  ///< places the search found but could not tell from a look-alike one
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
