#include "line_map_merging/slam/closure_gate.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>

#include "line_map_merging/slam/closure_consensus.hpp"
#include "line_map_merging/slam/relative_uncertainty.hpp"

namespace line_map_merging
{
using linemap::Pose2;

ClosureGate::ClosureGate(const LaserSlamParams& params)
    : params_(params),
      consistency_gate_(
          params.loop_consistency_probability > 0.0
              ? boost::math::quantile(boost::math::chi_squared(3.0), params.loop_consistency_probability)
              : std::numeric_limits<double>::infinity())
{
}

bool ClosureGate::passesScreening(const LoopMatch& match, std::size_t attempt, SlamCounters& counters)
{
  // Ambiguity first: an ambiguous match comes unrefined (ConstraintBuilder), its score from the coarse field.
  if (params_.ambiguous(match.ambiguity))
  {
    ++counters.loops_ambiguous;
    attempts_[attempt].outcome = ClosureOutcome::kAmbiguous;
    return false;
  }
  if (match.match->score < attempts_[attempt].min_score)
  {
    ++counters.loops_rejected_score;
    return false;
  }
  return true;
}

ClosureVerdict ClosureGate::consider(const LoopMatch& match, PoseGraph& graph, SlamCounters& counters)
{
  if (!match.match)
  {
    ++counters.loops_rejected_score;
    return {};
  }
  const std::size_t j = match.from, k = match.to;
  const MatchResult& found = *match.match;
  const std::size_t attempt = attempts_.size();
  attempts_.push_back(
      {j, k, ClosureOutcome::kRejectedScore, found.score, params_.loopMinScore(front_end_score_)});
  if (!passesScreening(match, attempt, counters)) return {};
  const PoseGraphEdge& e = match.edge;
  // Judged as matched: the edge keeps the estimate where the match is weak, which would hide a slide there.
  PoseGraphEdge as_matched = e;
  as_matched.measurement = found.pose;
  if (!consistentWithGraph(graph, as_matched))
  {
    ++counters.loops_inconsistent;
    ++counters.inconsistent_in_a_row;
    counters.most_inconsistent_in_a_row =
        std::max(counters.most_inconsistent_in_a_row, counters.inconsistent_in_a_row);
    attempts_[attempt].outcome = ClosureOutcome::kInconsistent;
    return outvoteChain(match, attempt, graph, counters);
  }
  const std::size_t edge = graph.addEdge(e);
  const Pose2 disagreement = graph.edgeError(edge);
  // Translations in the closure's own metric: along a direction its match did not fix, the
  // estimate's drift is no disagreement.
  const double size = graph.weightedTranslationError(edge);
  if (size <= params_.loop_consistent_xy && std::fabs(disagreement.theta) <= params_.loop_consistent_theta)
  {
    // The estimate already agrees with it: optimising would barely move anything. It takes part in
    // the next optimisation.
    ++counters.loops_accepted;
    ++counters.loops_consistent;
    counters.inconsistent_in_a_row = 0;
    attempts_[attempt].outcome = ClosureOutcome::kAccepted;
    counters.loops_degenerate += match.shape.degenerate ? 1 : 0;
    return {true, false};
  }
  std::vector<std::size_t> added{edge};
  // A corroborated pending closure goes in (or out) with this one.
  const std::size_t pending_attempt = pending_ ? pending_->attempt : attempts_.size();
  if (!admitDisagreeing(graph, j, k, e, found.pose, size, disagreement.theta, added, counters))
  {
    attempts_[attempt].outcome = ClosureOutcome::kPending;
    return {};
  }
  const bool kept = optimizeKeeping(graph, added, counters);
  const ClosureOutcome outcome = kept ? ClosureOutcome::kAccepted : ClosureOutcome::kRejectedGraph;
  attempts_[attempt].outcome = outcome;
  if (added.size() > 1 && pending_attempt < attempts_.size()) attempts_[pending_attempt].outcome = outcome;
  if (!kept) return {};
  counters.inconsistent_in_a_row = 0;
  counters.loops_accepted += added.size();
  counters.loops_degenerate += match.shape.degenerate ? 1 : 0;
  return {true, true};
}

ClosureVerdict ClosureGate::outvoteChain(const LoopMatch& match, std::size_t attempt, PoseGraph& graph,
                                         SlamCounters& counters)
{
  if (params_.loop_consensus == 0) return {};
  refused_.push_back({match.edge, attempt, match.shape.degenerate});
  if (refused_.size() > params_.loop_consensus_waiting)
    refused_.erase(
        refused_.begin(),
        refused_.begin() + static_cast<std::ptrdiff_t>(refused_.size() - params_.loop_consensus_waiting));
  std::vector<PoseGraphEdge> edges;
  for (const auto& r : refused_) edges.push_back(r.edge);
  const std::vector<std::size_t> agreeing =
      consistentGroup(graph, edges, edges.size() - 1, consistency_gate_);
  const std::vector<std::size_t> group = independentVotes(edges, agreeing);
  if (distinctKeyframes(edges, group) < params_.loop_consensus) return {};
  // Each under a loss as wide as its own disagreement with the estimate, as an unambiguous closure goes in:
  // the correction they agree on is the drift they are for.
  std::vector<std::size_t> added;
  for (std::size_t g : group)
  {
    const std::size_t edge = graph.addEdge(edges[g]);
    graph.setLossScale(edge, disagreementScale(graph.weightedTranslationError(edge)));
    added.push_back(edge);
  }
  const bool kept = optimizeKeeping(graph, added, counters);
  for (std::size_t g : group)
  {
    attempts_[refused_[g].attempt].outcome =
        kept ? ClosureOutcome::kAccepted : ClosureOutcome::kRejectedGraph;
    if (kept) counters.loops_degenerate += refused_[g].degenerate ? 1 : 0;
  }
  // They leave the waiting list either way: in the graph, or refused by it.
  std::vector<bool> in_group(refused_.size(), false);
  for (std::size_t g : group) in_group[g] = true;
  std::vector<RefusedClosure> waiting;
  for (std::size_t i = 0; i < refused_.size(); ++i)
    if (!in_group[i]) waiting.push_back(refused_[i]);
  refused_ = std::move(waiting);
  counters.loops_inconsistent -= group.size();
  if (!kept)
  {
    // optimizeKeeping counted them as refused by the graph.
    return {};
  }
  counters.loops_accepted += group.size();
  counters.loops_by_consensus += group.size();
  counters.inconsistent_in_a_row = 0;
  return {true, true};
}

std::vector<std::size_t> ClosureGate::independentVotes(const std::vector<PoseGraphEdge>& edges,
                                                       const std::vector<std::size_t>& agreeing) const
{
  // Closures against overlapping submaps share their errors (a match slid along one corridor agrees with its
  // neighbours' slide), so only one per two submap spans of older keyframes counts.
  std::vector<std::size_t> votes;
  for (std::size_t g : agreeing)
    if (std::all_of(votes.begin(), votes.end(),
                    [&](std::size_t h)
                    {
                      const std::size_t a = edges[g].from, b = edges[h].from;
                      return (a > b ? a - b : b - a) > 2 * params_.submapKeyframes();
                    }))
      votes.push_back(g);
  return votes;
}

double ClosureGate::disagreementScale(double size) const
{
  if (!(params_.loop_scale_by_disagreement > 0.0)) return params_.loop_loss_scale;
  return std::max(params_.loop_loss_scale, params_.loop_scale_by_disagreement * size / params_.loop_sigma_xy);
}

bool ClosureGate::consistentWithGraph(const PoseGraph& graph, const PoseGraphEdge& e) const
{
  if (!std::isfinite(consistency_gate_)) return true;
  const auto path = relativeCovariance(graph, e.from, e.to);
  if (!path) return true;  // nothing relates the two: nothing to disagree with
  const Pose2 relative = graph.node(e.from).inverse() * graph.node(e.to);
  const Eigen::Vector3d r(relative.x - e.measurement.x, relative.y - e.measurement.y,
                          linemap::normalizeAngle(relative.theta - e.measurement.theta));
  const Eigen::Matrix3d combined = *path + edgeCovariance(e);
  return r.dot(combined.ldlt().solve(r)) <= consistency_gate_;
}

bool ClosureGate::admitDisagreeing(PoseGraph& graph, std::size_t j, std::size_t k, const PoseGraphEdge& e,
                                   const Pose2& relative, double size, double theta_error,
                                   std::vector<std::size_t>& added, SlamCounters& counters)
{
  // A large disagreement is the drift a closure is for, or a false match: it must be corroborated by a
  // second closure, from another keyframe, implying the same correction of the current pose (a false
  // match rarely repeats itself consistently).
  const std::size_t edge = added.front();
  const Pose2 implied = graph.node(j) * relative;  // where this closure puts keyframe k
  if (size > params_.loop_corroborate_xy || std::fabs(theta_error) > params_.loop_corroborate_theta)
  {
    if (!corroborates(graph, k, implied))
    {
      graph.removeEdge(edge);
      pending_ = PendingClosure{e, implied, k, attempts_.size() - 1};
      ++counters.loops_pending;
      return false;
    }
    // Both go in, under a loss wide enough for the correction they agree on.
    const double scale = std::max(params_.loop_loss_scale, 2.0 * size / params_.loop_sigma_xy);
    graph.setLossScale(edge, scale);
    PoseGraphEdge first = pending_->edge;
    first.loss_scale = scale;
    added.push_back(graph.addEdge(first));
    pending_.reset();
  }
  else if (params_.loop_scale_by_disagreement > 0.0)
    graph.setLossScale(edge, disagreementScale(size));
  return true;
}

bool ClosureGate::corroborates(const PoseGraph& graph, std::size_t k, const Pose2& implied) const
{
  if (!pending_ || k - pending_->to > params_.loop_pending_keyframes || pending_->to == k) return false;
  // The pending closure's correction, applied to keyframe k: where it puts k.
  const Pose2 pending_k = pending_->implied * (graph.node(pending_->to).inverse() * graph.node(k));
  const Pose2 diff = pending_k.inverse() * implied;
  return std::hypot(diff.x, diff.y) <= params_.loop_agreement_xy &&
         std::fabs(diff.theta) <= params_.loop_agreement_theta;
}

bool ClosureGate::optimizeKeeping(PoseGraph& graph, std::vector<std::size_t> added,
                                  SlamCounters& counters) const
{
  std::vector<Pose2> before(graph.nodeCount());
  for (std::size_t i = 0; i < before.size(); ++i) before[i] = graph.node(i);
  const OptimizationStats stats = graph.optimize();
  ++counters.optimizations;
  counters.last_optimization_ms = stats.milliseconds;
  counters.total_optimization_ms += stats.milliseconds;
  bool fits = true;
  for (std::size_t a : added)
  {
    const Pose2 error = graph.edgeError(a);
    fits &= graph.weightedTranslationError(a) <= params_.loop_max_error_xy &&
            std::fabs(error.theta) <= params_.loop_max_error_theta;
  }
  if (fits) return true;
  // The rest of the graph disagrees: a false closure the robust loss only damped. Undo it.
  std::sort(added.rbegin(), added.rend());
  for (std::size_t a : added) graph.removeEdge(a);
  for (std::size_t i = 0; i < before.size(); ++i) graph.setNode(i, before[i]);
  counters.loops_rejected_graph += added.size();
  return false;
}

}  // namespace line_map_merging
