#include "line_map_merging/slam/laser_slam.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <chrono>
#include <cmath>
#include <sstream>

#include "line_extraction/param_checks.hpp"
#include "line_map_merging/slam/chain_edge.hpp"
#include "line_map_merging/slam/relative_uncertainty.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
namespace
{
using line_extraction::countParam;
using line_extraction::positiveParam;
using linemap::Pose2;
using linemap::Vec2;

void readWindow(const linemap::ParamSet& p, const std::string& block, SearchWindow& w)
{
  w.linear = p.getDouble(block + "/linear", w.linear);
  w.angular = p.getDouble(block + "/angular", w.angular);
  w.linear_step = p.getDouble(block + "/linear_step", w.linear_step);
  w.angular_step = p.getDouble(block + "/angular_step", w.angular_step);
  w.translation_penalty = p.getDouble(block + "/translation_penalty", w.translation_penalty);
  w.rotation_penalty = p.getDouble(block + "/rotation_penalty", w.rotation_penalty);
  if (!(w.linear >= 0.0) || !(w.angular >= 0.0) || !(w.angular_step > 0.0))
    throw linemap::ParameterError(block + "/linear, /angular must be >= 0 and /angular_step > 0");
}

/// The closure edge j -> k measured by a loop match, its information shaped by the match's.
PoseGraphEdge loopEdge(std::size_t j, std::size_t k, const Pose2& measurement, const TranslationShape& shape,
                       const LaserSlamParams& params)
{
  PoseGraphEdge e;
  e.from = j;
  e.to = k;
  e.measurement = measurement;
  e.sigma_xy = params.loop_sigma_xy;
  e.sigma_theta = params.loop_sigma_theta;
  e.translation_weights = shape.weights;
  e.loop = true;
  return e;
}
}  // namespace

std::string closureSummary(const SlamCounters& c)
{
  std::ostringstream out;
  out << c.loops_accepted << " closures of " << c.loop_attempts
      << " attempts (refused: " << c.loops_rejected_score << " score, " << c.loops_ambiguous << " ambiguous, "
      << c.loops_inconsistent << " inconsistent, " << c.loops_rejected_graph << " graph, " << c.loops_pending
      << " uncorroborated)";
  return out.str();
}

