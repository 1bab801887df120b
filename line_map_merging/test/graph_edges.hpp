// A pose graph edge in one call, for the tests that build their graphs by hand.
#pragma once

#include <cstddef>

#include "line_map_merging/slam/pose_graph.hpp"
#include "linemap/geometry.hpp"

namespace graph_edges
{
/// The edge from -> to measuring `z` with isotropic translation weights and the graph's loss scale; `loop`
/// puts it under the robust loss.
inline line_map_merging::PoseGraphEdge edge(std::size_t from, std::size_t to, const linemap::Pose2& z,
                                            double sigma_xy, double sigma_theta, bool loop = false)
{
  line_map_merging::PoseGraphEdge e;
  e.from = from;
  e.to = to;
  e.measurement = z;
  e.sigma_xy = sigma_xy;
  e.sigma_theta = sigma_theta;
  e.loop = loop;
  return e;
}

}  // namespace graph_edges
