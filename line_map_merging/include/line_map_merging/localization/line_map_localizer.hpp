// Localization of a robot in a saved line map (ROS-free): the core of the localization nodelet and of
// `linemap_relations --localize`.
// Tracking: each scan is matched against the map's segments (localization_segment_matcher.hpp) from
// the odometry prediction, under the odometry as a prior whose spread grows with the motion; a match
// whose inlier share is poor is retried from a correlative search around the prediction (odometry that
// slipped). Lost: a poor inlier share for lost_scans scans in a row starts global localization.
// Global localization (on request, without an initial pose, or when lost): the hypotheses of a search
// over the whole map (localization_global_search.hpp) are each tracked with the odometry; those that
// stop matching are dropped, the search is repeated while none is convincing, and one is accepted once
// the robot has moved far enough for its lead over every distinct rival to mean something.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_extraction/types.hpp"
#include "line_map_merging/localization/localization_global_search.hpp"
#include "line_map_merging/localization/localization_segment_matcher.hpp"
#include "linemap/geometry.hpp"
#include "linemap/odometry_jump.hpp"
#include "linemap/params.hpp"
#include "linemap/time_jump_detector.hpp"

namespace line_map_merging
{
struct LocalizerParams
{
  double max_range = 20.0;      ///< [m] farther scan points are dropped
  std::size_t min_points = 20;  ///< fewer valid points: the scan is not matched (pose predicted)
  SegmentMatchParams match;
  double index_cell = 0.1;  ///< [m] cell of the segment index
  // Odometry prior: standard deviations of the predicted motion, a floor plus a share of the motion.
  double odom_sigma_xy = 0.02;                ///< [m]
  double odom_sigma_xy_per_m = 0.1;           ///< [m/m]
  double odom_sigma_theta = 0.01;             ///< [rad]
  double odom_sigma_theta_per_rad = 0.1;      ///< [rad/rad]
  double odom_sigma_theta_per_m = 0.05;       ///< [rad/m]
  double no_odom_sigma_xy = 0.3;              ///< [m] the prior without odometry (constant pose)
  double no_odom_sigma_theta = 0.3;           ///< [rad]
  linemap::OdometryJumpLimits odometry_jump;  ///< more between two scans: a jump, not a motion
  double time_jump_tolerance = 1.0;           ///< [s] a stamp further back restarts the odometry reference
  // Recovery of a poor match by a correlative search around the prediction.
  double retry_inlier_share = 0.6;
  SearchWindow retry_window{0.3, 0.2, 0.05, 0.01, 0.0, 0.0};
  /// Across an odometry jump: around the jumped prediction and around the last pose.
  SearchWindow jump_window{0.5, 0.6, 0.05, 0.01, 0.0, 0.0};
  // Lost detection.
  double lost_inlier_share = 0.25;
  std::size_t lost_scans = 15;
  /// A track whose mean inlier share (smoothed like a hypothesis') falls below this is doubted: the
  /// hypotheses of global searches are tracked beside it, and one that explains the scans better by
  /// accept_margin, over the motion acceptance needs, replaces it (a wrong initial pose that still
  /// matches a part of the map, a kidnapping to a similar place).
  double doubt_share = 0.5;
  std::size_t doubt_research_every = 30;  ///< scans between global searches while doubted
  std::size_t doubt_hypotheses = 10;      ///< rivals tracked at most
  // Global localization.
  GlobalSearchParams global;
  double hypothesis_min_share = 0.45;  ///< a hypothesis whose mean inlier share falls below is dropped
  double hypothesis_smoothing = 0.15;  ///< weight of the newest scan in a hypothesis' mean
  std::size_t hypotheses = 30;         ///< at most tracked at once
  std::size_t research_every = 10;     ///< scans between global searches while undecided
  /// The same while a SLAM that gave its session search up maps apart (SessionContinuation): it looks on for
  /// itself in the same thread.
  std::size_t research_every_apart = 50;
  double accept_share = 0.6;    ///< mean inlier share an accepted hypothesis needs
  double accept_margin = 0.08;  ///< lead over the best distinct rival
  double accept_travel = 2.0;   ///< [m] or accept_turn [rad] of motion since the hypothesis began
  double accept_turn = 1.5;
  std::size_t accept_scans = 10;  ///< and at least this many scans