// A line per parameter: long, but a list rather than steps.
LaserSlamParams LaserSlamParams::fromParams(const linemap::ParamSet& p)
{
  LaserSlamParams s;
  s.max_range = positiveParam(p, "front_end/max_range", s.max_range);
  s.min_points = countParam(p, "front_end/min_points", s.min_points, 3);
  s.resolution = positiveParam(p, "front_end/resolution", s.resolution);
  s.sigma = positiveParam(p, "front_end/sigma", s.sigma);
  readWindow(p, "front_end/window", s.window);
  readWindow(p, "front_end/window_no_odometry", s.window_no_odometry);
  s.refinement.translation_weight =
      p.getDouble("front_end/refinement/translation_weight", s.refinement.translation_weight);
  s.refinement.rotation_weight =
      p.getDouble("front_end/refinement/rotation_weight", s.refinement.rotation_weight);
  s.refinement.max_iterations = static_cast<int>(countParam(
      p, "front_end/refinement/max_iterations", static_cast<std::size_t>(s.refinement.max_iterations), 1));
  s.min_score = p.getDouble("front_end/min_score", s.min_score);
  s.widen_ratio = p.getDouble("front_end/widen_ratio", s.widen_ratio);
  if (!(s.widen_ratio >= 0.0 && s.widen_ratio <= 1.0))
    throw linemap::ParameterError("parameter 'front_end/widen_ratio' must be in [0, 1]");
  s.filter_distance = p.getDouble("front_end/filter_distance", s.filter_distance);
  s.filter_angle = p.getDouble("front_end/filter_angle", s.filter_angle);
  s.keyframe_distance = positiveParam(p, "front_end/keyframe_distance", s.keyframe_distance);
  s.keyframe_angle = positiveParam(p, "front_end/keyframe_angle", s.keyframe_angle);
  s.local_map_keyframes = countParam(p, "front_end/local_map_keyframes", s.local_map_keyframes, 1);
  s.surfaces.lambda = p.getDouble("front_end/surface_lambda", s.surfaces.lambda);
  if (!(s.surfaces.lambda >= 0.0 && s.surfaces.lambda < linemap::kPi / 2))
    throw linemap::ParameterError("parameter 'front_end/surface_lambda' must be in [0, pi/2) rad");
  s.surfaces.range_sigma = positiveParam(p, "front_end/range_sigma", s.surfaces.range_sigma);
  s.max_odometry_step = positiveParam(p, "front_end/max_odometry_step", s.max_odometry_step);
  s.max_odometry_turn = positiveParam(p, "front_end/max_odometry_turn", s.max_odometry_turn);
  s.time_jump_tolerance = positiveParam(p, "front_end/time_jump_tolerance", s.time_jump_tolerance);
  s.edge_sigma_xy = positiveParam(p, "graph/edge_sigma_xy", s.edge_sigma_xy);
  s.edge_sigma_theta = positiveParam(p, "graph/edge_sigma_theta", s.edge_sigma_theta);
  s.odometry_sigma_xy = positiveParam(p, "graph/odometry_sigma_xy", s.odometry_sigma_xy);
  s.odometry_sigma_theta = positiveParam(p, "graph/odometry_sigma_theta", s.odometry_sigma_theta);
  s.loop_sigma_xy = positiveParam(p, "graph/loop_sigma_xy", s.loop_sigma_xy);
  s.loop_sigma_theta = positiveParam(p, "graph/loop_sigma_theta", s.loop_sigma_theta);
  s.loop_loss_scale = positiveParam(p, "graph/loop_loss_scale", s.loop_loss_scale);
  s.loop_min_path = p.getDouble("loop/min_path", s.loop_min_path);
  s.loop_radius = positiveParam(p, "loop/radius", s.loop_radius);
  s.loop_radius_growth = p.getDouble("loop/radius_growth", s.loop_radius_growth);
  s.loop_max_radius = positiveParam(p, "loop/max_radius", s.loop_max_radius);
  s.loop_angle = positiveParam(p, "loop/angle", s.loop_angle);
  s.loop_angle_growth = p.getDouble("loop/angle_growth", s.loop_angle_growth);
  s.loop_max_angle = positiveParam(p, "loop/max_angle", s.loop_max_angle);
  s.loop_resolution = positiveParam(p, "loop/resolution", s.loop_resolution);
  s.loop_angular_step = positiveParam(p, "loop/angular_step", s.loop_angular_step);
  s.loop_submap_keyframes = countParam(p, "loop/submap_keyframes", s.loop_submap_keyframes, 0);
  s.loop_candidates = countParam(p, "loop/candidates", s.loop_candidates, 0);
  s.loop_every = countParam(p, "loop/every", s.loop_every, 1);
  s.loop_min_score = p.getDouble("loop/min_score", s.loop_min_score);
  s.loop_max_error_xy = positiveParam(p, "loop/max_error_xy", s.loop_max_error_xy);
  s.loop_max_error_theta = positiveParam(p, "loop/max_error_theta", s.loop_max_error_theta);
  s.loop_corroborate_xy = p.getDouble("loop/corroborate_xy", s.loop_corroborate_xy);
  s.loop_corroborate_theta = p.getDouble("loop/corroborate_theta", s.loop_corroborate_theta);
  s.loop_agreement_xy = p.getDouble("loop/agreement_xy", s.loop_agreement_xy);
  s.loop_agreement_theta = p.getDouble("loop/agreement_theta", s.loop_agreement_theta);
  s.loop_pending_keyframes = countParam(p, "loop/pending_keyframes", s.loop_pending_keyframes, 1);
  s.loop_ambiguity_distance = p.getDouble("loop/ambiguity_distance", s.loop_ambiguity_distance);
  s.loop_ambiguity_ratio = p.getDouble("loop/ambiguity_ratio", s.loop_ambiguity_ratio);
  s.loop_consistency_probability =
      p.getDouble("loop/consistency_probability", s.loop_consistency_probability);
  if (!(s.loop_consistency_probability >= 0.0 && s.loop_consistency_probability < 1.0))
    throw linemap::ParameterError("parameter 'loop/consistency_probability' must be in [0, 1)");
  s.loop_scale_by_disagreement = p.getDouble("loop/scale_by_disagreement", s.loop_scale_by_disagreement);
  s.loop_consistent_xy = p.getDouble("loop/consistent_xy", s.loop_consistent_xy);
  s.loop_consistent_theta = p.getDouble("loop/consistent_theta", s.loop_consistent_theta);
  s.isotropic_ratio = p.getDouble("isotropic_ratio", s.isotropic_ratio);
  if (!(s.isotropic_ratio >= 0.0 && s.isotropic_ratio <= 1.0))
    throw linemap::ParameterError("parameter 'isotropic_ratio' must be in [0, 1]");
  s.min_weight = p.getDouble("min_weight", s.min_weight);
  if (!(s.min_weight > 0.0 && s.min_weight <= 1.0))
    throw linemap::ParameterError("parameter 'min_weight' must be in (0, 1]");
  return s;
}

