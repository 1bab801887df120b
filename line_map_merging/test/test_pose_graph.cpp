// Pose graph with Ceres: exact constraints are kept; a loop closes a biased chain; a false closure
// is bounded by the Cauchy loss (and would wreck a graph without it).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "graph_edges.hpp"
#include "line_map_merging/slam/pose_graph.hpp"

using line_map_merging::PoseGraph;
using line_map_merging::PoseGraphEdge;
using linemap::Pose2;

namespace
{
/// A ring of n poses on a circle of radius r, heading along it.
std::vector<Pose2> ring(int n, double r)
{
  std::vector<Pose2> p;
  for (int i = 0; i < n; ++i)
  {
    const double a = 2 * linemap::kPi * i / n;
    p.push_back({r * std::cos(a), r * std::sin(a), linemap::normalizeAngle(a + linemap::kPi / 2)});
  }
  return p;
}

PoseGraphEdge edge(std::size_t i, std::size_t j, const Pose2& z, bool loop, double sxy = 0.02,
                   double sth = 0.005)
{
  return graph_edges::edge(i, j, z, sxy, sth, loop);
}

/// A ring graph: chain edges with a heading bias per edge, true loop edges every `loop_every` nodes
/// across to the node half way round, the first node at its truth.
PoseGraph biasedRing(const std::vector<Pose2>& truth, double bias)
{
  PoseGraph g;
  Pose2 estimate = truth[0];
  g.addNode(estimate);
  for (std::size_t i = 1; i < truth.size(); ++i)
  {
    const Pose2 z = truth[i - 1].inverse() * truth[i] * Pose2(0, 0, bias);
    estimate = estimate * z;
    g.addNode(estimate);
    g.addEdge(edge(i - 1, i, z, false));
  }
  // Closing the ring: last -> first, exact, under a loss as wide as the drift it corrects (as the
  // SLAM does for a corroborated closure).
  auto close = edge(truth.size() - 1, 0, truth.back().inverse() * truth[0], true);
  close.loss_scale = 200.0;
  g.addEdge(close);
  return g;
}

double maxError(const PoseGraph& g, const std::vector<Pose2>& truth)
{
  double m = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    m = std::max(m, std::hypot(g.node(i).x - truth[i].x, g.node(i).y - truth[i].y));
  return m;
}
}  // namespace

TEST(PoseGraph, ExactConstraintsStay)
{
  const auto truth = ring(12, 5.0);
  PoseGraph g = biasedRing(truth, 0.0);
  g.optimize();
  EXPECT_LT(maxError(g, truth), 1e-6);
}

TEST(PoseGraph, LoopClosureCorrectsAHeadingBias)
{
  const auto truth = ring(40, 8.0);
  PoseGraph g = biasedRing(truth, 0.004);  // 0.16 rad over the ring: the chain misses its start by metres
  const double before = maxError(g, truth);
  EXPECT_GT(before, 1.0);
  const auto stats = g.optimize();
  // The bias is spread over the chain's 40 edges; what remains is each edge's share of the bias's
  // translation effect, far below the drift.
  EXPECT_LT(maxError(g, truth), 0.1);
  EXPECT_LT(stats.final_cost, stats.initial_cost);
  const Pose2 e = g.edgeError(g.edges().size() - 1);
  EXPECT_LT(std::hypot(e.x, e.y), 0.05);
}

