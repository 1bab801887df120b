// A 2D pose graph optimised with Ceres (ROS-free). Nodes are poses (x, y, theta); an edge i -> j
// measures pose_i^-1 * pose_j with a diagonal information. Loop-closure edges go through a Cauchy
// loss: a false closure that survived the matcher's checks pulls with a bounded force instead of a
// quadratic one, and is then found by its residual and removed (pruneLoops).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct PoseGraphEdge
{
  std::size_t from = 0, to = 0;
  linemap::Pose2 measurement;  ///< pose_from^-1 * pose_to
  double sigma_xy = 0.05;      ///< [m] standard deviation of the translation
  /// Shape of the translation's information in the `from` frame (symmetric, eigenvalues in (0, 1]):
  /// the information is translation_weights / sigma_xy^2, so a direction of weight w has standard
  /// deviation sigma_xy / sqrt(w). Identity: isotropic (a match that fixes both directions).
  Eigen::Matrix2d translation_weights = Eigen::Matrix2d::Identity();
  double sigma_theta = 0.01;  ///< [rad]
  bool loop = false;          ///< under the robust loss
  double loss_scale = 0.0;    ///< its Cauchy scale in standard deviations; 0 = the graph's
};

struct PoseGraphParams
{
  double loop_loss_scale = 1.0;  ///< Cauchy scale of loop edges, in standard deviations
  int max_iterations = 50;
};

struct OptimizationStats
{
  double milliseconds = 0.0;
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;
  bool converged = false;
};

class PoseGraph
{
 public:
  explicit PoseGraph(const PoseGraphParams& params = {}) : params_(params) {}

  /// Appends a node at `initial` (e.g. the previous node composed with the odometry edge).
  std::size_t addNode(const linemap::Pose2& initial);
  /// Adds an edge between existing nodes; returns its index. Throws std::out_of_range on a bad node.
  std::size_t addEdge(const PoseGraphEdge& edge);
  /// Changes the Cauchy scale of loop edge `index` (standard deviations).
  void setLossScale(std::size_t index, double scale) { edges_.at(index).loss_scale = scale; }
  /// Removes edge `index` (the last added edge is the usual one to remove).
  void removeEdge(std::size_t index);

  /// Optimises every node but the first (the map frame's anchor) from the current estimate.
  OptimizationStats optimize();

  /// Error of edge `index` at the current estimate: measurement^-1 * (pose_from^-1 * pose_to).
  linemap::Pose2 edgeError(std::size_t index) const;
  /// The translation of edgeError in the edge's own metric: sqrt(e^T W e) with W its
  /// translation_weights, so a disagreement along a direction its match did not fix counts less.
  double weightedTranslationError(std::size_t index) const;

  std::size_t nodeCount() const { return nodes_.size(); }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  linemap::Pose2 node(std::size_t i) const { return {nodes_[i][0], nodes_[i][1], nodes_[i][2]}; }
  void setNode(std::size_t i, const linemap::Pose2& p) { nodes_[i] = {p.x, p.y, p.theta}; }
  void clear()
  {
    nodes_.clear();
    edges_.clear();
  }

 private:
  PoseGraphParams params_;
  std::vector<std::array<double, 3>> nodes_;
  std::vector<PoseGraphEdge> edges_;
};

}  // namespace line_map_merging
