#include "line_map_merging/slam/constraint_builder.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/submap_view.hpp"

namespace line_map_merging
{
namespace
{
using linemap::Pose2;
using linemap::Vec2;

/// A loop match on the in-view points alone may rest its heading on points near the pose (a corridor's
/// walls beside it, the far stretch it faces never seen by the submap): the edge is then as sure of the
/// heading as the match's lever arm allows, graph/loop_sigma_xy over it, never surer than loop_sigma_theta.
double loopSigmaTheta(const MatchResult& match, const LaserSlamParams& params)
{
  if (!params.loop_in_view_only || params.isotropic_ratio <= 0.0) return params.loop_sigma_theta;
  const double lever = matchLeverArm(match.curvature);
  if (!(lever > 0.0)) return params.loop_sigma_theta;
  return std::max(params.loop_sigma_theta, params.loop_sigma_xy / lever);
}

/// The closure edge j -> k measured by a loop match, its information shaped by the match's.
PoseGraphEdge loopEdge(std::size_t j, std::size_t k, const Pose2& measurement, const MatchResult& match,
                       const TranslationShape& shape, const LaserSlamParams& params)
{
  PoseGraphEdge e;
  e.from = j;
  e.to = k;
  e.measurement = measurement;
  e.sigma_xy = params.loop_sigma_xy;
  e.sigma_theta = loopSigmaTheta(match, params);
  e.translation_weights = shape.weights;
  e.loop = true;
  return e;
}
}  // namespace

LoopSearch ConstraintBuilder::search(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                     std::size_t k) const
{
  LoopSearch s;
  const double since = keyframes[k].path - path_at_closure_;
  s.radius = std::min(params_.loop_max_radius, params_.loop_radius + params_.loop_radius_growth * since);
  s.angle = std::min(params_.loop_max_angle, params_.loop_angle + params_.loop_angle_growth * since);
  chooseCandidates(keyframes, graph, k, openSuspects(graph), s);
  return s;
}

std::vector<ConstraintBuilder::SuspectEdge> ConstraintBuilder::openSuspects(const PoseGraph& graph) const
{
  std::vector<SuspectEdge> open;
  for (const SuspectEdge& s : suspects_)
  {
    const bool spanned =
        std::any_of(graph.edges().begin(), graph.edges().end(),
                    [&](const PoseGraphEdge& e)
                    { return e.loop && std::min(e.from, e.to) < s.to && std::max(e.from, e.to) >= s.to; });
    if (!spanned && s.to < graph.nodeCount()) open.push_back(s);
  }
  return open;
}

std::pair<double, double> ConstraintBuilder::slipAllowance(const PoseGraph& graph,
                                                           const std::vector<SuspectEdge>& open,
                                                           std::size_t j, std::size_t k)
{
  // A slip turning the chain by `turn` at keyframe s moves keyframe k about s by turn times their distance,
  // and shifts it by `shift`: a slip's size is what its match disagreed with the odometry by.
  double shift = 0.0, turn = 0.0;
  const linemap::Vec2 here = graph.node(k).translation();
  for (const SuspectEdge& s : open)
  {
    if (s.to <= j || s.to > k) continue;
    shift += s.shift + s.turn * (here - graph.node(s.to).translation()).norm();
    turn += s.turn;
  }
  return {shift, turn};
}

LoopMatch ConstraintBuilder::match(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                   std::size_t j, std::size_t k, const LoopSearch& search,
                                   SlamCounters& counters) const
{
  ++counters.loop_attempts;
  LoopMatch m;
  m.from = j;
  m.to = k;
  const Pose2 guess = graph.node(j).inverse() * graph.node(k);
  const auto at = std::find(search.candidates.begin(), search.candidates.end(), j);
  const std::size_t c = static_cast<std::size_t>(at - search.candidates.begin());
  const bool own = at != search.candidates.end() && c < search.radii.size();
  // Slid matches count only across a suspect chain edge: elsewhere a corridor's chain holds the estimate
  // along its axis no better than the slide, and laser only (no suspects) it may lie metres off there.
  const bool slide =
      params_.loop_ridge_closures && slipAllowance(graph, openSuspects(graph), j, k).first > 0.0;
  const auto found = matchLoop(keyframes, graph, j, k, guess, own ? search.radii[c] : search.radius,
                               own ? search.angles[c] : search.angle, slide);
  if (!found) return m;
  m.match = found->match;
  m.ambiguity = found->ambiguity;
  m.shape = found->shape;
  // A best on the border even of the window searched again around it (matchLoop) is as ambiguous as a match
  // can be along a direction the match determines: where the score peaks is not known (in a corridor of
  // doors, a pose slid onto the next door scores on). Along a direction it leaves open the edge keeps the
  // estimate (heldToEstimate): the rest of it counts. The window grows with the path, so a true closure
  // beyond it is found again from further on.
  if (params_.loop_ambiguity_distance > 0.0 && found->onDeterminedBorder()) m.ambiguity = 1.0;
  m.edge = loopEdge(j, k, heldToEstimate(found->match.pose, guess, m.shape), found->match, m.shape, params_);
  return m;
}

std::vector<std::size_t> ConstraintBuilder::submapOf(const std::vector<SlamKeyframe>& keyframes,
                                                     std::size_t candidate, std::size_t current) const
{
  const std::size_t s = params_.submapKeyframes();
  std::vector<std::size_t> members;
  // Not those too recent for `current`: they are part of the chain being checked.
  for (std::size_t i = candidate >= s ? candidate - s : 0; i <= candidate + s && i < keyframes.size(); ++i)
    if (keyframes[current].path - keyframes[i].path >= 0.5 * params_.loop_min_path) members.push_back(i);
  return members;
}

std::vector<Vec2> ConstraintBuilder::submapPoints(const std::vector<SlamKeyframe>& keyframes,
                                                  const PoseGraph& graph, std::size_t candidate,
                                                  std::size_t current, const Pose2& guess,
                                                  double radius) const
{
  const Pose2 inv = graph.node(candidate).inverse();
  // Only submap points within reach of the scan somewhere in the search window (its points lie within
  // max_range of its pose, a field value depends on points a few sigma away): farther ones cannot change a
  // score and would only widen the fields — without bound where the keyframes of a submap lie far apart.
  const double reach = params_.max_range + radius + 1.0;
  std::vector<Vec2> points;
  for (std::size_t i : submapOf(keyframes, candidate, current))
  {
    const Pose2 rel = inv * graph.node(i);
    for (const auto& p : keyframes[i].points)
    {
      const Vec2 q = rel.apply(p);
      if (std::fabs(q.x() - guess.x) <= reach && std::fabs(q.y() - guess.y) <= reach) points.push_back(q);
    }
  }
  return points;
}

std::vector<Vec2> ConstraintBuilder::pointsInSubmapView(const std::vector<SlamKeyframe>& keyframes,
                                                        const PoseGraph& graph, std::size_t candidate,
                                                        std::size_t current, const Pose2& guess,
                                                        double radius) const
{
  const Pose2 inv = graph.node(candidate).inverse();
  std::vector<std::pair<Pose2, ViewCone>> views;
  for (std::size_t i : submapOf(keyframes, candidate, current))
    views.push_back({inv * graph.node(i), viewCone(keyframes[i].points)});
  const auto& own = keyframes[current].points;
  std::vector<Vec2> at_guess;
  at_guess.reserve(own.size());
  for (const auto& p : own) at_guess.push_back(guess.apply(p));
  // Within the search's reach of a cone: the scan may lie anywhere in the window.
  const std::vector<bool> seen = inView(at_guess, views, radius);
  std::vector<Vec2> kept;
  for (std::size_t i = 0; i < own.size(); ++i)
    if (seen[i]) kept.push_back(own[i]);
  return kept;
}

bool ConstraintBuilder::Found::onDeterminedBorder() const
{
  return border.norm() > 0.0 && border.dot(shape.weights * border) >= 0.5;
}

std::optional<ConstraintBuilder::Found> ConstraintBuilder::matchLoop(
    const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph, std::size_t candidate,
    std::size_t current, const Pose2& guess, double radius, double angle, bool slide) const
{
  std::vector<Vec2> points = submapPoints(keyframes, graph, candidate, current, guess, radius);
  if (points.size() < params_.min_points) return std::nullopt;
  const std::vector<Vec2> scan = params_.loop_in_view_only
                                     ? pointsInSubmapView(keyframes, graph, candidate, current, guess, radius)
                                     : keyframes[current].points;
  if (scan.size() < params_.min_points ||
      static_cast<double>(scan.size()) <
          params_.loop_min_in_view * static_cast<double>(keyframes[current].points.size()))
    return std::nullopt;
  LikelihoodGrid coarse(points, params_.loop_resolution, params_.loop_resolution, 0.5);
  const Fields fields{std::move(points), std::move(coarse), std::nullopt};
  const SearchWindow wide{radius, angle, params_.loop_resolution, params_.loop_angular_step, 0.0, 0.0};
  TranslationScores first;
  std::optional<Found> found = searchAround(fields, scan, guess, wide, nullptr, &first, slide);
  // A best on the border is no peak: the score may go on rising beyond the window. Where the match
  // determines the border's direction and no rival came near it, the same window is searched once more,
  // centred on that best: it holds a peak a little beyond the first window (a drift just past its reach),
  // and where look-alikes repeat (a door slid onto the next), rivals, among the poses of both windows. A
  // best on the second window's border match() judges ambiguous. An ambiguous first best stays refused: on
  // a corridor's long ramp of nearly equal scores the second window's best edges its rivals out by chance.
  if (found && params_.loop_ambiguity_distance > 0.0 && !params_.ambiguous(found->ambiguity) &&
      found->onDeterminedBorder())
  {
    const Pose2 centre(found->coarse_best.x(), found->coarse_best.y(), guess.theta);
    if (std::optional<Found> again = searchAround(fields, scan, centre, wide, &first, nullptr, false))
      found = std::move(again);
  }
  return found;
}

std::optional<ConstraintBuilder::Found> ConstraintBuilder::searchAround(
    const Fields& fields, const std::vector<Vec2>& scan, const Pose2& centre, const SearchWindow& wide,
    const TranslationScores* earlier, TranslationScores* spread_out, bool slide) const
{
  TranslationScores spread;
  const auto candidates = correlativeSearch(fields.coarse, scan, centre, wide, 3, &spread);
  if (candidates.empty()) return std::nullopt;
  Found result;
  result.coarse_best = candidates.front().pose.translation();
  result.border = spread.borderDirection(result.coarse_best);
  if (params_.loop_ambiguity_distance > 0.0 && candidates.front().score > 0.0)
  {
    double rival = spread.bestAwayFrom(result.coarse_best, params_.loop_ambiguity_distance);
    if (earlier)
      rival = std::max(rival, earlier->bestAwayFrom(result.coarse_best, params_.loop_ambiguity_distance));
    result.ambiguity = rival / candidates.front().score;
  }
  if (slide && params_.ambiguous(result.ambiguity))
    if (std::optional<Found> slid = alongRidge(fields, scan, centre, candidates.front(), spread))
    {
      if (spread_out) *spread_out = std::move(spread);
      return slid;
    }
  if (spread_out) *spread_out = std::move(spread);
  // The gate refuses an ambiguous match whatever its refined score: the fine field is not worth building.
  if (params_.ambiguous(result.ambiguity))
  {
    result.match = candidates.front();
    result.shape = matchShape(result.match, params_);
    return result;
  }
  std::optional<MatchResult> best;
  for (const auto& c : candidates)
  {
    const std::optional<MatchResult> refined = refinedAround(fields, scan, c.pose, std::nullopt);
    if (refined && (!best || refined->score > best->score)) best = refined;
  }
  if (!best) return std::nullopt;
  result.match = *best;
  result.shape = matchShape(result.match, params_);
  return result;
}

std::optional<MatchResult> ConstraintBuilder::refinedAround(const Fields& fields,
                                                            const std::vector<Vec2>& scan, const Pose2& start,
                                                            const std::optional<Pose2>& prior) const
{
  if (!fields.fine) fields.fine.emplace(fields.points, params_.resolution, params_.sigma, 0.5);
  const SearchWindow narrow{params_.loop_resolution,
                            params_.loop_angular_step,
                            params_.resolution,
                            params_.loop_angular_step / 3.0,
                            0.0,
                            0.0};
  const auto local = correlativeSearch(*fields.fine, scan, start, narrow, 1);
  if (local.empty()) return std::nullopt;
  return refineMatch(*fields.fine, scan, local.front().pose, prior.value_or(local.front().pose),
                     params_.refinement);
}

std::optional<ConstraintBuilder::Found> ConstraintBuilder::alongRidge(const Fields& fields,
                                                                      const std::vector<Vec2>& scan,
                                                                      const Pose2& estimate,
                                                                      const MatchResult& best,
                                                                      const TranslationScores& spread) const
{
  const Vec2 at = best.pose.translation();
  const auto ridge = spread.ridgeThrough(at, (1.0 - params_.loop_ambiguity_margin) * best.score);
  if (!ridge) return std::nullopt;
  const Vec2& along_ridge = ridge->direction;
  Found result;
  result.ambiguity = spread.bestAcross(at, along_ridge, params_.loop_ambiguity_distance) / best.score;
  if (params_.ambiguous(result.ambiguity)) return std::nullopt;
  // Where the slid matches reach past the estimate's place on the line, the match is made there: a pose slid
  // onto a look-alike (the next door) fits its jambs to the wrong ones, and its heading with them.
  const double along = (estimate.translation() - at).dot(along_ridge);
  if (along < ridge->from - spread.step || along > ridge->to + spread.step) return std::nullopt;
  const Vec2 on_ridge = at + along * along_ridge;
  const Pose2 start(on_ridge.x(), on_ridge.y(), best.pose.theta);
  const std::optional<MatchResult> refined = refinedAround(fields, scan, start, start);
  if (!refined) return std::nullopt;
  result.match = *refined;
  result.coarse_best = on_ridge;
  result.border = spread.borderDirection(on_ridge);
  // Nothing is known along the line: the edge keeps the estimate there (heldToEstimate).
  result.shape = matchShape(result.match, params_);
  const Vec2 across(-along_ridge.y(), along_ridge.x());
  result.shape.weights = across.dot(result.shape.weights * across) * across * across.transpose() +
                         params_.min_weight * along_ridge * along_ridge.transpose();
  result.shape.degenerate = true;
  return result;
}

void ConstraintBuilder::chooseCandidates(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                         std::size_t k, const std::vector<SuspectEdge>& open,
                                         LoopSearch& search) const
{
  const Pose2 here = graph.node(k);
  struct Near
  {
    double distance;
    std::size_t index;
    double radius, angle;
    bool operator<(const Near& o) const { return distance < o.distance; }
  };
  std::vector<Near> near;
  for (std::size_t j = 0; j < k; ++j)
  {
    if (keyframes[k].path - keyframes[j].path < params_.loop_min_path)
      break;  // paths only grow: the rest are recent too
    const Pose2 there = graph.node(j);
    const double d = std::hypot(there.x - here.x, there.y - here.y);
    double radius = search.radius, angle = search.angle;
    if (!open.empty())
    {
      const auto [shift, turn] = slipAllowance(graph, open, j, k);
      radius = std::max(radius, std::min(params_.loop_max_radius, search.radius + shift));
      angle = std::max(angle, std::min(params_.loop_max_angle, search.angle + turn));
    }
    if (d <= radius) near.push_back({d, j, radius, angle});
  }
  std::sort(near.begin(), near.end());
  for (const Near& n : near)
  {
    if (search.candidates.size() >= params_.loop_candidates) break;
    bool overlaps = false;
    for (std::size_t c : search.candidates)
      overlaps |= (n.index > c ? n.index - c : c - n.index) <= params_.submapKeyframes();
    if (overlaps) continue;
    search.candidates.push_back(n.index);
    search.radii.push_back(n.radius);
    search.angles.push_back(n.angle);
  }
}

}  // namespace line_map_merging