LaserSlam::LaserSlam(const LaserSlamParams& params)
    : params_(params),
      consistency_gate_(
          params.loop_consistency_probability > 0.0
              ? boost::math::quantile(boost::math::chi_squared(3.0), params.loop_consistency_probability)
              : std::numeric_limits<double>::infinity()),
      graph_(PoseGraphParams{params.loop_loss_scale, 50}),
      time_jumps_(params.time_jump_tolerance, {"scan"})
{
}

void LaserSlam::reset()
{
  graph_.clear();
  keyframes_.clear();
  local_map_ = LikelihoodGrid();
  scans_.clear();
  have_scan_ = false;
  last_local_ = last_matched_local_ = velocity_ = Pose2();
  scans_since_match_ = 0;
  typical_score_ = 0.0;
  last_odom_.reset();
  last_matched_odom_.reset();
  path_ = path_at_closure_ = 0.0;
  chain_matched_ = true;
  pending_.reset();
  closures_.clear();
  time_jumps_.reset();
}

bool LaserSlam::observeStamp(double stamp)
{
  if (!time_jumps_.observe(0.0, stamp)) return false;
  ++counters_.time_jumps;
  return true;
}

bool LaserSlam::restartOnTimeJump(double stamp)
{
  // The check alone, on a copy: addScan records the stamp when the scan comes.
  linemap::TimeJumpDetector probe = time_jumps_;
  if (!probe.observe(0.0, stamp)) return false;
  ++counters_.time_jumps;
  ++counters_.new_trajectories;
  reset();
  return true;
}

SlamOutcome LaserSlam::addScan(const SlamScan& in)
{
  keyframe_added_ = graph_optimized_ = false;
  ++counters_.scans;
  observeStamp(in.stamp);
  if (have_scan_ && !(in.stamp > last_stamp_))
  {
    ++counters_.rejected;
    return SlamOutcome::kRejected;
  }
  const auto start = std::chrono::steady_clock::now();
  const SlamScan scan = validScan(in);
  const Prediction prediction = predict(scan);
  last_match_weights_ = Eigen::Matrix2d::Identity();
  SlamOutcome outcome = SlamOutcome::kPredicted;
  Pose2 pose = prediction.pose;
  if (barelyMoved(scan, prediction))
    outcome = SlamOutcome::kFiltered;
  else if (const auto matched = matchFrontEnd(scan, prediction))
  {
    pose = *matched;
    outcome = SlamOutcome::kMatched;
  }
  countOutcome(outcome);
  advance(scan, pose, outcome);

  const std::size_t index = scans_.size();
  if (isKeyframe(scan, pose)) addKeyframe(scan, index, chain_matched_);
  if (keyframes_.empty())
  {
    // No keyframe yet (the first scans were empty): nothing to hang the scan on.
    scans_.push_back({scan.stamp, static_cast<std::size_t>(-1), pose});
  }
  else
    scans_.push_back({scan.stamp, keyframes_.size() - 1, keyframes_.back().local.inverse() * pose});
  counters_.last_match_ms = linemap::millisecondsSince(start);
  return outcome;
}

SlamScan LaserSlam::validScan(const SlamScan& in)
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
  if (!scan.odom) ++counters_.without_odometry;
  return scan;
}

LaserSlam::Prediction LaserSlam::predict(const SlamScan& scan)
{
  // Odometry since the last scan, unless it jumped or is missing (then constant velocity). A jump may
  // also be real motion during a gap in the log: then both are tried (matchFrontEnd).
  Prediction prediction;
  prediction.pose = last_local_;
  if (!have_scan_) return prediction;
  if (scan.odom && last_odom_)
  {
    const Pose2 step = last_odom_->inverse() * *scan.odom;
    if (std::hypot(step.x, step.y) <= params_.max_odometry_step &&
        std::fabs(step.theta) <= params_.max_odometry_turn)
    {
      prediction.odometry_usable = true;
      prediction.pose = last_local_ * step;
    }
    else
    {
      ++counters_.odometry_jumps;
      prediction.jumped = last_local_ * step;
    }
  }
  if (!prediction.odometry_usable) prediction.pose = last_local_ * velocity_;
  return prediction;
}

