// 2D laser SLAM (ROS-free): the trajectory source for users without one. Front end: every scan is
// matched against a local map (a likelihood field of the last keyframes' points) by correlative
// search + Ceres refinement, from the odometry prediction when there is odometry, else from a
// constant-velocity prediction with a wider window. Keyframes (every keyframe_distance /
// keyframe_angle of matched motion) are the nodes of a pose graph whose chain edges are the matched
// relative poses. Loop closures: each keyframe is matched against submaps around older keyframes
// near its estimate, within a window that grows with the path travelled since the last closure;
// an accepted closure adds a robust edge and the graph is optimised at once (pose_graph.hpp); a
// closure the optimised graph cannot agree with is removed again.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/scan_surfaces.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"
#include "linemap/time_jump_detector.hpp"

namespace line_map_merging
{
struct LaserSlamParams
{
  // Scan points.
  double max_range = 20.0;  ///< [m] farther points are dropped (sparse, and small angle errors grow there)
  std::size_t min_points = 20;  ///< fewer valid points: the scan is not matched (pose predicted)
  // Front end.
  double resolution = 0.025;  ///< [m] local likelihood field
  /// [m] its spread: about that of a scan point about a map point (both ranges noisy, plus a cell)
  double sigma = 0.03;
  SearchWindow window{0.1, 0.12, 0.05, 0.006, 2.0, 20.0};            ///< with odometry
  SearchWindow window_no_odometry{0.3, 0.3, 0.05, 0.008, 2.0, 5.0};  ///< without or off the odometry
  RefinementParams refinement{2.0, 2.0, 20};
  double min_score = 0.25;  ///< refined field score below: the prediction is kept
  /// The wide window is also searched when the normal one's match scores below this fraction of the
  /// run's recent matches (a running mean), or finds its best heading on the window's border.
  double widen_ratio = 0.75;
  double filter_distance = 0.02;         ///< [m] with odometry, scans that moved less are not matched
  double filter_angle = 0.01;            ///< [rad]
  double keyframe_distance = 0.2;        ///< [m]
  double keyframe_angle = 0.17;          ///< [rad]
  std::size_t local_map_keyframes = 20;  ///< keyframes in the local map
  /// With lambda > 0 the local map's field is of the keyframes' surfaces (scanSurfaces), not of their
  /// points alone: a wall at grazing incidence is then a line, not a row of dots that holds a scan at
  /// the keyframe's pose along a corridor. 0: the points alone.
  SurfaceParams surfaces{10.0 * linemap::kPi / 180.0, 0.01};
  double max_odometry_step = 0.5;    ///< [m] odometry moving more between two scans is a jump
  double max_odometry_turn = 0.5;    ///< [rad]
  double time_jump_tolerance = 1.0;  ///< [s] a stamp this much before the last one: time jumped back
  /// What a match determines, as a weight per direction of the translation (its score's curvature;
  /// TranslationShape): a direction fixed at least this fraction as sharply as the best one counts
  /// fully, a weaker one in proportion. The front end takes the match's translation in the
  /// determined directions and keeps the prediction in the others (a corridor's axis); a closure's
  /// information takes the same shape, and its acceptance tests measure its disagreement in that
  /// metric. 0: every match determines everything (isotropic).
  double isotropic_ratio = 0.05;
  /// Floor of a direction's weight: only keeps the information invertible. A closure sliding along a
  /// corridor must not hold the estimate along it, and many weakly held closures add up.
  double min_weight = 1e-6;
  // Back end.
  double edge_sigma_xy = 0.02, edge_sigma_theta = 0.002;        ///< matched chain edges
  double odometry_sigma_xy = 0.2, odometry_sigma_theta = 0.05;  ///< chain edges with unmatched scans
  double loop_sigma_xy = 0.05, loop_sigma_theta = 0.01;
  double loop_loss_scale = 1.0;           ///< Cauchy scale, in standard deviations
  double loop_min_path = 5.0;             ///< [m] path between a keyframe and a candidate
  double loop_radius = 0.6;               ///< [m] search radius just after a closure
  double loop_radius_growth = 0.05;       ///< [m per m of path since the last closure]
  double loop_max_radius = 3.0;           ///< [m]
  double loop_angle = 0.15;               ///< [rad]
  double loop_angle_growth = 0.01;        ///< [rad per m]
  double loop_max_angle = 0.5;            ///< [rad]
  double loop_resolution = 0.1;           ///< [m] coarse field of the wide search
  double loop_angular_step = 0.015;       ///< [rad]
  std::size_t loop_submap_keyframes = 6;  ///< on each side of the candidate
  std::size_t loop_candidates = 2;        ///< submaps tried per keyframe
  std::size_t loop_every = 1;             ///< keyframes between attempts
  double loop_min_score = 0.55;
  /// A closure whose coarse search finds another pose at least ambiguity_distance away scoring at least
  /// ambiguity_ratio of the best is refused (a corridor seen from inside); 0 / ratio > 1: no check.
  double loop_ambiguity_distance = 0.3;  ///< [m]
  double loop_ambiguity_ratio = 0.9;
  /// A closure is refused when its disagreement with the estimate is beyond this quantile of the chi-square
  /// distribution (3 degrees of freedom) in the metric of the combined uncertainty: the closure's own
  /// covariance plus that of the estimate's relative pose along the graph's most certain path
  /// (relativeCovariance). 0: no such test.
  double loop_consistency_probability = 0.999;
  /// An unambiguous closure goes in under a Cauchy scale of this many times its disagreement with the
  /// estimate (in standard deviations), so a true closure after a long drift is applied, not damped
  /// like an outlier; 0: always the graph's loop_loss_scale.
  double loop_scale_by_disagreement = 2.0;
  double loop_max_error_xy = 0.3;     ///< [m] a closure the optimised graph misses by more is removed
  double loop_max_error_theta = 0.1;  ///< [rad]
  /// A closure the estimate misses by more than these needs a second one implying the same correction
  /// (within agreement_*) from one of the next pending_keyframes keyframes; both then go in under a
  /// loss as wide as twice the correction. Off by default (infinite): on the Intel and ACES corridors,
  /// closures sliding along a corridor corroborated each other.
  double loop_corroborate_xy = std::numeric_limits<double>::infinity();     ///< [m]
  double loop_corroborate_theta = std::numeric_limits<double>::infinity();  ///< [rad]
  double loop_agreement_xy = 0.1;                                           ///< [m]
  double loop_agreement_theta = 0.03;                                       ///< [rad]
  std::size_t loop_pending_keyframes = 10;
  /// A closure the current estimate meets within these is added without optimising at once.
  double loop_consistent_xy = 0.03;     ///< [m]
  double loop_consistent_theta = 0.01;  ///< [rad]

