#include "line_map_merging/slam/closure_consensus.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <utility>

#include "line_map_merging/slam/relative_uncertainty.hpp"

namespace line_map_merging
{
using linemap::Pose2;

namespace
{
Eigen::Matrix2d rotation(double theta)
{
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix2d r;
  r << c, -s, s, c;
  return r;
}

/// The graph's estimate of `to` relative to `from`, with its covariance.
std::optional<UncertainPose> graphRelative(const PoseGraph& graph, std::size_t from, std::size_t to)
{
  const auto covariance = relativeCovariance(graph, from, to);
  if (!covariance) return std::nullopt;
  return UncertainPose{graph.node(from).inverse() * graph.node(to), *covariance};
}
}  // namespace

UncertainPose compose(const UncertainPose& a, const UncertainPose& b)
{
  // t = t_a + R_a t_b, theta = theta_a + theta_b; a's heading swings b's translation.
  const Eigen::Vector2d swung = rotation(a.pose.theta) * Eigen::Vector2d(b.pose.x, b.pose.y);
  Eigen::Matrix3d ja = Eigen::Matrix3d::Identity();
  ja(0, 2) = -swung.y();
  ja(1, 2) = swung.x();
  Eigen::Matrix3d jb = Eigen::Matrix3d::Identity();
  jb.topLeftCorner<2, 2>() = rotation(a.pose.theta);
  return {a.pose * b.pose, ja * a.covariance * ja.transpose() + jb * b.covariance * jb.transpose()};
}

UncertainPose inverse(const UncertainPose& a)
{
  // t' = -R^T t, theta' = -theta.
  const double c = std::cos(a.pose.theta), s = std::sin(a.pose.theta);
  Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
  j.topLeftCorner<2, 2>() = -rotation(a.pose.theta).transpose();
  j(0, 2) = s * a.pose.x - c * a.pose.y;
  j(1, 2) = c * a.pose.x + s * a.pose.y;
  j(2, 2) = -1.0;
  return {a.pose.inverse(), j * a.covariance * j.transpose()};
}

PairwiseCheck checkPair(const PoseGraph& graph, const PoseGraphEdge& a, const PoseGraphEdge& b)
{
  const double infinite = std::numeric_limits<double>::infinity();
  const auto newer = graphRelative(graph, a.to, b.to);
  const auto older = graphRelative(graph, b.from, a.from);
  if (!newer || !older) return {infinite, 0.0};
  const UncertainPose closure_a{a.measurement, edgeCovariance(a)};
  const UncertainPose closure_b{b.measurement, edgeCovariance(b)};
  const UncertainPose cycle = compose(compose(compose(closure_a, *newer), inverse(closure_b)), *older);
  const auto solver = cycle.covariance.ldlt();
  const auto chi2 = [&](const Pose2& p)
  {
    const Eigen::Vector3d r(p.x, p.y, linemap::normalizeAngle(p.theta));
    return r.dot(solver.solve(r));
  };
  // A closure's correction of the graph: the cycle with the other closure replaced by the graph's own
  // estimate of its relative pose (in the same frame, so in the same metric).
  const auto as_estimated = [&](const PoseGraphEdge& e)
  { return graph.node(e.from).inverse() * graph.node(e.to); };
  const Pose2 correction_a = a.measurement * newer->pose * as_estimated(b).inverse() * older->pose;
  const Pose2 correction_b = as_estimated(a) * newer->pose * b.measurement.inverse() * older->pose;
  return {chi2(cycle.pose), std::max(chi2(correction_a), chi2(correction_b))};
}

double pairwiseDisagreement(const PoseGraph& graph, const PoseGraphEdge& a, const PoseGraphEdge& b)
{
  return checkPair(graph, a, b).disagreement;
}

std::vector<std::size_t> consistentGroup(const PoseGraph& graph, const std::vector<PoseGraphEdge>& closures,
                                         std::size_t newest, double gate)
{
  const std::size_t n = closures.size();
  // Pairwise disagreements, computed once each; a pair whose cycle could not have told the larger of their
  // corrections from none does not agree (infinite): over a long, loose stretch of graph anything does.
  std::vector<std::vector<double>> d(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
    {
      const PairwiseCheck check = checkPair(graph, closures[i], closures[j]);
      d[i][j] = d[j][i] =
          check.larger_correction > gate ? check.disagreement : std::numeric_limits<double>::infinity();
    }
  std::vector<std::pair<double, std::size_t>> order;
  for (std::size_t i = 0; i < n; ++i)
    if (i != newest && d[newest][i] <= gate) order.push_back({d[newest][i], i});
  std::sort(order.begin(), order.end());
  std::vector<std::size_t> group{newest};
  for (const auto& [ignored, i] : order)
    if (std::all_of(group.begin(), group.end(), [&](std::size_t g) { return d[g][i] <= gate; }))
      group.push_back(i);
  return group;
}

std::size_t distinctKeyframes(const std::vector<PoseGraphEdge>& closures,
                              const std::vector<std::size_t>& group)
{
  std::set<std::size_t> keyframes;
  for (std::size_t i : group) keyframes.insert(closures[i].to);
  return keyframes.size();
}

}  // namespace line_map_merging
