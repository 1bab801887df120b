#include "line_map_merging/slam/pose_graph.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "silent_solve.hpp"

namespace line_map_merging
{
namespace
{
template <typename T>
T wrapAngle(const T& a)
{
  const double two_pi = 2.0 * linemap::kPi;
  return a - two_pi * ceres::floor((a + linemap::kPi) / two_pi);
}

// Residual of one edge, whitened: (R_i^T (t_j - t_i) - z_t) / sigma_xy, wrap(th_j - th_i - z_th) / sigma_th.
// The translation is whitened by W^(1/2) / sigma_xy, W the edge's translation_weights.
struct EdgeCost
{
  explicit EdgeCost(const PoseGraphEdge& e) : z_(e.measurement), ith_(1.0 / e.sigma_theta)
  {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(e.translation_weights);
    const Eigen::Vector2d roots = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    sqrt_w_ = eigen.eigenvectors() * roots.asDiagonal() * eigen.eigenvectors().transpose() / e.sigma_xy;
  }
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const
  {
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    const T ex = c * dx + s * dy - z_.x;
    const T ey = -s * dx + c * dy - z_.y;
    r[0] = sqrt_w_(0, 0) * ex + sqrt_w_(0, 1) * ey;
    r[1] = sqrt_w_(1, 0) * ex + sqrt_w_(1, 1) * ey;
    r[2] = ith_ * wrapAngle(b[2] - a[2] - z_.theta);
    return true;
  }
  linemap::Pose2 z_;
  Eigen::Matrix2d sqrt_w_;
  double ith_;
};
}  // namespace

std::size_t PoseGraph::addNode(const linemap::Pose2& initial)
{
  nodes_.push_back({initial.x, initial.y, initial.theta});
  return nodes_.size() - 1;
}

std::size_t PoseGraph::addEdge(const PoseGraphEdge& edge)
{
  if (edge.from >= nodes_.size() || edge.to >= nodes_.size() || edge.from == edge.to)
    throw std::out_of_range("PoseGraph::addEdge: node index out of range or a self edge");
  edges_.push_back(edge);
  return edges_.size() - 1;
}

void PoseGraph::removeEdge(std::size_t index)
{
  if (index < edges_.size()) edges_.erase(edges_.begin() + static_cast<std::ptrdiff_t>(index));
}

linemap::Pose2 PoseGraph::edgeError(std::size_t index) const
{
  const auto& e = edges_.at(index);
  return e.measurement.inverse() * (node(e.from).inverse() * node(e.to));
}

double PoseGraph::weightedTranslationError(std::size_t index) const
{
  const auto& e = edges_.at(index);
  // The translation residual as EdgeCost forms it (in the `from` frame), not edgeError's.
  const linemap::Pose2 relative = node(e.from).inverse() * node(e.to);
  const Eigen::Vector2d d(relative.x - e.measurement.x, relative.y - e.measurement.y);
  return std::sqrt(std::max(0.0, d.dot(e.translation_weights * d)));
}

OptimizationStats PoseGraph::optimize()
{
  OptimizationStats stats;
  const auto start = std::chrono::steady_clock::now();
  if (nodes_.size() < 2 || edges_.empty()) return stats;
  ceres::Problem problem;
  for (const auto& e : edges_)
  {
    ceres::LossFunction* loss =
        e.loop ? new ceres::CauchyLoss(e.loss_scale > 0.0 ? e.loss_scale : params_.loop_loss_scale) : nullptr;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<EdgeCost, 3, 3, 3>(new EdgeCost(e)), loss,
                             nodes_[e.from].data(), nodes_[e.to].data());
  }
  problem.SetParameterBlockConstant(nodes_[0].data());
  const ceres::Solver::Summary summary =
      solveSilently(problem, ceres::SPARSE_NORMAL_CHOLESKY, params_.max_iterations);
  for (auto& n : nodes_) n[2] = linemap::normalizeAngle(n[2]);
  stats.iterations = static_cast<int>(summary.iterations.size());
  stats.initial_cost = summary.initial_cost;
  stats.final_cost = summary.final_cost;
  stats.converged = summary.termination_type == ceres::CONVERGENCE;
  stats.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace line_map_merging
