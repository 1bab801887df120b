// A building that changed between two mapping sessions (ROS-free): the robot maps a world, then drives
// the same path again in the world after its changes (config/worlds/*_changed.yaml, `based_on`) and
// continues the first session: the SLAM is placed in the saved graph and goes on, and CAE-RLSM goes on
// from the saved map with its provenance, retiring what the second session sees through (see_through).
// The maps are scored on the removed, added and unchanged walls (change_coverage.hpp) and by q against
// the building as it stands. `changed_world_benchmark` and test_changed_world drive it.
#pragma once

#include <optional>
#include <string>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/change_coverage.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/slam/laser_slam_params.hpp"

namespace line_map_eval
{
struct ChangedWorldMap
{
  /// q [%] against the building as it stands: both sessions' scan points, less those on walls removed
  /// since (a wall the second session no longer sees still stands). With true poses, the scans at their
  /// true poses; with the SLAM, as the joined graph registered them (the second session alone: as its own
  /// graph did), as q is measured on logs without ground truth.
  double quality = 0.0;
  /// [%] ground-truth coverage against the world its run mapped (the first session's: the world before).
  double truth_coverage = 0.0;
  ChangeScores changes;
  std::size_t segments = 0;
  std::size_t retired = 0;  ///< originals of the first session's map retired as seen through
};

struct ChangedWorldResult
{
  ChangedWorldMap first;      ///< the first session's map: what the robot knew before the second run
  ChangedWorldMap continued;  ///< the second session continuing the first (see_through as configured)
  ChangedWorldMap kept;       ///< the same with see_through off: every old wall kept
  ChangedWorldMap fresh;      ///< the second session alone, from nothing
  /// The second run's scan at which global localization placed it in the first session (0 with a given
  /// start); none: never, and then only `first` and `fresh` are filled.
  std::optional<std::size_t> localized_at;
  std::size_t closures_between = 0;  ///< loop edges from the second run's keyframes to the first's
};

/// Where the keyframes' poses come from.
enum class ChangedWorldPoses
{
  kSlam,   ///< our SLAM; the second run is placed in the first session's graph and continues it
  kTruth,  ///< the simulation's true poses (as a corrected log's): the map's own behaviour alone
};

/// Simulates `before` and `after` (seeds apart), maps the first with CAE-RLSM (`options`: parameters, the
/// merger is cae), continues its map with the second, and scores the maps. With kSlam the poses are our
/// SLAM's: the second run's odometry starts at zero, and it is placed by global localization in the first
/// session's graph (`start`: its first base pose in that map frame instead). Figures and map files go
/// under `work_dir`.
ChangedWorldResult runChangedWorld(const World& before, const World& after, const BatchOptions& options,
                                   ChangedWorldPoses poses, const line_map_merging::LaserSlamParams& slam,
                                   const line_map_merging::LocalizerParams& localizer,
                                   const std::string& work_dir,
                                   const std::optional<linemap::Pose2>& start = std::nullopt);

}  // namespace line_map_eval