bool LaserSlam::barelyMoved(const SlamScan& scan, const Prediction& prediction) const
{
  // Then odometry is better than a fresh match over the same map.
  if (!have_scan_ || !prediction.odometry_usable || !last_matched_odom_ || keyframes_.empty()) return false;
  const Pose2 moved = last_matched_odom_->inverse() * *scan.odom;
  return std::hypot(moved.x, moved.y) < params_.filter_distance &&
         std::fabs(moved.theta) < params_.filter_angle;
}

std::optional<Pose2> LaserSlam::matchFrontEnd(const SlamScan& scan, const Prediction& prediction)
{
  if (scan.points.size() < params_.min_points)
  {
    ++counters_.few_points;
    return std::nullopt;
  }
  if (local_map_.empty()) return std::nullopt;
  // The normal window first; a poor match (odometry off by more than the window) or a prediction
  // without usable odometry gets the wide window, around each prediction there is.
  std::optional<MatchResult> best;
  auto attempt = [&](const Pose2& centre, bool wide)
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
  };
  const Pose2& predicted = prediction.pose;
  const bool at_edge = prediction.odometry_usable && attempt(predicted, false);
  // Poor against this run's own recent matches (an absolute floor would pass a match far worse than
  // the scene allows here), or at the window's edge: the odometry may be off by more than the window.
  const double enough = std::max(params_.min_score, params_.widen_ratio * typical_score_);
  if (!best || best->score < enough || at_edge)
  {
    if (prediction.odometry_usable) ++counters_.wide_searches;
    attempt(predicted, true);
    if (prediction.jumped) attempt(*prediction.jumped, true);
  }
  if (!best || best->score < params_.min_score)
  {
    ++counters_.poor_matches;
    return std::nullopt;
  }
  typical_score_ = typical_score_ > 0.0 ? 0.9 * typical_score_ + 0.1 * best->score : best->score;
  Pose2 pose = best->pose;
  if (prediction.odometry_usable)
  {
    // The match's translation where it determines one, the odometry's elsewhere.
    const TranslationShape shape = matchShape(*best);
    last_match_weights_ = shape.weights;
    if (shape.degenerate)
    {
      const Vec2 t =
          predicted.translation() + shape.weights * (best->pose.translation() - predicted.translation());
      pose.x = t.x();
      pose.y = t.y();
      ++counters_.degenerate_matches;
    }
  }
  return pose;
}

void LaserSlam::countOutcome(SlamOutcome outcome)
{
  switch (outcome)
  {
    case SlamOutcome::kMatched:
      ++counters_.matched;
      break;
    case SlamOutcome::kFiltered:
      ++counters_.filtered;
      break;
    default:
      ++counters_.predicted;
      if (!keyframes_.empty()) chain_matched_ = false;
  }
}

