// How well a pose graph knows one node's pose relative to another (ROS-free): the covariance of the
// relative pose, propagated to first order along the graph's most certain path between the two nodes
// (Dijkstra over the edges' variances, loop edges included). The path ignores the information the other
// paths add, so the covariance is an upper bound: a loop closure's disagreement with the estimate is
// judged against it plus the closure's own covariance (ClosureGate's consistency gate).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>

#include "line_map_merging/slam/pose_graph.hpp"

namespace line_map_merging
{
/// Covariance of edge e's measurement in its `from` frame (x, y, theta): the translation's sigma_xy^2
/// times the inverse of its translation_weights, the heading's sigma_theta^2.
Eigen::Matrix3d edgeCovariance(const PoseGraphEdge& e);

/// Covariance of node `to`'s pose relative to node `from`, in `from`'s frame (x, y, theta), at the
/// graph's current estimate; nullopt when no path joins them (or either index is out of range).
std::optional<Eigen::Matrix3d> relativeCovariance(const PoseGraph& graph, std::size_t from, std::size_t to);

}  // namespace line_map_merging