TEST(PoseGraph, FalseClosureIsBoundedByTheRobustLoss)
{
  const auto truth = ring(40, 8.0);
  auto build = [&](bool robust)
  {
    PoseGraph g;
    for (const auto& p : truth) g.addNode(p);
    for (std::size_t i = 1; i < truth.size(); ++i)
      g.addEdge(edge(i - 1, i, truth[i - 1].inverse() * truth[i], false));
    // True closures across the ring.
    for (std::size_t i = 0; i < 20; i += 10)
      g.addEdge(edge(i, i + 20, truth[i].inverse() * truth[i + 20], robust));
    // A false one: node 10 "seen" 3 m beside and 0.5 rad off where node 30 really is.
    g.addEdge(edge(10, 30, truth[10].inverse() * truth[30] * Pose2(3.0, 0.0, 0.5), robust, 0.05, 0.01));
    return g;
  };
  PoseGraph robust = build(true);
  robust.optimize();
  // Absorbed: the map barely moves, and the false edge stands out by its residual.
  EXPECT_LT(maxError(robust, truth), 0.1);
  const Pose2 e = robust.edgeError(robust.edges().size() - 1);
  EXPECT_GT(std::hypot(e.x, e.y), 2.5);
  // Without the loss the same graph is wrecked: the false edge pulls the ring apart.
  PoseGraph plain = build(false);
  plain.optimize();
  EXPECT_GT(maxError(plain, truth), 0.5);
}

TEST(PoseGraph, BadEdgesAreRefused)
{
  PoseGraph g;
  g.addNode(Pose2());
  EXPECT_THROW(g.addEdge(edge(0, 1, Pose2(), false)), std::out_of_range);
  EXPECT_THROW(g.addEdge(edge(0, 0, Pose2(), false)), std::out_of_range);
  g.addNode(Pose2(1, 0, 0));
  const auto i = g.addEdge(edge(0, 1, Pose2(1, 0, 0), false));
  g.removeEdge(i);
  EXPECT_TRUE(g.edges().empty());
  EXPECT_EQ(g.optimize().iterations, 0);  // nothing to optimise
}

// A closure whose translation information is weak along x (a corridor match) corrects y but leaves
// x where the chain puts it; the same closure isotropic drags x too.
TEST(PoseGraph, ClosureMovesOnlyWhatItsMatchDetermines)
{
  auto solve = [](const Eigen::Matrix2d& weights)
  {
    PoseGraph g;
    g.addNode(Pose2(0, 0, 0));
    g.addNode(Pose2(10, 0, 0));
    g.addNode(Pose2(20, 0, 0));
    g.addEdge(edge(0, 1, Pose2(10, 0, 0), false, 0.05, 1e-5));
    g.addEdge(edge(1, 2, Pose2(10, 0, 0), false, 0.05, 1e-5));
    // The closure says node 2 is 0.5 m further along x and 0.2 m off in y.
    auto close = edge(0, 2, Pose2(20.5, 0.2, 0), true, 0.05, 1e-5);  // stiff headings: y moves by translation
    close.translation_weights = weights;
    close.loss_scale = 100.0;
    const std::size_t index = g.addEdge(close);
    // Before optimising, its disagreement in its own metric: the y part alone when x is weak.
    const double weighted = g.weightedTranslationError(index);
    g.optimize();
    return std::make_pair(g.node(2), weighted);
  };
  Eigen::Matrix2d weak_x = Eigen::Matrix2d::Identity();
  weak_x(0, 0) = 1e-3;
  const auto [shaped, shaped_error] = solve(weak_x);
  const auto [isotropic, isotropic_error] = solve(Eigen::Matrix2d::Identity());
  EXPECT_NEAR(shaped_error, std::hypot(0.5 * std::sqrt(1e-3), 0.2), 1e-9);
  EXPECT_NEAR(isotropic_error, std::hypot(0.5, 0.2), 1e-9);
  // Isotropic: the closure (one edge against two chain edges of equal sigma) takes 2/3 of both.
  EXPECT_NEAR(isotropic.x, 20.0 + 0.5 * 2.0 / 3.0, 0.01);
  EXPECT_NEAR(isotropic.y, 0.2 * 2.0 / 3.0, 0.02);
  // Shaped: y as before, x barely (the chain's information along x is 500 times the closure's).
  EXPECT_NEAR(shaped.y, 0.2 * 2.0 / 3.0, 0.02);
  EXPECT_LT(std::fabs(shaped.x - 20.0), 0.01);
}
