#include "line_map_merging/localization/line_map_localizer.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "line_extraction/param_checks.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
using line_extraction::countParam;
using line_extraction::positiveParam;
using linemap::Pose2;
using linemap::Vec2;

namespace
{
double nowMs()
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double share(const linemap::ParamSet& p, const std::string& key, double fallback)
{
  const double v = p.getDouble(key, fallback);
  if (!(v >= 0.0 && v <= 1.0)) throw linemap::ParameterError(key + " must lie in [0, 1]");
  return v;
}

bool finitePose(const Pose2& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

bool samePlace(const Pose2& a, const Pose2& b, double distance, double angle)
{
  return std::hypot(a.x - b.x, a.y - b.y) < distance &&
         std::fabs(linemap::normalizeAngle(a.theta - b.theta)) < angle;
}
}  // namespace

LocalizerParams LocalizerParams::fromParams(const linemap::ParamSet& p)
{
  LocalizerParams s;
  s.max_range = positiveParam(p, "scan/max_range", s.max_range);
  s.min_points = countParam(p, "scan/min_points", s.min_points, 3);
  s.match.max_distance = positiveParam(p, "match/max_distance", s.match.max_distance);
  s.match.refine_distance = positiveParam(p, "match/refine_distance", s.match.refine_distance);
  s.match.loss_scale = positiveParam(p, "match/loss_scale", s.match.loss_scale);
  s.match.point_sigma = positiveParam(p, "match/point_sigma", s.match.point_sigma);
  s.match.inlier_distance = positiveParam(p, "match/inlier_distance", s.match.inlier_distance);
  s.match.max_iterations = static_cast<int>(countParam(p, "match/max_iterations", s.match.max_iterations, 1));
  s.match.check_free_side = p.getBool("match/check_free_side", s.match.check_free_side);
  s.index_cell = positiveParam(p, "match/index_cell", s.index_cell);
  s.odom_sigma_xy = positiveParam(p, "odometry/sigma_xy", s.odom_sigma_xy);
  s.odom_sigma_xy_per_m = p.getNonNegative("odometry/sigma_xy_per_m", s.odom_sigma_xy_per_m);
  s.odom_sigma_theta = positiveParam(p, "odometry/sigma_theta", s.odom_sigma_theta);
  s.odom_sigma_theta_per_rad = p.getNonNegative("odometry/sigma_theta_per_rad", s.odom_sigma_theta_per_rad);
  s.odom_sigma_theta_per_m = p.getNonNegative("odometry/sigma_theta_per_m", s.odom_sigma_theta_per_m);
  s.no_odom_sigma_xy = positiveParam(p, "odometry/no_odometry_sigma_xy", s.no_odom_sigma_xy);
  s.no_odom_sigma_theta = positiveParam(p, "odometry/no_odometry_sigma_theta", s.no_odom_sigma_theta);
  s.odometry_jump.step = positiveParam(p, "odometry/max_step", s.odometry_jump.step);
  s.odometry_jump.turn = positiveParam(p, "odometry/max_turn", s.odometry_jump.turn);
  s.odometry_jump.speed = p.getNonNegative("odometry/max_speed", s.odometry_jump.speed);
  s.odometry_jump.turn_rate = p.getNonNegative("odometry/max_turn_rate", s.odometry_jump.turn_rate);
  s.time_jump_tolerance = positiveParam(p, "odometry/time_jump_tolerance", s.time_jump_tolerance);
  s.retry_inlier_share = share(p, "tracking/retry_inlier_share", s.retry_inlier_share);
  s.retry_window.linear = p.getNonNegative("tracking/retry_linear", s.retry_window.linear);
  s.retry_window.angular = p.getNonNegative("tracking/retry_angular", s.retry_window.angular);
  s.lost_inlier_share = share(p, "tracking/lost_inlier_share", s.lost_inlier_share);
  s.lost_scans = countParam(p, "tracking/lost_scans", s.lost_scans, 1);
  s.doubt_share = share(p, "tracking/doubt_share", s.doubt_share);
  s.doubt_research_every = countParam(p, "tracking/doubt_research_every", s.doubt_research_every, 1);
  s.doubt_hypotheses = countParam(p, "tracking/doubt_hypotheses", s.doubt_hypotheses, 1);
  s.global.coarse_resolution = positiveParam(p, "global/coarse_resolution", s.global.coarse_resolution);
  s.global.coarse_sigma = positiveParam(p, "global/coarse_sigma", s.global.coarse_sigma);
  s.global.coarse_angular_step = positiveParam(p, "global/coarse_angular_step", s.global.coarse_angular_step);
  s.global.fine_resolution = positiveParam(p, "global/fine_resolution", s.global.fine_resolution);
  s.global.fine_sigma = positiveParam(p, "global/fine_sigma", s.global.fine_sigma);
  s.global.max_points = countParam(p, "global/max_points", s.global.max_points, 3);
  s.global.candidates = countParam(p, "global/candidates", s.global.candidates, 1);
  s.hypothesis_min_share = share(p, "global/hypothesis_min_share", s.hypothesis_min_share);
  s.hypotheses = countParam(p, "global/hypotheses", s.hypotheses, 1);
  s.research_every = countParam(p, "global/research_every", s.research_every, 1);
  s.research_every_apart = countParam(p, "global/research_every_apart", s.research_every_apart, 1);
  s.accept_share = share(p, "global/accept_share", s.accept_share);
  s.accept_margin = share(p, "global/accept_margin", s.accept_margin);
  s.accept_travel = p.getNonNegative("global/accept_travel", s.accept_travel);
  s.accept_turn = p.getNonNegative("global/accept_turn", s.accept_turn);
  s.accept_scans = countParam(p, "global/accept_scans", s.accept_scans, 1);
  return s;
}

LineMapLocalizer::LineMapLocalizer(const std::vector<linemap::Segment2>& segments,
                                   const LocalizerParams& params)
    : params_(params),
      index_(segments, params.index_cell, params.match.max_distance),
      global_(index_.segments(), params.global),
      time_jumps_(params.time_jump_tolerance, {"scan"})
{
}

void LineMapLocalizer::setMap(const std::vector<linemap::Segment2>& segments)
{
  index_ = LocalizationSegmentIndex(segments, params_.index_cell, params_.match.max_distance);
  global_ = LocalizationGlobalSearch(index_.segments(), params_.global);
  // The track, or the search, goes on in the new map: a map that grows (the merger's topic) keeps
  // its frame.
  hypotheses_.clear();
}

void LineMapLocalizer::setPose(const Pose2& pose)
{
  if (!finitePose(pose)) return;
  pose_ = {pose.x, pose.y, linemap::normalizeAngle(pose.theta)};
  tracking_ = true;
  poor_in_row_ = 0;
  track_share_ = 1.0;
  hypotheses_.clear();
}

void LineMapLocalizer::startGlobalLocalization()
{
  tracking_ = false;
  poor_in_row_ = 0;
  hypotheses_.clear();
}

PosePrior LineMapLocalizer::odometryPrior(const Pose2& predicted, const std::optional<Pose2>& step) const
{
  double sxy = params_.no_odom_sigma_xy, sth = params_.no_odom_sigma_theta;
  if (step)
  {
    const double d = std::hypot(step->x, step->y), r = std::fabs(step->theta);
    sxy = params_.odom_sigma_xy + params_.odom_sigma_xy_per_m * d;
    sth =
        params_.odom_sigma_theta + params_.odom_sigma_theta_per_rad * r + params_.odom_sigma_theta_per_m * d;
  }
  PosePrior prior;
  prior.mean = predicted;
  prior.information.diagonal() << 1.0 / (sxy * sxy), 1.0 / (sxy * sxy), 1.0 / (sth * sth);
  return prior;
}

SegmentMatch LineMapLocalizer::track(const LocalizerScan& scan, const Pose2& predicted,
                                     const PosePrior& prior, bool allow_retry)
{
  SegmentMatch m = matchToSegments(index_, scan.points, predicted, prior, params_.match, scan.sensor);
  if (!allow_retry || m.inlier_share >= params_.retry_inlier_share || global_.fineField().empty()) return m;
  // The odometry may have slipped beyond the prior's reach: search around the prediction, and let
  // the prior pull only weakly from there.
  ++counters_.retries;
  const auto found = correlativeSearch(global_.fineField(), scan.points, predicted, params_.retry_window, 1);
  if (found.empty()) return m;
  PosePrior weak = prior;
  weak.information *= 0.01;
  const SegmentMatch retried =
      matchToSegments(index_, scan.points, found.front().pose, weak, params_.match, scan.sensor);
  return retried.inlier_share > m.inlier_share + 0.05 ? retried : m;
}

LocalizerResult LineMapLocalizer::addScan(const LocalizerScan& in)
{
  const double start = nowMs();
  ++counters_.scans;
  if (!acceptStamp(in.stamp))
  {
    LocalizerResult r = last_;
    r.outcome = LocalizerOutcome::kRejected;
    return r;
  }
  LocalizerScan scan;
  scan.stamp = in.stamp;
  scan.sensor = in.sensor.allFinite() ? in.sensor : Vec2::Zero();
  const double max2 = params_.max_range * params_.max_range;
  scan.points.reserve(in.points.size());
  for (const auto& p : in.points)
    if (p.allFinite() && p.squaredNorm() <= max2 && p.squaredNorm() > 0.0) scan.points.push_back(p);
  const OdometryMotion motion = odometryMotion(in.odom, in.stamp);
  const LocalizerResult result =
      tracking_ ? trackStep(scan, motion.step, motion.jump) : globalStep(scan, motion.step);
  counters_.last_ms = nowMs() - start;
  last_ = result;
  return result;
}

bool LineMapLocalizer::acceptStamp(double stamp)
{
  if (time_jumps_.observe(0.0, stamp))
  {
    // The clock jumped back (a replayed bag): the odometry before it tells nothing about the motion.
    ++counters_.time_jumps;
    last_odom_.reset();
  }
  else if (have_stamp_ && !(stamp > last_stamp_))
  {
    ++counters_.rejected;
    return false;
  }
  have_stamp_ = true;
  last_stamp_ = stamp;
  return true;
}

LineMapLocalizer::OdometryMotion LineMapLocalizer::odometryMotion(const std::optional<Pose2>& reading,
                                                                  double stamp)
{
  OdometryMotion motion;
  std::optional<Pose2> odom = reading && finitePose(*reading) ? reading : std::nullopt;
  if (odom && last_odom_)
  {
    const Pose2 s = last_odom_->inverse() * *odom;
    if (params_.odometry_jump.isMotion(s, stamp - last_odom_stamp_))
      motion.step = s;
    else
    {
      ++counters_.odometry_jumps;
      motion.jump = s;
    }
  }
  if (odom)
  {
    last_odom_ = odom;
    last_odom_stamp_ = stamp;
  }
  return motion;
}

LocalizerResult LineMapLocalizer::trackStep(const LocalizerScan& scan, const std::optional<Pose2>& step,
                                            const std::optional<Pose2>& jump)
{
  LocalizerResult result;
  const Pose2 predicted = step ? pose_ * *step : pose_;
  const PosePrior prior = odometryPrior(predicted, step);
  result.pose = predicted;
  result.covariance = prior.information.inverse();
  result.outcome = LocalizerOutcome::kPredicted;
  bool poor = true;
  if (scan.points.size() < params_.min_points)
    ++counters_.few_points;
  else if (!index_.empty())
  {
    SegmentMatch m = track(scan, predicted, prior, true);
    if (jump) matchAcrossJump(scan, *jump, m);
    result.score = m.score;
    result.inlier_share = m.inlier_share;
    poor = m.inlier_share < params_.lost_inlier_share;
    if (m.valid && !poor)
    {
      result.pose = m.pose;
      result.covariance = m.covariance;
      result.outcome = LocalizerOutcome::kTracked;
    }
  }
  pose_ = result.pose;
  result.localized = true;
  // A scan without points says nothing about being lost; a poor one does, once it persists.
  if (scan.points.size() >= params_.min_points) poor_in_row_ = poor ? poor_in_row_ + 1 : 0;
  if (result.outcome == LocalizerOutcome::kTracked)
    ++counters_.tracked;
  else
    ++counters_.predicted;
  if (poor_in_row_ >= params_.lost_scans && !index_.empty())
  {
    ++counters_.lost;
    startGlobalLocalization();
    result.localized = false;
  }
  else if (scan.points.size() >= params_.min_points && !index_.empty())
    challengeTrack(scan, step, result);
  return result;
}

void LineMapLocalizer::matchAcrossJump(const LocalizerScan& scan, const Pose2& jump, SegmentMatch& best) const
{
  // The odometry jumped: a glitch, or real motion across a gap in the data. Both are searched
  // widely and the better match wins.
  for (const Pose2& centre : {pose_ * jump, pose_})
  {
    const auto found = correlativeSearch(global_.fineField(), scan.points, centre, params_.jump_window, 1);
    if (found.empty()) continue;
    const SegmentMatch c =
        matchToSegments(index_, scan.points, found.front().pose, std::nullopt, params_.match, scan.sensor);
    if (c.valid && c.inlier_share > best.inlier_share) best = c;
  }
}

LocalizerResult LineMapLocalizer::globalStep(const LocalizerScan& scan, const std::optional<Pose2>& step)
{
  ++counters_.searching;
  LocalizerResult result;
  result.outcome = LocalizerOutcome::kSearching;
  // Until a hypothesis is accepted the pose shown is dead reckoning from the last one known: a lost
  // robot's odometry stays closer than the hypotheses jumping about the map.
  if (step) pose_ = pose_ * *step;
  result.pose = pose_;
  result.covariance = Eigen::Matrix3d::Identity() * 1e6;
  if (scan.points.size() < params_.min_points || index_.empty())
  {
    if (scan.points.size() < params_.min_points) ++counters_.few_points;
    for (auto& h : hypotheses_)
      if (step) h.pose = h.pose * *step;
    return result;
  }
  updateHypotheses(scan, step, params_.research_every, params_.hypotheses);
  if (hypotheses_.empty()) return result;
  result.score = hypotheses_.front().last.score;
  result.inlier_share = hypotheses_.front().last.inlier_share;
  const Hypothesis* best = acceptable(params_.accept_share);
  if (!best) return result;
  const SegmentMatch accepted = best->last;
  setPose(best->pose);
  ++counters_.recovered;
  result.outcome = LocalizerOutcome::kRecovered;
  result.localized = true;
  result.pose = pose_;
  result.covariance = accepted.covariance;
  return result;
}

void LineMapLocalizer::challengeTrack(const LocalizerScan& scan, const std::optional<Pose2>& step,
                                      LocalizerResult& result)
{
  const double alpha = params_.hypothesis_smoothing;
  track_share_ = (1.0 - alpha) * track_share_ + alpha * result.inlier_share;
  if (track_share_ >= params_.doubt_share)
  {
    hypotheses_.clear();
    return;
  }
  if (hypotheses_.empty()) ++counters_.doubted;
  // Fewer rivals and rarer searches than when lost: a doubted track is usually right (a part of the
  // map missing), and this runs beside it.
  updateHypotheses(scan, step, params_.doubt_research_every, params_.doubt_hypotheses);
  // Hypotheses at the track itself are no rivals of it.
  hypotheses_.erase(std::remove_if(hypotheses_.begin(), hypotheses_.end(),
                                   [&](const Hypothesis& h) {
                                     return samePlace(h.pose, pose_, params_.global.separation,
                                                      params_.global.separation_angle);
                                   }),
                    hypotheses_.end());
  const Hypothesis* best = acceptable(track_share_ + params_.accept_margin);
  if (!best || best->mean_share < params_.accept_share) return;
  ++counters_.replaced;
  const SegmentMatch accepted = best->last;
  setPose(best->pose);
  result.pose = pose_;
  result.covariance = accepted.covariance;
  result.outcome = LocalizerOutcome::kRecovered;
}

void LineMapLocalizer::updateHypotheses(const LocalizerScan& scan, const std::optional<Pose2>& step,
                                        std::size_t research_every, std::size_t max_hypotheses)
{
  // Every hypothesis follows the odometry and is matched.
  const double alpha = params_.hypothesis_smoothing;
  for (auto& h : hypotheses_)
  {
    const Pose2 predicted = step ? h.pose * *step : h.pose;
    h.last = matchToSegments(index_, scan.points, predicted, odometryPrior(predicted, step), params_.match,
                             scan.sensor);
    h.pose = h.last.valid ? h.last.pose : predicted;
    h.mean_share = (1.0 - alpha) * h.mean_share + alpha * h.last.inlier_share;
    ++h.scans;
    if (step)
    {
      h.travel += std::hypot(step->x, step->y);
      h.turn += std::fabs(step->theta);
    }
  }
  hypotheses_.erase(
      std::remove_if(hypotheses_.begin(), hypotheses_.end(),
                     [&](const Hypothesis& h) { return h.mean_share < params_.hypothesis_min_share; }),
      hypotheses_.end());
  // Hypotheses that converged on one pose: the one with the longer history stays.
  std::stable_sort(hypotheses_.begin(), hypotheses_.end(),
                   [](const Hypothesis& a, const Hypothesis& b) { return a.scans > b.scans; });
  const double sep = params_.global.separation / 3.0, sep_angle = params_.global.separation_angle / 3.0;
  std::vector<Hypothesis> kept;
  for (const auto& h : hypotheses_)
    if (std::none_of(kept.begin(), kept.end(),
                     [&](const Hypothesis& k) { return samePlace(h.pose, k.pose, sep, sep_angle); }))
      kept.push_back(h);
  hypotheses_ = std::move(kept);

  if (hypotheses_.empty() || scans_since_search_ >= research_every)
  {
    const double t0 = nowMs();
    ++counters_.global_searches;
    scans_since_search_ = 0;
    for (const auto& c : global_.search(scan.points))
    {
      Hypothesis h;
      h.last = matchToSegments(index_, scan.points, c.pose, std::nullopt, params_.match, scan.sensor);
      if (!h.last.valid) continue;
      h.pose = h.last.pose;
      h.mean_share = h.last.inlier_share;
      h.scans = 1;
      if (std::any_of(hypotheses_.begin(), hypotheses_.end(),
                      [&](const Hypothesis& k) { return samePlace(h.pose, k.pose, sep, sep_angle); }))
        continue;
      hypotheses_.push_back(h);
    }
    counters_.last_global_search_ms = nowMs() - t0;
  }
  else
    ++scans_since_search_;
  std::stable_sort(hypotheses_.begin(), hypotheses_.end(),
                   [](const Hypothesis& a, const Hypothesis& b) { return a.mean_share > b.mean_share; });
  if (hypotheses_.size() > max_hypotheses) hypotheses_.resize(max_hypotheses);
}

const LineMapLocalizer::Hypothesis* LineMapLocalizer::acceptable(double floor) const
{
  // The best hypothesis tested over enough motion (they are sorted by mean share), and its lead over
  // every distinct rival.
  const Hypothesis* best = nullptr;
  for (const auto& h : hypotheses_)
    if (h.scans >= params_.accept_scans &&
        (h.travel >= params_.accept_travel || h.turn >= params_.accept_turn))
    {
      best = &h;
      break;
    }
  if (!best || best->mean_share < floor) return nullptr;
  double rival = 0.0;
  for (const auto& h : hypotheses_)
    if (&h != best && h.scans >= 3 &&
        !samePlace(h.pose, best->pose, params_.global.separation, params_.global.separation_angle))
      rival = std::max(rival, h.mean_share);
  return best->mean_share - rival >= params_.accept_margin ? best : nullptr;
}

std::vector<std::pair<std::string, std::string>> LineMapLocalizer::diagnostics() const
{
  const auto& c = counters_;
  auto n = [](std::size_t v) { return std::to_string(v); };
  auto ms = [](double v)
  {
    std::ostringstream s;
    s.precision(3);
    s << v;
    return s.str();
  };
  return {{"state", tracking_ ? "tracking" : "global localization"},
          {"map segments", n(index_.segments().size())},
          {"match score", ms(last_.score)},
          {"inlier share", ms(last_.inlier_share)},
          {"scans", n(c.scans)},
          {"tracked scans", n(c.tracked)},
          {"scans posed by prediction", n(c.predicted)},
          {"scans during global localization", n(c.searching)},
          {"hypotheses", n(hypotheses_.size())},
          {"retries from a local search", n(c.retries)},
          {"scans with too few points", n(c.few_points)},
          {"odometry jumps", n(c.odometry_jumps)},
          {"scans out of order (ignored)", n(c.rejected)},
          {"time jumps back", n(c.time_jumps)},
          {"lost", n(c.lost)},
          {"recovered", n(c.recovered)},
          {"tracks doubted (rivals tracked)", n(c.doubted)},
          {"tracks replaced by a rival", n(c.replaced)},
          {"global searches", n(c.global_searches)},
          {"last scan [ms]", ms(c.last_ms)},
          {"last global search [ms]", ms(c.last_global_search_ms)}};
}

std::vector<linemap::Vec2> beamPoints(const line_extraction::ScanInput& scan, const linemap::Pose2& mount)
{
  std::vector<linemap::Vec2> points;
  points.reserve(scan.count);
  for (std::size_t i = 0; i < scan.count; ++i)
  {
    const double r = scan.ranges[i];
    if (!(r >= scan.range_min && r < scan.range_max)) continue;  // NaN and inf fail too
    const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    points.push_back(mount.apply({r * std::cos(a), r * std::sin(a)}));
  }
  return points;
}

std::vector<linemap::Segment2> loadLineMapSegments(const std::string& path)
{
  CaeRlsm merger;
  merger.load(path);
  std::vector<linemap::Segment2> segments;
  for (const auto& s : merger.map()) segments.push_back(s.segment);
  return segments;
}

}  // namespace line_map_merging