  /// Keys as in config/localization.yaml (e.g. "match/loss_scale", "global/candidates"); throws
  /// linemap::ParameterError naming the key.
  static LocalizerParams fromParams(const linemap::ParamSet& params);
};

struct LocalizerScan
{
  double stamp = 0.0;
  std::vector<linemap::Vec2> points;             ///< valid returns in the base frame
  std::optional<linemap::Pose2> odom;            ///< base in the odometry frame at `stamp`
  linemap::Vec2 sensor = linemap::Vec2::Zero();  ///< the laser's position in the base frame
};

enum class LocalizerOutcome
{
  kTracked,    ///< matched in the map
  kPredicted,  ///< not matched (too few points, poor match, no map): posed by the prediction
  kSearching,  ///< global localization under way: the pose is dead reckoning from the last known
  kRecovered,  ///< global localization accepted a hypothesis with this scan
  kRejected,   ///< stamp not after the last one: ignored
};

struct LocalizerCounters
{
  std::size_t scans = 0, tracked = 0, predicted = 0, searching = 0, rejected = 0, retries = 0, few_points = 0,
              odometry_jumps = 0, time_jumps = 0, lost = 0, recovered = 0, global_searches = 0, doubted = 0,
              replaced = 0;
  double last_ms = 0.0, last_global_search_ms = 0.0;
};

struct LocalizerResult
{
  LocalizerOutcome outcome = LocalizerOutcome::kPredicted;
  bool localized = false;  ///< the pose is tracked (not a hypothesis of a global search)
  linemap::Pose2 pose;     ///< base in the map frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double score = 0.0, inlier_share = 0.0;
};

class LineMapLocalizer
{
 public:
  LineMapLocalizer(const std::vector<linemap::Segment2>& segments, const LocalizerParams& params = {});

  /// Starts tracking from `pose` (RViz' initial pose; the first scan's pose of a log).
  void setPose(const linemap::Pose2& pose);
  /// Forgets the pose: the next scans localize globally.
  void startGlobalLocalization();

  LocalizerResult addScan(const LocalizerScan& scan);

  bool localized() const { return tracking_; }
  const LocalizerCounters& counters() const { return counters_; }
  const LocalizerParams& params() const { return params_; }
  /// A new map in the same frame (a map that grew or was saved again): the pose, the track or the
  /// global search go on in it.
  void setMap(const std::vector<linemap::Segment2>& segments);
  const LocalizationSegmentIndex& index() const { return index_; }
  std::size_t hypothesisCount() const { return hypotheses_.size(); }
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

 private:
  struct Hypothesis
  {
    linemap::Pose2 pose;
    double mean_share = 0.0;
    std::size_t scans = 0;
    double travel = 0.0, turn = 0.0;
    SegmentMatch last;
  };
  PosePrior odometryPrior(const linemap::Pose2& predicted, const std::optional<linemap::Pose2>& step) const;
  /// The odometry's motion since the last scan: a plausible `step`, or an implausible `jump`.
  struct OdometryMotion
  {
    std::optional<linemap::Pose2> step, jump;
  };
  /// Counts a clock jump back (forgetting the odometry); false for a stamp that is not new.
  bool acceptStamp(double stamp);
  OdometryMotion odometryMotion(const std::optional<linemap::Pose2>& reading, double stamp);
  /// One scan while tracking: matched near the odometry's prediction; lost after lost_scans poor ones.
  LocalizerResult trackStep(const LocalizerScan& scan, const std::optional<linemap::Pose2>& step,
                            const std::optional<linemap::Pose2>& jump);
  /// Replaces `best` by a match found by wide searches around the jumped and the unmoved pose, if better.
  void matchAcrossJump(const LocalizerScan& scan, const linemap::Pose2& jump, SegmentMatch& best) const;
  SegmentMatch track(const LocalizerScan& scan, const linemap::Pose2& predicted, const PosePrior& prior,
                     bool allow_retry);
  LocalizerResult globalStep(const LocalizerScan& scan, const std::optional<linemap::Pose2>& step);
  /// Tracks rival hypotheses while the track's smoothed share is below doubt_share; replaces the
  /// track by one that does better.
  void challengeTrack(const LocalizerScan& scan, const std::optional<linemap::Pose2>& step,
                      LocalizerResult& result);
  /// Moves every hypothesis by the odometry, matches, prunes and merges them, searches the map again
  /// when there are none or research_every scans have passed, and keeps the max_hypotheses best.
  void updateHypotheses(const LocalizerScan& scan, const std::optional<linemap::Pose2>& step,
                        std::size_t research_every, std::size_t max_hypotheses);
  /// The best hypothesis tested over enough motion whose mean share reaches `floor` and leads every
  /// distinct rival by accept_margin; null if none.
  const Hypothesis* acceptable(double floor) const;

  LocalizerParams params_;
  LocalizationSegmentIndex index_;
  LocalizationGlobalSearch global_;
  bool tracking_ = false;
  linemap::Pose2 pose_;
  std::optional<linemap::Pose2> last_odom_;
  double last_odom_stamp_ = 0.0;
  bool have_stamp_ = false;
  double last_stamp_ = 0.0;
  std::size_t poor_in_row_ = 0, scans_since_search_ = 0;
  double track_share_ = 1.0;  ///< smoothed inlier share of the track
  std::vector<Hypothesis> hypotheses_;
  linemap::TimeJumpDetector time_jumps_;
  LocalizerCounters counters_;
  LocalizerResult last_;
};

/// The valid returns of `scan` (range_min <= r < range_max) in the frame the laser is mounted in.
std::vector<linemap::Vec2> beamPoints(const line_extraction::ScanInput& scan, const linemap::Pose2& mount);

/// The segments a saved map file (CAE-RLSM's format, map_file.cpp) shows; throws MapFileError.
std::vector<linemap::Segment2> loadLineMapSegments(const std::string& path);

}  // namespace line_map_merging
