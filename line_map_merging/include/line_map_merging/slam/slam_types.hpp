// What the laser SLAM takes in, gives out and keeps, shared by LaserSlam (laser_slam.hpp) and its
// parts: scans, their outcomes, the counters, the closure attempts' records and the keyframes.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct SlamScan
{
  double stamp = 0.0;
  std::vector<linemap::Vec2> points;   ///< valid returns in the base frame
  std::optional<linemap::Pose2> odom;  ///< base in the odometry frame at `stamp`
};

enum class SlamOutcome
{
  kMatched,    ///< matched against the local map
  kFiltered,   ///< barely moved (odometry): posed by odometry, not matched
  kPredicted,  ///< not matched (too few points, no map yet, match too poor): posed by the prediction
  kRejected,   ///< stamp not after the last one: ignored
};

struct SlamCounters
{
  std::size_t scans = 0, matched = 0, filtered = 0, predicted = 0, rejected = 0;
  std::size_t few_points = 0, poor_matches = 0, degenerate_matches = 0, odometry_jumps = 0, wide_searches = 0,
              without_odometry = 0, time_jumps = 0;
  /// Of the ROS wrapper: scans dropped for want of tf, scans stamped zero, new trajectories started
  /// by time jumping back, trajectories published.
  std::size_t dropped = 0, zero_stamps = 0, new_trajectories = 0, paths = 0;
  std::size_t keyframes = 0, loop_attempts = 0, loops_accepted = 0, loops_rejected_score = 0,
              loops_rejected_graph = 0, loops_consistent = 0, loops_pending = 0, loops_ambiguous = 0,
              loops_inconsistent = 0, loops_degenerate = 0, optimizations = 0;
  /// Closures refused as inconsistent with the chain that a group of mutually consistent ones later
  /// brought in (counted among the accepted, no longer among the inconsistent).
  std::size_t loops_by_consensus = 0;
  /// Trouble signs: closures refused as inconsistent since the last accepted one (and the longest such
  /// run), front-end matches whose best heading lay on the search window's border.
  std::size_t inconsistent_in_a_row = 0, most_inconsistent_in_a_row = 0, border_matches = 0;
  /// Chain edges whose match disagreed with the odometry beyond its uncertainty (loosened).
  std::size_t suspect_edges = 0;
  std::size_t suspect_edges_on_odometry = 0;  ///< of them, those whose mean is the odometry's motion
  /// [s] Without usable odometry: how long the current run of matches has lasted whose translation along
  /// some direction is more the constant-velocity prediction's than their own, and the longest such run.
  /// Along that direction the front end only assumes the robot keeps its speed: a long run is where it may
  /// have run on or lagged.
  double held_time = 0.0, longest_held_time = 0.0;
  double last_optimization_ms = 0.0, total_optimization_ms = 0.0, last_match_ms = 0.0, total_loop_ms = 0.0;
};

/// What became of a loop-closure attempt that got as far as a match of keyframe `to` against the
/// submap around keyframe `from`.
enum class ClosureOutcome
{
  kAccepted,       ///< in the graph (also a closure the estimate already met, and a corroborated one)
  kRejectedScore,  ///< the match scored below loop_min_score
  kAmbiguous,      ///< another pose away from the match scored nearly as well (loop_ambiguity_*)
  kInconsistent,   ///< beyond what the graph and the match allow (loop_consistency_probability)
  kPending,        ///< waiting for a corroborating closure that never came
  kRejectedGraph,  ///< the optimised graph still missed it by more than loop_max_error_*
};

struct ClosureAttempt
{
  std::size_t from = 0, to = 0;  ///< keyframe indices, from < to
  ClosureOutcome outcome = ClosureOutcome::kRejectedScore;
  double score = 0.0;      ///< the refined match's mean field value (an ambiguous one's: the coarse field's)
  double min_score = 0.0;  ///< the score it had to reach (LaserSlamParams::loopMinScore then)
};

struct SlamKeyframe
{
  double stamp = 0.0;
  std::size_t scan = 0;                  ///< index among the scans accepted (not rejected)
  linemap::Pose2 local;                  ///< front-end pose
  std::vector<linemap::Vec2> points;     ///< base frame
  std::vector<linemap::Segment2> joins;  ///< base frame: scanSurfaces of the points
  double path = 0.0;                     ///< [m] front-end path length up to here
};

}  // namespace line_map_merging
