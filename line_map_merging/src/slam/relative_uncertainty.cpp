#include "line_map_merging/slam/relative_uncertainty.hpp"

#include <Eigen/Cholesky>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace line_map_merging
{
Eigen::Matrix3d edgeCovariance(const PoseGraphEdge& e)
{
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c.topLeftCorner<2, 2>() =
      e.sigma_xy * e.sigma_xy * e.translation_weights.ldlt().solve(Eigen::Matrix2d::Identity());
  c(2, 2) = e.sigma_theta * e.sigma_theta;
  return c;
}

std::optional<Eigen::Matrix3d> relativeCovariance(const PoseGraph& graph, std::size_t from, std::size_t to)
{
  const std::size_t n = graph.nodeCount();
  if (from >= n || to >= n) return std::nullopt;
  if (from == to) return Eigen::Matrix3d::Zero();
  const auto& edges = graph.edges();
  std::vector<std::vector<std::size_t>> incident(n);
  std::vector<Eigen::Matrix3d> covariance(edges.size());
  std::vector<double> cost(edges.size());
  for (std::size_t i = 0; i < edges.size(); ++i)
  {
    incident[edges[i].from].push_back(i);
    incident[edges[i].to].push_back(i);
    covariance[i] = edgeCovariance(edges[i]);
    // A scalar for the search: the translation's variance plus the heading's over a metre of lever.
    cost[i] = covariance[i].trace();
  }
  // Dijkstra from `from`; the path is then walked back from `to`.
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  std::vector<std::size_t> via(n, edges.size());
  using Entry = std::pair<double, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  distance[from] = 0.0;
  queue.push({0.0, from});
  while (!queue.empty())
  {
    const auto [d, u] = queue.top();
    queue.pop();
    if (d > distance[u]) continue;
    if (u == to) break;
    for (std::size_t i : incident[u])
    {
      const std::size_t v = edges[i].from == u ? edges[i].to : edges[i].from;
      if (d + cost[i] < distance[v])
      {
        distance[v] = d + cost[i];
        via[v] = i;
        queue.push({distance[v], v});
      }
    }
  }
  if (via[to] == edges.size()) return std::nullopt;
  std::vector<std::pair<std::size_t, std::size_t>> path;  // (node, edge into it)
  for (std::size_t v = to; v != from;)
  {
    const std::size_t i = via[v];
    path.push_back({v, i});
    v = edges[i].from == v ? edges[i].to : edges[i].from;
  }
  // First order: the next node's pose is the current one's composed with the edge, so the current
  // heading's uncertainty moves it by its lever arm, and the edge adds its own covariance, rotated
  // into `from`'s frame by its `from` node's estimated heading.
  const linemap::Pose2 origin_inverse = graph.node(from).inverse();
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  linemap::Pose2 at;  // the current node relative to `from`
  for (auto step = path.rbegin(); step != path.rend(); ++step)
  {
    const linemap::Pose2 next = origin_inverse * graph.node(step->first);
    const linemap::Pose2 edge_from = origin_inverse * graph.node(edges[step->second].from);
    Eigen::Matrix3d lever = Eigen::Matrix3d::Identity();
    lever(0, 2) = -(next.y - at.y);
    lever(1, 2) = next.x - at.x;
    Eigen::Matrix3d rotate = Eigen::Matrix3d::Identity();
    const double c = std::cos(edge_from.theta), s = std::sin(edge_from.theta);
    rotate.topLeftCorner<2, 2>() << c, -s, s, c;
    sigma = lever * sigma * lever.transpose() + rotate * covariance[step->second] * rotate.transpose();
    at = next;
  }
  return sigma;
}

}  // namespace line_map_merging
