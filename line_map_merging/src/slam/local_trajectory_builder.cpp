#include "line_map_merging/slam/local_trajectory_builder.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/scan_surfaces.hpp"

namespace line_map_merging
{
using linemap::Pose2;
using linemap::Vec2;

LocalTrajectoryBuilder::LocalTrajectoryBuilder(const LaserSlamParams& params) : params_(params) {}

LocalScanResult LocalTrajectoryBuilder::addScan(const SlamScan& in, SlamCounters& counters)
{
  LocalScanResult result;
  if (have_scan_ && !(in.stamp > last_stamp_))
  {
    ++counters.rejected;
    return result;
  }
  result.scan = validScan(in, counters);
  const SlamScan& scan = result.scan;
  const Prediction prediction = predict(scan, counters);
  odometry_continuous_ &= scan.odom && prediction.odometry_usable;
  result.outcome = SlamOutcome::kPredicted;
  result.pose = prediction.pose;
  if (barelyMoved(scan, prediction))
    result.outcome = SlamOutcome::kFiltered;
  else if (const auto matched = matchFrontEnd(scan, prediction, result.match_weights, counters))
  {
    result.pose = *matched;
    result.outcome = SlamOutcome::kMatched;
  }
  countOutcome(result.outcome, counters);
  countHeldTime(result, prediction, counters);
  advance(scan, result.pose, result.outcome);
  result.path = path_;
  result.chain_matched = chain_matched_;
  if (isKeyframe(scan, result.pose))
  {
    result.keyframe = true;
    if (odometry_continuous_ && keyframe_odom_ && scan.odom)
      result.odometry_motion = keyframe_odom_->inverse() * *scan.odom;
    keyframe_odom_ = scan.odom;
    odometry_continuous_ = scan.odom.has_value();
    result.joins = scanSurfaces(scan.points, params_.surfaces);
    addKeyframe(result.pose, scan.points, result.joins);
  }
  return result;
}

SlamScan LocalTrajectoryBuilder::validScan(const SlamScan& in, SlamCounters& counters) const
{
  SlamScan scan;
  scan.stamp = in.stamp;
  scan.odom = in.odom;
  if (scan.odom &&
      !(std::isfinite(scan.odom->x) && std::isfinite(scan.odom->y) && std::isfinite(scan.odom->theta)))
    scan.odom.reset();
  const double max2 = params_.max_range * params_.max_range;
  scan.points.reserve(in.points.size());
  for (const auto& p : in.points)
    if (p.allFinite() && p.squaredNorm() <= max2) scan.points.push_back(p);
  if (!scan.odom) ++counters.without_odometry;
  return scan;
}

LocalTrajectoryBuilder::Prediction LocalTrajectoryBuilder::predict(const SlamScan& scan,
                                                                   SlamCounters& counters) const
{
  // Odometry since the last scan, unless it jumped or is missing (then constant velocity). A jump may
  // also be real motion during a gap in the log: then both are tried (matchFrontEnd).
  Prediction prediction;
  prediction.pose = last_local_;
  if (!have_scan_) return prediction;
  if (scan.odom && last_odom_)
  {
    const Pose2 step = last_odom_->inverse() * *scan.odom;
    if (params_.odometry_jump.isMotion(step, scan.stamp - last_stamp_))
    {
      prediction.odometry_usable = true;
      prediction.pose = last_local_ * step;
    }
    else
    {
      ++counters.odometry_jumps;
      prediction.jumped = last_local_ * step;
    }
  }
  if (!prediction.odometry_usable) prediction.pose = last_local_ * velocity_;
  return prediction;
}

bool LocalTrajectoryBuilder::barelyMoved(const SlamScan& scan, const Prediction& prediction) const
{
  // Then odometry is better than a fresh match over the same map.
  if (!have_scan_ || !prediction.odometry_usable || !last_matched_odom_ || recent_.empty()) return false;
  const Pose2 moved = last_matched_odom_->inverse() * *scan.odom;
  return std::hypot(moved.x, moved.y) < params_.filter_distance &&
         std::fabs(moved.theta) < params_.filter_angle;
}

std::optional<Pose2> LocalTrajectoryBuilder::matchFrontEnd(const SlamScan& scan, const Prediction& prediction,
                                                           Eigen::Matrix2d& weights, SlamCounters& counters)
{
  if (scan.points.size() < params_.min_points)
  {
    ++counters.few_points;
    return std::nullopt;
  }
  if (local_map_.empty()) return std::nullopt;
  // The normal window first; a poor match (odometry off by more than the window) or a prediction
  // without usable odometry gets the wide window, around each prediction there is.
  std::optional<MatchResult> best;
  auto attempt = [&](const Pose2& centre, bool wide) { return searchNear(scan, centre, wide, best); };
  const Pose2& predicted = prediction.pose;
  const bool at_edge = prediction.odometry_usable && attempt(predicted, false);
  // Poor against this run's own recent matches (an absolute floor would pass a match far worse than
  // the scene allows here), or at the window's edge: the odometry may be off by more than the window.
  const double enough = std::max(params_.min_score, params_.widen_ratio * typical_score_);
  counters.border_matches += at_edge ? 1 : 0;
  if (!best || best->score < enough || at_edge)
  {
    if (prediction.odometry_usable) ++counters.wide_searches;
    // Across an odometry jump the odometry's motion is a measurement and the constant velocity an
    // assumption: the odometry's pose stands unless its match is refused. (Where many headings look alike,
    // a round hall, the assumption finds a match as good or better: against a keyframe the front end posed
    // wrongly just before, after a gap in the log.)
    if (prediction.jumped) attempt(*prediction.jumped, true);
    if (!prediction.jumped || !best || best->score < params_.min_score) attempt(predicted, true);
  }
  if (!prediction.odometry_usable && (afterGap(scan) || velocity_across_pause_) &&
      (!best || best->score < enough))
  {
    const auto found = searchEveryHeading(scan);
    if (found && (!best || found->score > best->score)) best = found;
  }
  if (!best || best->score < params_.min_score)
  {
    ++counters.poor_matches;
    return std::nullopt;
  }
  typical_score_ = typical_score_ > 0.0 ? 0.9 * typical_score_ + 0.1 * best->score : best->score;
  run_score_matches_ = std::min(run_score_matches_ + 1, kRunScoreMatches);
  run_score_ += (best->score - run_score_) / static_cast<double>(run_score_matches_);
  // Without odometry too: the constant velocity is the only information along a corridor's axis, and a
  // match that lags there would slow the velocity it is predicted by.
  return heldToPrediction(*best, predicted, weights, counters);
}

bool LocalTrajectoryBuilder::searchNear(const SlamScan& scan, const Pose2& centre, bool wide,
                                        std::optional<MatchResult>& best) const
{
  const SearchWindow& window = wide ? params_.window_no_odometry : params_.window;
  const auto found = correlativeSearch(local_map_, scan.points, centre, window, 1);
  if (found.empty()) return false;
  // Held towards the prediction, not the search's pick: where the scan fixes nothing (along a
  // corridor) the search's choice is arbitrary, and it favours poses that keep every point
  // on the local map, i.e. lags behind; the prediction is the information there. Not in heading
  // after a wide search: the prediction's heading was what failed, and a scan fixes its heading.
  Pose2 prior = centre;
  if (wide) prior.theta = found.front().pose.theta;
  const MatchResult refined =
      refineMatch(local_map_, scan.points, found.front().pose, prior, params_.refinement);
  if (!best || refined.score > best->score) best = refined;
  // Whether the search's best heading is on the window's border: the true one may lie beyond it.
  return std::fabs(linemap::normalizeAngle(found.front().pose.theta - centre.theta)) >=
         window.angular - 0.5 * window.angular_step;
}

std::optional<MatchResult> LocalTrajectoryBuilder::searchEveryHeading(const SlamScan& scan) const
{
  // Without odometry across a gap in the scans the robot may have turned any way (ACES turns in place
  // during one): every heading around where the robot was, as far as it may have moved at its last speed.
  // So too for the scan after: its velocity, the motion through the gap taken as one scan's, may predict a
  // turn the robot no longer makes.
  SearchWindow around = params_.window_no_odometry;
  around.angular = M_PI;
  around.rotation_penalty = 0.0;
  const double periods = (scan.stamp - last_stamp_) / typical_period_;
  around.linear += std::min(std::hypot(velocity_.x, velocity_.y) * periods, params_.odometry_jump.step);
  const auto found = correlativeSearch(local_map_, scan.points, last_local_, around, 1);
  if (found.empty()) return std::nullopt;
  return refineMatch(local_map_, scan.points, found.front().pose, found.front().pose, params_.refinement);
}

Pose2 LocalTrajectoryBuilder::heldToPrediction(const MatchResult& match, const Pose2& predicted,
                                               Eigen::Matrix2d& weights, SlamCounters& counters) const
{
  // The match's translation where it determines one, the prediction's elsewhere.
  const TranslationShape shape = matchShape(match, params_);
  weights = shape.weights;
  if (shape.degenerate) ++counters.degenerate_matches;
  return heldToEstimate(match.pose, predicted, shape);
}

void LocalTrajectoryBuilder::countHeldTime(const LocalScanResult& result, const Prediction& prediction,
                                           SlamCounters& counters) const
{
  // Held: along its weakest direction the pose is more the prediction's than the match's.
  const bool held =
      result.outcome == SlamOutcome::kMatched && !prediction.odometry_usable &&
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(result.match_weights).eigenvalues()(0) <= 0.5;
  // Time, not the path: a speed held wrongly at zero moves the estimate nowhere. (A match has a scan
  // before it: the local map is made of earlier ones.)
  if (!held)
  {
    counters.held_time = 0.0;
    return;
  }
  counters.held_time += result.scan.stamp - last_stamp_;
  counters.longest_held_time = std::max(counters.longest_held_time, counters.held_time);
}

void LocalTrajectoryBuilder::countOutcome(SlamOutcome outcome, SlamCounters& counters)
{
  switch (outcome)
  {
    case SlamOutcome::kMatched:
      ++counters.matched;
      break;
    case SlamOutcome::kFiltered:
      ++counters.filtered;
      break;
    default:
      ++counters.predicted;
      if (!recent_.empty()) chain_matched_ = false;
  }
}

void LocalTrajectoryBuilder::advance(const SlamScan& scan, const Pose2& pose, SlamOutcome outcome)
{
  if (have_scan_)
  {
    const Pose2 step = last_local_.inverse() * pose;
    path_ += std::hypot(step.x, step.y);
    // Per-scan motion for the constant-velocity prediction (scans arrive at a steady rate): the motion
    // since the last match spread over the scans in between (taken whole, the motion across a run of
    // poor matches would be extrapolated as one scan's, and the prediction would run away). The
    // prediction stays one period's motion, not the time since the last scan's: logs also pause while the
    // robot stands, and a motion extrapolated over such a pause runs away.
    ++scans_since_match_;
    if (outcome == SlamOutcome::kMatched)
    {
      velocity_across_pause_ = pausedSinceMatch(scan);
      const Pose2 motion = last_matched_local_.inverse() * pose;
      const double n = static_cast<double>(scans_since_match_);
      velocity_ = Pose2(motion.x / n, motion.y / n, motion.theta / n);
    }
  }
  if (outcome == SlamOutcome::kMatched || !have_scan_)
  {
    last_matched_local_ = pose;
    last_matched_odom_ = scan.odom;
    scans_since_match_ = 0;
    last_matched_stamp_ = scan.stamp;
  }
  if (have_scan_)
  {
    // The scans' usual period, by a running median-like update that a gap hardly moves.
    const double dt = scan.stamp - last_stamp_;
    if (typical_period_ <= 0.0)
      typical_period_ = dt;
    else
      typical_period_ += 0.05 * typical_period_ * (dt > typical_period_ ? 1.0 : -1.0);
  }
  last_local_ = pose;
  last_odom_ = scan.odom;
  last_stamp_ = scan.stamp;
  have_scan_ = true;
}

bool LocalTrajectoryBuilder::afterGap(const SlamScan& scan) const
{
  return have_scan_ && typical_period_ > 0.0 && scan.stamp - last_stamp_ > kGapPeriods * typical_period_;
}

bool LocalTrajectoryBuilder::pausedSinceMatch(const SlamScan& scan) const
{
  return typical_period_ > 0.0 && scan.stamp - last_matched_stamp_ >
                                      kGapPeriods * typical_period_ * static_cast<double>(scans_since_match_);
}

bool LocalTrajectoryBuilder::isKeyframe(const SlamScan& scan, const Pose2& pose) const
{
  if (scan.points.size() < params_.min_points) return false;
  if (recent_.empty()) return true;
  const Pose2 since = recent_.back().local.inverse() * pose;
  return std::hypot(since.x, since.y) >= params_.keyframe_distance ||
         std::fabs(since.theta) >= params_.keyframe_angle;
}

void LocalTrajectoryBuilder::addKeyframe(const Pose2& pose, const std::vector<Vec2>& points,
                                         const std::vector<linemap::Segment2>& joins)
{
  recent_.push_back({pose, points, joins});
  // The last one stays even with local_map_keyframes 0: the next keyframe is decided from it.
  while (recent_.size() > std::max<std::size_t>(params_.local_map_keyframes, 1)) recent_.pop_front();
  chain_matched_ = true;
  rebuildLocalMap();
}

void LocalTrajectoryBuilder::injectSlip(const Pose2& slip)
{
  const Pose2 moved = last_local_ * slip;
  const Pose2 shift = moved * last_local_.inverse();  // the old front-end frame into the slipped one
  last_local_ = moved;
  last_matched_local_ = shift * last_matched_local_;
  for (auto& kf : recent_) kf.local = shift * kf.local;
  if (!recent_.empty()) rebuildLocalMap();
}

void LocalTrajectoryBuilder::resumeFrom(const std::vector<SlamKeyframe>& keyframes)
{
  *this = LocalTrajectoryBuilder(params_);
  if (keyframes.empty()) return;
  const std::size_t n = std::min(std::max<std::size_t>(params_.local_map_keyframes, 1), keyframes.size());
  for (std::size_t i = keyframes.size() - n; i < keyframes.size(); ++i)
    recent_.push_back({keyframes[i].local, keyframes[i].points, keyframes[i].joins});
  last_local_ = last_matched_local_ = keyframes.back().local;
  path_ = keyframes.back().path;
  rebuildLocalMap();
}

void LocalTrajectoryBuilder::restart(double path)
{
  *this = LocalTrajectoryBuilder(params_);
  path_ = path;
}

void LocalTrajectoryBuilder::rebuildLocalMap()
{
  std::vector<Vec2> points;
  std::vector<linemap::Segment2> joins;
  const std::size_t n = std::min(params_.local_map_keyframes, recent_.size());
  // Only what the next scans can reach: they are matched near the newest keyframe (a keyframe every few
  // decimetres, an odometry step at most max_odometry_step) and see max_range. Where the front end lost
  // track, the last keyframes lie far apart and their union would make the field unbounded.
  const Vec2 centre = recent_.back().local.translation();
  const double reach = params_.max_range + params_.odometry_jump.step + 1.0;
  const auto near = [&](const Vec2& q) { return (q - centre).cwiseAbs().maxCoeff() <= reach; };
  for (std::size_t i = recent_.size() - n; i < recent_.size(); ++i)
  {
    for (const auto& p : recent_[i].points)
      if (const Vec2 q = recent_[i].local.apply(p); near(q)) points.push_back(q);
    for (const auto& s : recent_[i].joins)
      if (const linemap::Segment2 t = s.transformed(recent_[i].local); near(t.start) || near(t.end))
        joins.push_back(t);
  }
  local_map_ = LikelihoodGrid(points, joins, params_.resolution, params_.sigma, 0.5);
}

}  // namespace line_map_merging