  /// Keys as in config/slam.yaml (e.g. "window/linear", "loop/min_score"); throws
  /// linemap::ParameterError naming the key.
  static LaserSlamParams fromParams(const linemap::ParamSet& params);
};

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
  double last_optimization_ms = 0.0, total_optimization_ms = 0.0, last_match_ms = 0.0, total_loop_ms = 0.0;
};

/// One line on the loop closures for a run's summary: accepted of attempted, and the refusals by reason.
std::string closureSummary(const SlamCounters& counters);

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
  double score = 0.0;  ///< the refined match's mean field value
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

class LaserSlam
{
 public:
  explicit LaserSlam(const LaserSlamParams& params = {});

  /// A scan stamped after the last accepted one is matched and may become a keyframe; an older one
  /// is rejected (counted as a time jump when more than time_jump_tolerance older).
  SlamOutcome addScan(const SlamScan& scan);
  /// A replay from the start (a stamp more than time_jump_tolerance before the newest seen): starts
  /// a new trajectory (reset(), counted) and returns true; the caller then drops what it holds of
  /// the old time line (its tf buffer). For callers that follow a live clock; addScan alone rejects
  /// such a scan instead.
  bool restartOnTimeJump(double stamp);
  void countDropped() { ++counters_.dropped; }
  void countZeroStamp() { ++counters_.zero_stamps; }
  void countPublished() { ++counters_.paths; }
  /// Whether the last addScan made a keyframe, and whether it changed the optimised poses.
  bool keyframeAdded() const { return keyframe_added_; }
  bool graphOptimized() const { return graph_optimized_; }

  /// Optimised base poses of the keyframes in the map frame, with their scans' stamps.
  std::vector<std::pair<double, linemap::Pose2>> trajectory() const;
  /// Optimised base pose of every accepted scan (its keyframe's pose composed with the front end's
  /// motion from it), in order; with its stamp.
  std::vector<std::pair<double, linemap::Pose2>> scanPoses() const;
  /// Base pose of the last accepted scan in the map frame.
  linemap::Pose2 currentPose() const;
  /// The last accepted scan's front-end pose.
  const linemap::Pose2& currentLocal() const { return last_local_; }

  const std::vector<SlamKeyframe>& keyframes() const { return keyframes_; }
  /// Every loop-closure attempt that got as far as a match, in order (since the last reset()).
  const std::vector<ClosureAttempt>& closureAttempts() const { return closures_; }
  const PoseGraph& graph() const { return graph_; }
  const SlamCounters& counters() const { return counters_; }
  const LaserSlamParams& params() const { return params_; }
  std::vector<std::pair<std::string, std::string>> diagnostics() const;
  /// Forgets everything but the counters (a new trajectory starts at the origin).
  void reset();

