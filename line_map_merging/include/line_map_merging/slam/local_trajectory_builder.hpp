// The laser SLAM's front end (ROS-free): every scan is matched against a local map (a likelihood
// field of the last keyframes' surfaces) by correlative search + Ceres refinement, from the odometry
// prediction when there is odometry, else from a constant-velocity prediction with a wider window;
// it decides which scans become keyframes and keeps the few recent ones its local map is made of.
// Knows nothing of the pose graph: LaserSlam hangs its keyframes into one.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include "line_map_merging/slam/laser_slam_params.hpp"
#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// What the front end made of one scan.
struct LocalScanResult
{
  SlamOutcome outcome = SlamOutcome::kRejected;
  SlamScan scan;        ///< the valid scan: odometry when finite, points within max_range
  linemap::Pose2 pose;  ///< front-end pose
  double path = 0.0;    ///< [m] front-end path length up to here
  /// The translation shape of the scan's match in the local frame (identity: no match or no odometry to
  /// leave a direction to); the chain edge of a keyframe takes it.
  Eigen::Matrix2d match_weights = Eigen::Matrix2d::Identity();
  bool keyframe = false;
  bool chain_matched = true;  ///< every scan since the last keyframe was matched
  /// Of a keyframe: the odometry's motion since the previous keyframe, when every scan in between had
  /// usable odometry (an independent measurement of what the chain edge measures).
  std::optional<linemap::Pose2> odometry_motion;
  std::vector<linemap::Segment2> joins;  ///< of a keyframe: scanSurfaces of its points
};

class LocalTrajectoryBuilder
{
 public:
  explicit LocalTrajectoryBuilder(const LaserSlamParams& params = {});

  /// A scan stamped after the last accepted one is posed (matched, filtered or predicted) and may become
  /// a keyframe, which joins the local map; an older one is rejected. Counts into `counters`.
  LocalScanResult addScan(const SlamScan& scan, SlamCounters& counters);
  /// The last accepted scan's front-end pose.
  const linemap::Pose2& currentLocal() const { return last_local_; }
  /// The mean score of the recent accepted matches (about the last fifty; 0 before the first): how well
  /// this sensor's scans meet the local map here, the reference of the closures' score floor.
  double runScore() const { return run_score_; }
  /// Starts afresh at the newest of `keyframes` (a restored session), with the newest of them as the
  /// local map: the next scan is searched for around that keyframe's pose.
  void resumeFrom(const std::vector<SlamKeyframe>& keyframes);
  /// Starts afresh in a new local frame (the next scan at its origin), the path counted on from `path`
  /// (a new trajectory in a restored session: paths only grow along the keyframes).
  void restart(double path);
  /// Counts the path on from `shift` further (a run joined after a saved session: LaserSlam::joinSession).
  void shiftPath(double shift) { path_ += shift; }
  /// Fault injection (tests, the robustness benchmark): the front end's estimate jumps by `slip`,
  /// composed onto the last scan's pose, as after a false match it cannot see; its local map moves with
  /// it, so the following scans are matched consistently in the slipped frame and only the graph's
  /// closures can tell.
  void injectSlip(const linemap::Pose2& slip);
  /// The field the next scan is matched against (empty before the first keyframe).
  const LikelihoodGrid& localMap() const { return local_map_; }