void LaserSlam::advance(const SlamScan& scan, const Pose2& pose, SlamOutcome outcome)
{
  if (have_scan_)
  {
    const Pose2 step = last_local_.inverse() * pose;
    path_ += std::hypot(step.x, step.y);
    // Per-scan motion for the constant-velocity prediction (scans arrive at a steady rate): the motion
    // since the last match spread over the scans in between (taken whole, the motion across a run of
    // poor matches would be extrapolated as one scan's, and the prediction would run away).
    ++scans_since_match_;
    if (outcome == SlamOutcome::kMatched)
    {
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
  }
  last_local_ = pose;
  last_odom_ = scan.odom;
  last_stamp_ = scan.stamp;
  have_scan_ = true;
}

bool LaserSlam::isKeyframe(const SlamScan& scan, const Pose2& pose) const
{
  if (scan.points.size() < params_.min_points) return false;
  if (keyframes_.empty()) return true;
  const Pose2 since = keyframes_.back().local.inverse() * pose;
  return std::hypot(since.x, since.y) >= params_.keyframe_distance ||
         std::fabs(since.theta) >= params_.keyframe_angle;
}

void LaserSlam::addKeyframe(const SlamScan& scan, std::size_t scan_index, bool chain_matched)
{
  SlamKeyframe kf;
  kf.stamp = scan.stamp;
  kf.scan = scan_index;
  kf.local = last_local_;
  kf.points = scan.points;
  kf.joins = scanSurfaces(scan.points, params_.surfaces);
  kf.path = path_;
  if (keyframes_.empty())
    graph_.addNode(kf.local);
  else
  {
    const Pose2 relative = keyframes_.back().local.inverse() * kf.local;
    const std::size_t prev = keyframes_.size() - 1;
    graph_.addNode(graph_.node(prev) * relative);
    PoseGraphEdge e;
    e.from = prev;
    e.to = prev + 1;
    e.measurement = relative;
    e.sigma_xy = chain_matched ? params_.edge_sigma_xy : params_.odometry_sigma_xy;
    e.sigma_theta = chain_matched ? params_.edge_sigma_theta : params_.odometry_sigma_theta;
    if (chain_matched)
    {
      // What the keyframe's match determined: along a direction it left to the odometry, the edge is as
      // loose as an odometry edge, so a closure may move the keyframe there.
      e.translation_weights = chainEdgeTranslationWeights(last_match_weights_, keyframes_.back().local.theta,
                                                          params_.edge_sigma_xy, params_.odometry_sigma_xy);
    }
    graph_.addEdge(e);
  }
  keyframes_.push_back(std::move(kf));
  chain_matched_ = true;
  ++counters_.keyframes;
  keyframe_added_ = true;
  rebuildLocalMap();
  if (params_.loop_candidates > 0 && (keyframes_.size() - 1) % params_.loop_every == 0)
  {
    const auto start = std::chrono::steady_clock::now();
    closeLoops();
    counters_.total_loop_ms += linemap::millisecondsSince(start);
  }
}

void LaserSlam::rebuildLocalMap()
{
  std::vector<Vec2> points;
  std::vector<linemap::Segment2> joins;
  const std::size_t n = std::min(params_.local_map_keyframes, keyframes_.size());
  // Only what the next scans can reach: they are matched near the newest keyframe (a keyframe every few
  // decimetres, an odometry step at most max_odometry_step) and see max_range. Where the front end lost
  // track, the last keyframes lie far apart and their union would make the field unbounded.
  const Vec2 centre = keyframes_.back().local.translation();
  const double reach = params_.max_range + params_.max_odometry_step + 1.0;
  const auto near = [&](const Vec2& q) { return (q - centre).cwiseAbs().maxCoeff() <= reach; };
  for (std::size_t i = keyframes_.size() - n; i < keyframes_.size(); ++i)
  {
    for (const auto& p : keyframes_[i].points)
      if (const Vec2 q = keyframes_[i].local.apply(p); near(q)) points.push_back(q);
    for (const auto& s : keyframes_[i].joins)
      if (const linemap::Segment2 t = s.transformed(keyframes_[i].local); near(t.start) || near(t.end))
        joins.push_back(t);
  }
  local_map_ = LikelihoodGrid(points, joins, params_.resolution, params_.sigma, 0.5);
}

std::optional<std::pair<MatchResult, double>> LaserSlam::matchLoop(std::size_t candidate, std::size_t current,
                                                                   const Pose2& guess, double radius,
                                                                   double angle)
{
  // Submap: the candidate and its neighbours in the candidate's frame, by their optimised poses.
  const Pose2 inv = graph_.node(candidate).inverse();
  const std::size_t s = params_.loop_submap_keyframes;
  const std::size_t lo = candidate >= s ? candidate - s : 0;
  // Only submap points within reach of the scan somewhere in the search window (its points lie within
  // max_range of its pose, a field value depends on points a few sigma away): farther ones cannot change a
  // score and would only widen the fields — without bound where the keyframes of a submap lie far apart.
  const double reach = params_.max_range + radius + 1.0;
  std::vector<Vec2> points;
  for (std::size_t i = lo; i <= candidate + s && i < keyframes_.size(); ++i)
  {
    if (keyframes_[current].path - keyframes_[i].path < 0.5 * params_.loop_min_path)
      continue;  // too recent: part of the chain being checked
    const Pose2 rel = inv * graph_.node(i);
    for (const auto& p : keyframes_[i].points)
    {
      const Vec2 q = rel.apply(p);
      if (std::fabs(q.x() - guess.x) <= reach && std::fabs(q.y() - guess.y) <= reach) points.push_back(q);
    }
  }
  if (points.size() < params_.min_points) return std::nullopt;
  const auto& scan = keyframes_[current].points;
  const LikelihoodGrid coarse(points, params_.loop_resolution, params_.loop_resolution, 0.5);
  const SearchWindow wide{radius, angle, params_.loop_resolution, params_.loop_angular_step, 0.0, 0.0};
  TranslationScores spread;
  const auto candidates = correlativeSearch(coarse, scan, guess, wide, 3, &spread);
  if (candidates.empty()) return std::nullopt;
  const LikelihoodGrid fine(points, params_.resolution, params_.sigma, 0.5);
  SearchWindow narrow{params_.loop_resolution,
                      params_.loop_angular_step,
                      params_.resolution,
                      params_.loop_angular_step / 3.0,
                      0.0,
                      0.0};
  std::optional<MatchResult> best;
  for (const auto& c : candidates)
  {
    const auto local = correlativeSearch(fine, scan, c.pose, narrow, 1);
    if (local.empty()) continue;
    const MatchResult refined =
        refineMatch(fine, scan, local.front().pose, local.front().pose, params_.refinement);
    if (!best || refined.score > best->score) best = refined;
  }
  if (!best) return std::nullopt;
  double ambiguity = 0.0;
  if (params_.loop_ambiguity_distance > 0.0 && candidates.front().score > 0.0)
    ambiguity = spread.bestAwayFrom(candidates.front().pose.translation(), params_.loop_ambiguity_distance) /
                candidates.front().score;
  return std::make_pair(*best, ambiguity);
}

void LaserSlam::closeLoops()
{
  const std::size_t k = keyframes_.size() - 1;
  const double since = keyframes_[k].path - path_at_closure_;
  const double radius =
      std::min(params_.loop_max_radius, params_.loop_radius + params_.loop_radius_growth * since);
  const double angle =
      std::min(params_.loop_max_angle, params_.loop_angle + params_.loop_angle_growth * since);
  for (std::size_t j : loopCandidates(k, radius)) tryLoop(j, k, radius, angle);
}

std::vector<std::size_t> LaserSlam::loopCandidates(std::size_t k, double radius) const
{
  const Pose2 here = graph_.node(k);
  std::vector<std::pair<double, std::size_t>> near;
  for (std::size_t j = 0; j < k; ++j)
  {
    if (keyframes_[k].path - keyframes_[j].path < params_.loop_min_path)
      break;  // paths only grow: the rest are recent too
    const Pose2 there = graph_.node(j);
    const double d = std::hypot(there.x - here.x, there.y - here.y);
    if (d <= radius) near.push_back({d, j});
  }
  std::sort(near.begin(), near.end());
  std::vector<std::size_t> chosen;
  for (const auto& [d, j] : near)
  {
    if (chosen.size() >= params_.loop_candidates) break;
    bool overlaps = false;
    for (std::size_t c : chosen) overlaps |= (j > c ? j - c : c - j) <= params_.loop_submap_keyframes;
    if (!overlaps) chosen.push_back(j);
  }
  return chosen;
}

void LaserSlam::tryLoop(std::size_t j, std::size_t k, double radius, double angle)
{
  ++counters_.loop_attempts;
  const Pose2 guess = graph_.node(j).inverse() * graph_.node(k);
  const auto found = matchLoop(j, k, guess, radius, angle);
  if (!found)
  {
    ++counters_.loops_rejected_score;
    return;
  }
  const std::size_t attempt = closures_.size();
  closures_.push_back({j, k, ClosureOutcome::kRejectedScore, found->first.score});
  if (found->first.score < params_.loop_min_score)
  {
    ++counters_.loops_rejected_score;
    return;
  }
  if (params_.loop_ambiguity_distance > 0.0 && found->second >= params_.loop_ambiguity_ratio)
  {
    ++counters_.loops_ambiguous;
    closures_[attempt].outcome = ClosureOutcome::kAmbiguous;
    return;
  }
  const MatchResult& match = found->first;
  const TranslationShape shape = matchShape(match);
  const PoseGraphEdge e = loopEdge(j, k, match.pose, shape, params_);
  if (!consistentWithGraph(e))
  {
    ++counters_.loops_inconsistent;
    closures_[attempt].outcome = ClosureOutcome::kInconsistent;
    return;
  }
  const std::size_t edge = graph_.addEdge(e);
  const Pose2 disagreement = graph_.edgeError(edge);
  // Translations in the closure's own metric: along a direction its match did not fix, the
  // estimate's drift is no disagreement.
  const double size = graph_.weightedTranslationError(edge);
  if (size <= params_.loop_consistent_xy && std::fabs(disagreement.theta) <= params_.loop_consistent_theta)
  {
    // The estimate already agrees with it: optimising would barely move anything. It takes part in
    // the next optimisation.
    ++counters_.loops_accepted;
    ++counters_.loops_consistent;
    closures_[attempt].outcome = ClosureOutcome::kAccepted;
    counters_.loops_degenerate += shape.degenerate ? 1 : 0;
    path_at_closure_ = keyframes_[k].path;
    return;
  }
  std::vector<std::size_t> added{edge};
  // A corroborated pending closure goes in (or out) with this one.
  const std::size_t pending_attempt = pending_ ? pending_->attempt : closures_.size();
  if (!admitDisagreeing(j, k, e, match.pose, size, disagreement.theta, added))
  {
    closures_[attempt].outcome = ClosureOutcome::kPending;
    return;
  }
  const bool kept = optimizeKeeping(added);
  const ClosureOutcome outcome = kept ? ClosureOutcome::kAccepted : ClosureOutcome::kRejectedGraph;
  closures_[attempt].outcome = outcome;
  if (added.size() > 1 && pending_attempt < closures_.size()) closures_[pending_attempt].outcome = outcome;
  if (!kept) return;
  counters_.loops_accepted += added.size();
  counters_.loops_degenerate += shape.degenerate ? 1 : 0;
  graph_optimized_ = true;
  path_at_closure_ = keyframes_[k].path;
}

bool LaserSlam::consistentWithGraph(const PoseGraphEdge& e) const
{
  if (!std::isfinite(consistency_gate_)) return true;
  const auto path = relativeCovariance(graph_, e.from, e.to);
  if (!path) return true;  // nothing relates the two: nothing to disagree with
  const Pose2 relative = graph_.node(e.from).inverse() * graph_.node(e.to);
  const Eigen::Vector3d r(relative.x - e.measurement.x, relative.y - e.measurement.y,
                          linemap::normalizeAngle(relative.theta - e.measurement.theta));
  const Eigen::Matrix3d combined = *path + edgeCovariance(e);
  return r.dot(combined.ldlt().solve(r)) <= consistency_gate_;
}

bool LaserSlam::admitDisagreeing(std::size_t j, std::size_t k, const PoseGraphEdge& e, const Pose2& relative,
                                 double size, double theta_error, std::vector<std::size_t>& added)
{
  // A large disagreement is the drift a closure is for, or a false match: it must be corroborated by a
  // second closure, from another keyframe, implying the same correction of the current pose (a false
  // match rarely repeats itself consistently).
  const std::size_t edge = added.front();
  const Pose2 implied = graph_.node(j) * relative;  // where this closure puts keyframe k
  if (size > params_.loop_corroborate_xy || std::fabs(theta_error) > params_.loop_corroborate_theta)
  {
    if (!corroborates(k, implied))
    {
      graph_.removeEdge(edge);
      pending_ = PendingClosure{e, implied, k, closures_.size() - 1};
      ++counters_.loops_pending;
      return false;
    }
    // Both go in, under a loss wide enough for the correction they agree on.
    const double scale = std::max(params_.loop_loss_scale, 2.0 * size / params_.loop_sigma_xy);
    graph_.setLossScale(edge, scale);
    PoseGraphEdge first = pending_->edge;
    first.loss_scale = scale;
    added.push_back(graph_.addEdge(first));
    pending_.reset();
  }
  else if (params_.loop_scale_by_disagreement > 0.0)
    graph_.setLossScale(edge, std::max(params_.loop_loss_scale,
                                       params_.loop_scale_by_disagreement * size / params_.loop_sigma_xy));
  return true;
}

bool LaserSlam::corroborates(std::size_t k, const Pose2& implied) const
{
  if (!pending_ || k - pending_->to > params_.loop_pending_keyframes || pending_->to == k) return false;
  // The pending closure's correction, applied to keyframe k: where it puts k.
  const Pose2 pending_k = pending_->implied * (graph_.node(pending_->to).inverse() * graph_.node(k));
  const Pose2 diff = pending_k.inverse() * implied;
  return std::hypot(diff.x, diff.y) <= params_.loop_agreement_xy &&
         std::fabs(diff.theta) <= params_.loop_agreement_theta;
}

bool LaserSlam::optimizeKeeping(std::vector<std::size_t> added)
{
  std::vector<Pose2> before(graph_.nodeCount());
  for (std::size_t i = 0; i < before.size(); ++i) before[i] = graph_.node(i);
  const OptimizationStats stats = graph_.optimize();
  ++counters_.optimizations;
  counters_.last_optimization_ms = stats.milliseconds;
  counters_.total_optimization_ms += stats.milliseconds;
  bool fits = true;
  for (std::size_t a : added)
  {
    const Pose2 error = graph_.edgeError(a);
    fits &= graph_.weightedTranslationError(a) <= params_.loop_max_error_xy &&
            std::fabs(error.theta) <= params_.loop_max_error_theta;
  }
  if (fits) return true;
  // The rest of the graph disagrees: a false closure the robust loss only damped. Undo it.
  std::sort(added.rbegin(), added.rend());
  for (std::size_t a : added) graph_.removeEdge(a);
  for (std::size_t i = 0; i < before.size(); ++i) graph_.setNode(i, before[i]);
  counters_.loops_rejected_graph += added.size();
  return false;
}

TranslationShape LaserSlam::matchShape(const MatchResult& match) const
{
  if (params_.isotropic_ratio <= 0.0) return {};
  return translationShape(match.curvature, params_.isotropic_ratio, params_.min_weight);
}

std::vector<std::pair<double, Pose2>> LaserSlam::trajectory() const
{
  std::vector<std::pair<double, Pose2>> out;
  out.reserve(keyframes_.size());
  for (std::size_t i = 0; i < keyframes_.size(); ++i) out.emplace_back(keyframes_[i].stamp, graph_.node(i));
  return out;
}

std::vector<std::pair<double, Pose2>> LaserSlam::scanPoses() const
{
  std::vector<std::pair<double, Pose2>> out;
  out.reserve(scans_.size());
  for (const auto& s : scans_)
  {
    if (s.keyframe < keyframes_.size())
      out.emplace_back(s.stamp, graph_.node(s.keyframe) * s.relative);
    else
      out.emplace_back(s.stamp, s.relative);
  }
  return out;
}

Pose2 LaserSlam::currentPose() const
{
  if (keyframes_.empty()) return last_local_;
  const std::size_t k = keyframes_.size() - 1;
  return graph_.node(k) * (keyframes_[k].local.inverse() * last_local_);
}

std::vector<std::pair<std::string, std::string>> LaserSlam::diagnostics() const
{
  const auto& c = counters_;
  auto n = [](std::size_t v) { return std::to_string(v); };
  std::ostringstream opt;
  opt.precision(3);
  opt << c.last_optimization_ms;
  std::ostringstream total;
  total.precision(4);
  total << c.total_optimization_ms;
  return {{"scans", n(c.scans)},
          {"matched scans", n(c.matched)},
          {"scans posed by odometry (barely moved)", n(c.filtered)},
          {"scans posed by prediction (not matched)", n(c.predicted)},
          {"scans with too few points", n(c.few_points)},
          {"poor matches", n(c.poor_matches)},
          {"scans without odometry", n(c.without_odometry)},
          {"odometry jumps", n(c.odometry_jumps)},
          {"wide searches (match off the odometry)", n(c.wide_searches)},
          {"scans out of order (ignored)", n(c.rejected)},
          {"time jumps back", n(c.time_jumps)},
          {"keyframes", n(c.keyframes)},
          {"loop closure attempts", n(c.loop_attempts)},
          {"loop closures accepted", n(c.loops_accepted)},
          {"loop closures consistent (not optimised)", n(c.loops_consistent)},
          {"loop closures waiting for corroboration", n(c.loops_pending)},
          {"loop closures rejected (ambiguous)", n(c.loops_ambiguous)},
          {"loop closures rejected (inconsistent with the graph)", n(c.loops_inconsistent)},
          {"loop closures accepted with a direction their match left open", n(c.loops_degenerate)},
          {"matches leaving a direction to the odometry", n(c.degenerate_matches)},
          {"loop closures rejected (score)", n(c.loops_rejected_score)},
          {"loop closures rejected (graph)", n(c.loops_rejected_graph)},
          {"optimizations", n(c.optimizations)},
          {"last optimization [ms]", opt.str()},
          {"total optimization [ms]", total.str()},
          {"scans dropped (no tf)", n(c.dropped)},
          {"scans stamped zero", n(c.zero_stamps)},
          {"new trajectories (time jumped back)", n(c.new_trajectories)},
          {"trajectories published", n(c.paths)}};
}

}  // namespace line_map_merging
