// 2D laser SLAM (ROS-free): the trajectory source for users without one. A facade over three parts,
// as in Cartographer: the front end (LocalTrajectoryBuilder: every scan matched against a local map of
// the last keyframes, which keyframes to make), the loop-closure search (ConstraintBuilder: each keyframe
// matched against submaps around older keyframes near its estimate) and the closures' acceptance
// (ClosureGate: consistency with the graph, optimisation, removal of a closure the optimised graph
// cannot agree with). LaserSlam owns the keyframes, the pose graph (chain edges: the matched relative
// poses) and the scans' records, and wires the three.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/slam/closure_gate.hpp"
#include "line_map_merging/slam/constraint_builder.hpp"
#include "line_map_merging/slam/laser_slam_params.hpp"
#include "line_map_merging/slam/local_trajectory_builder.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"
#include "linemap/time_jump_detector.hpp"

namespace line_map_merging
{
/// One line on the loop closures for a run's summary: accepted of attempted, and the refusals by reason.
std::string closureSummary(const SlamCounters& counters);

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
  const linemap::Pose2& currentLocal() const { return front_end_.currentLocal(); }

  const std::vector<SlamKeyframe>& keyframes() const { return keyframes_; }
  /// Every loop-closure attempt that got as far as a match, in order (since the last reset()).
  const std::vector<ClosureAttempt>& closureAttempts() const { return gate_.attempts(); }
  const PoseGraph& graph() const { return graph_; }
  const SlamCounters& counters() const { return counters_; }
  const LaserSlamParams& params() const { return params_; }
  std::vector<std::pair<std::string, std::string>> diagnostics() const;
  /// The share of the keyframes' path that no accepted closure spans (a stretch between a closure's two
  /// keyframes is held by it): where a slip would go unseen. 0 before any path.
  double unclosedShare() const;
  /// A sentence on why the run may be going wrong (many closures in a row refused as inconsistent: the
  /// estimate and the scans disagree), or empty: for a WARN on /diagnostics without ground truth.
  std::string trouble() const;
  /// Fault injection (tests, the robustness benchmark): the front end slips by `slip` before the next
  /// scan (LocalTrajectoryBuilder::injectSlip); the graph's closures must repair it.
  void injectFrontEndSlip(const linemap::Pose2& slip) { front_end_.injectSlip(slip); }
  /// Forgets everything but the counters (a new trajectory starts at the origin).
  void reset();
  /// What a session file keeps of the run (session_file.hpp): keyframes, graph, scans.
  SlamSession session() const;
  /// Takes over a saved session in place of the current run: its keyframes, graph and scans, the front end
  /// going on from the newest keyframe. The loop gate's bookkeeping starts afresh. Throws
  /// std::invalid_argument when the session is inconsistent (nodes and keyframes differ in number, an
  /// edge or scan names a keyframe it does not have); the current run is then kept.
  void restore(const SlamSession& session);
  /// Takes over a saved session (as restore()) and starts a new trajectory in it: the next scan's base pose
  /// in the session's map frame is `start` (found by the caller: global localization, an initial pose),
  /// known to `sigma_xy` and `sigma_theta`. Its first keyframe is tied to the saved keyframe nearest to it
  /// by that pose, the rest by the chain and by loop closures to the saved keyframes as to its own.
  void continueFrom(const SlamSession& session, const linemap::Pose2& start, double sigma_xy,
                    double sigma_theta);
  /// Joins a saved session this run could not be placed in when it started (it mapped apart, in its own
  /// frame) once the robot is found in it: `saved_in_map` is the saved map frame's pose in this run's map
  /// frame. The saved keyframes, graph and scans are moved there and put before this run's, and this run's
  /// newest keyframe is tied to the saved keyframe nearest to it, known to `sigma_xy` and `sigma_theta`;
  /// loop closures to the saved keyframes follow as to this run's own. This run's frame stays the map
  /// frame (the graph's fixed node is then the first saved keyframe, so it holds up to `saved_in_map`'s
  /// error); the front end goes on undisturbed. Throws
  /// std::invalid_argument (and changes nothing) for an inconsistent session, one without keyframes, a
  /// run without a keyframe yet, or sigmas that are not positive.
  void joinSession(const SlamSession& saved, const linemap::Pose2& saved_in_map, double sigma_xy,
                   double sigma_theta);

 private:
  /// Whether the stamp went back by more than time_jump_tolerance (counted).
  bool observeStamp(double stamp);
  /// Scan `scan_index`, a keyframe by the front end: a graph node with its chain edge, then its loop
  /// closures.
  void addKeyframe(LocalScanResult& scan, std::size_t scan_index);
  /// The closures of the newest keyframe: each candidate matched from the graph as the previous
  /// one left it, then judged.
  void closeLoops();

  LaserSlamParams params_;
  LocalTrajectoryBuilder front_end_;
  ConstraintBuilder constraints_;
  ClosureGate gate_;
  PoseGraph graph_;
  std::vector<SlamKeyframe> keyframes_;
  struct ScanRecord
  {
    double stamp;
    std::size_t keyframe;
    linemap::Pose2 relative;  ///< keyframe local^-1 * scan local
  };
  std::vector<ScanRecord> scans_;
  linemap::TimeJumpDetector time_jumps_;
  /// The translation shape of the last scan's front-end match in the local frame (identity: no match or
  /// no odometry to leave a direction to).
  Eigen::Matrix2d last_match_weights_ = Eigen::Matrix2d::Identity();
  /// The chain edge of a keyframe, its sigmas widened when its match disagrees with the odometry far more
  /// than the run's matches usually do (a slip): true then.
  bool widenBySlip(const linemap::Pose2& disagreement, PoseGraphEdge& e);
  /// Whether `points` (a new keyframe's scan) fit the `previous` keyframe's scan at the odometry's motion
  /// (a mean field value of at least kPairFits: the points about a sigma from the other scan's) and better
  /// than at the front end's `matched` one, both relative to the previous keyframe.
  static constexpr double kPairFits = 0.5;
  bool odometryFitsBetter(const SlamKeyframe& previous, const std::vector<linemap::Vec2>& points,
                          const linemap::Pose2& matched, const linemap::Pose2& odometry) const;
  /// The recent chain edges' disagreements with the odometry (shift, turn): the odometry's own noise as
  /// this run sees it.
  std::deque<std::pair<double, double>> recent_disagreements_;
  /// A new trajectory in a restored session (continueFrom): its first keyframe's index, the map pose of its
  /// front end's origin, and how well that is known.
  struct Continuation
  {
    std::size_t first_keyframe = 0;
    linemap::Pose2 origin;
    double sigma_xy = 0.0, sigma_theta = 0.0;
  };
  std::optional<Continuation> continuation_;
  /// The continued trajectory's first keyframe `k`: its node at the start pose, tied to the nearest saved
  /// keyframe.
  void anchorContinuation(std::size_t k);
  /// Ties keyframe `k` where the graph has it to the nearest of the keyframes before `saved` (a loop edge
  /// with these sigmas, robust as a closure is: the closures that follow outweigh a start known roughly).
  void tieToNearestSaved(std::size_t k, std::size_t saved, double sigma_xy, double sigma_theta);
  bool keyframe_added_ = false, graph_optimized_ = false;
  SlamCounters counters_;
};

}  // namespace line_map_merging