 private:
  /// The prediction of a scan's front-end pose from the last scan's.
  struct Prediction
  {
    linemap::Pose2 pose;
    bool odometry_usable = false;          ///< pose is the odometry's prediction
    std::optional<linemap::Pose2> jumped;  ///< the odometry's prediction across a jump
  };
  /// A keyframe as far as the local map needs it: front-end pose, points and surfaces (base frame).
  struct RecentKeyframe
  {
    linemap::Pose2 local;
    std::vector<linemap::Vec2> points;
    std::vector<linemap::Segment2> joins;
  };
  /// The scan with its odometry (when finite) and its valid points within max_range.
  SlamScan validScan(const SlamScan& in, SlamCounters& counters) const;
  Prediction predict(const SlamScan& scan, SlamCounters& counters) const;
  /// With usable odometry: whether the scan barely moved since the last match (not matched then).
  bool barelyMoved(const SlamScan& scan, const Prediction& prediction) const;
  /// The scan matched against the local map around the prediction(s), or nothing (counted); sets the
  /// match's translation shape in `weights`.
  std::optional<linemap::Pose2> matchFrontEnd(const SlamScan& scan, const Prediction& prediction,
                                              Eigen::Matrix2d& weights, SlamCounters& counters);
  /// The scan matched in the normal (or, `wide`, the no-odometry) window around `centre`, kept in `best`
  /// when it scores higher; whether the search's best heading lay on the window's border.
  bool searchNear(const SlamScan& scan, const linemap::Pose2& centre, bool wide,
                  std::optional<MatchResult>& best) const;
  /// The scan matched at every heading around the last pose (after a gap in the scans, without odometry).
  std::optional<MatchResult> searchEveryHeading(const SlamScan& scan) const;
  /// The time of the current run of matches held more to the constant velocity than to the scan along some
  /// direction (no usable odometry) and of the longest such run, in `counters`.
  void countHeldTime(const LocalScanResult& result, const Prediction& prediction,
                     SlamCounters& counters) const;
  void countOutcome(SlamOutcome outcome, SlamCounters& counters);
  /// The front end's state after a scan posed at `pose`: path, velocity, last poses and stamp.
  void advance(const SlamScan& scan, const linemap::Pose2& pose, SlamOutcome outcome);
  /// Whether the scan follows the last after several times the scans' usual period (a gap in the log).
  bool afterGap(const SlamScan& scan) const;
  /// Whether the time since the last match is several times the scans' usual period per scan.
  bool pausedSinceMatch(const SlamScan& scan) const;
  /// A keyframe when the scan has enough points and moved far enough from the last keyframe.
  bool isKeyframe(const SlamScan& scan, const linemap::Pose2& pose) const;
  /// Adds the keyframe to the recent ones and rebuilds the local map from them.
  void addKeyframe(const linemap::Pose2& pose, const std::vector<linemap::Vec2>& points,
                   const std::vector<linemap::Segment2>& joins);
  void rebuildLocalMap();
  /// A match's translation where it determines one, the prediction's (odometry or constant velocity)
  /// along a direction it leaves open; `weights` its translation shape.
  linemap::Pose2 heldToPrediction(const MatchResult& match, const linemap::Pose2& predicted,
                                  Eigen::Matrix2d& weights, SlamCounters& counters) const;

  LaserSlamParams params_;
  double typical_score_ = 0.0;  ///< running mean of the accepted match scores
  /// Their mean over the last kRunScoreMatches or so (runScore): slower than typical_score_, which follows
  /// the last few scans to widen a search; the closures' floor is a property of the sensor and the place.
  double run_score_ = 0.0;
  std::size_t run_score_matches_ = 0;
  static constexpr std::size_t kRunScoreMatches = 50;
  /// The last local_map_keyframes keyframes (at least the last one: the keyframe decision's reference).
  std::deque<RecentKeyframe> recent_;
  LikelihoodGrid local_map_;
  bool have_scan_ = false;
  double last_stamp_ = 0.0;      ///< of the last accepted scan
  double typical_period_ = 0.0;  ///< [s] the scans' usual period (0: not known yet)
  static constexpr double kGapPeriods = 5.0;
  linemap::Pose2 last_local_, last_matched_local_, velocity_;  ///< velocity: last matched motion per scan
  double last_matched_stamp_ = 0.0;                            ///< of the scan at last_matched_local_
  bool velocity_across_pause_ = false;  ///< velocity_ was measured across a pause in the scans
  std::size_t scans_since_match_ = 0;   ///< scans since last_matched_local_
  std::optional<linemap::Pose2> last_odom_, last_matched_odom_;
  double path_ = 0.0;
  bool chain_matched_ = true;                    ///< every scan since the last keyframe was matched
  std::optional<linemap::Pose2> keyframe_odom_;  ///< odometry at the last keyframe's scan
  bool odometry_continuous_ = false;             ///< usable odometry at every scan since it
};

}  // namespace line_map_merging