 private:
  /// The prediction of a scan's front-end pose from the last scan's.
  struct Prediction
  {
    linemap::Pose2 pose;
    bool odometry_usable = false;          ///< pose is the odometry's prediction
    std::optional<linemap::Pose2> jumped;  ///< the odometry's prediction across a jump
  };
  /// Whether the stamp went back by more than time_jump_tolerance (counted).
  bool observeStamp(double stamp);
  /// The scan with its odometry (when finite) and its valid points within max_range.
  SlamScan validScan(const SlamScan& in);
  Prediction predict(const SlamScan& scan);
  /// With usable odometry: whether the scan barely moved since the last match (not matched then).
  bool barelyMoved(const SlamScan& scan, const Prediction& prediction) const;
  /// The scan matched against the local map around the prediction(s), or nothing (counted).
  std::optional<linemap::Pose2> matchFrontEnd(const SlamScan& scan, const Prediction& prediction);
  void countOutcome(SlamOutcome outcome);
  /// The front end's state after a scan posed at `pose`: path, velocity, last poses and stamp.
  void advance(const SlamScan& scan, const linemap::Pose2& pose, SlamOutcome outcome);
  /// A keyframe when the scan has enough points and moved far enough from the last keyframe.
  bool isKeyframe(const SlamScan& scan, const linemap::Pose2& pose) const;
  void addKeyframe(const SlamScan& scan, std::size_t scan_index, bool chain_matched);
  void rebuildLocalMap();
  void closeLoops();
  /// The older keyframes to match keyframe k against: nearest first within `radius`, at most
  /// loop_candidates, no two within one submap's span.
  std::vector<std::size_t> loopCandidates(std::size_t k, double radius) const;
  /// One closure of keyframe k against candidate j: matched, checked, added and optimised, or not.
  void tryLoop(std::size_t j, std::size_t k, double radius, double angle);
  /// A closure (edge `added[0]`, `relative` pose of k from j) that disagrees with the estimate by
  /// `size` and `theta_error`: sets its loss, adds a corroborating pending closure to `added`, or
  /// leaves it pending (removed from the graph; false).
  /// Whether closure edge e (not yet in the graph) disagrees with the estimate by no more than the
  /// consistency gate allows, in the metric of its covariance plus the estimate's (relativeCovariance).
  bool consistentWithGraph(const PoseGraphEdge& e) const;
  bool admitDisagreeing(std::size_t j, std::size_t k, const PoseGraphEdge& e, const linemap::Pose2& relative,
                        double size, double theta_error, std::vector<std::size_t>& added);
  /// Whether the pending closure implies the same correction of keyframe k as one putting it at
  /// `implied`.
  bool corroborates(std::size_t k, const linemap::Pose2& implied) const;
  /// Optimises the graph with the closure edges `added`; when the optimised graph misses one of them
  /// by more than loop_max_error_*, removes them and restores the poses. Whether they stayed.
  bool optimizeKeeping(std::vector<std::size_t> added);
  /// The translation shape of a match (identity when isotropic_ratio is 0).
  TranslationShape matchShape(const MatchResult& match) const;
  /// The refined match and its ambiguity (best coarse score away from the peak / the peak's).
  std::optional<std::pair<MatchResult, double>> matchLoop(std::size_t candidate, std::size_t current,
                                                          const linemap::Pose2& guess, double radius,
                                                          double angle);

  LaserSlamParams params_;
  double typical_score_ = 0.0;  ///< running mean of the front end's accepted match scores
  double consistency_gate_;     ///< chi-square quantile of loop_consistency_probability (infinite: off)
  PoseGraph graph_;
  std::vector<SlamKeyframe> keyframes_;
  LikelihoodGrid local_map_;
  struct ScanRecord
  {
    double stamp;
    std::size_t keyframe;
    linemap::Pose2 relative;  ///< keyframe local^-1 * scan local
  };
  std::vector<ScanRecord> scans_;
  bool have_scan_ = false;
  double last_stamp_ = 0.0;  ///< of the last accepted scan
  linemap::TimeJumpDetector time_jumps_;
  linemap::Pose2 last_local_, last_matched_local_, velocity_;  ///< velocity: last matched motion per scan
  std::size_t scans_since_match_ = 0;                          ///< scans since last_matched_local_
  std::optional<linemap::Pose2> last_odom_, last_matched_odom_;
  double path_ = 0.0, path_at_closure_ = 0.0;
  bool chain_matched_ = true;  ///< every scan since the last keyframe was matched
  /// The translation shape of the last scan's front-end match in the local frame (identity: no match or
  /// no odometry to leave a direction to).
  Eigen::Matrix2d last_match_weights_ = Eigen::Matrix2d::Identity();
  bool keyframe_added_ = false, graph_optimized_ = false;
  struct PendingClosure
  {
    PoseGraphEdge edge;
    linemap::Pose2 implied;  ///< where the closure puts its keyframe
    std::size_t to;
    std::size_t attempt;  ///< its entry in closures_
  };
  std::optional<PendingClosure> pending_;
  std::vector<ClosureAttempt> closures_;
  SlamCounters counters_;
};

}  // namespace line_map_merging
