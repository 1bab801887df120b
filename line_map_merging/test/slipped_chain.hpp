// An out-and-back drive whose chain slipped once, for the tests of closures across a slip: out 40 poses
// 0.5 m apart along x, back 40 along y = 1 (pose 79 - i beside pose i); the chain edges are the true
// relative poses but for the one into `slipped_node`, composed with the slip. The nodes stand at the chain's
// (slipped) estimate, as a front end that slipped would leave them.
#pragma once

#include <cstddef>
#include <vector>

#include "graph_edges.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "linemap/geometry.hpp"

namespace slipped_chain
{
using line_map_merging::PoseGraph;
using line_map_merging::PoseGraphEdge;
using linemap::Pose2;

inline std::vector<Pose2> outAndBack()
{
  std::vector<Pose2> t;
  for (int i = 0; i < 40; ++i) t.push_back({0.5 * i, 0.0, 0.0});
  for (int i = 0; i < 40; ++i) t.push_back({19.5 - 0.5 * i, 1.0, linemap::kPi});
  return t;
}

inline PoseGraph slippedChain(std::size_t slipped_node, const Pose2& slip, double sigma_xy,
                              double sigma_theta, const line_map_merging::PoseGraphParams& params = {})
{
  const auto truth = outAndBack();
  PoseGraph g(params);
  g.addNode(truth[0]);
  for (std::size_t i = 1; i < truth.size(); ++i)
  {
    PoseGraphEdge e = graph_edges::edge(i - 1, i, truth[i - 1].inverse() * truth[i], sigma_xy, sigma_theta);
    if (i == slipped_node) e.measurement = e.measurement * slip;
    g.addNode(g.node(i - 1) * e.measurement);
    g.addEdge(e);
  }
  return g;
}

}  // namespace slipped_chain
