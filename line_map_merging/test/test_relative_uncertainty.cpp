// The covariance of a relative pose along a pose graph's most certain path, against closed forms: a
// straight chain of n equal edges (the heading's random walk swings the far end sideways), the same chain
// turned (the result is in the first node's frame, so it must not change), a shorter certain path
// taken over the chain, a shaped edge's covariance, and nodes no path joins.
#include <gtest/gtest.h>

#include <cmath>

#include "graph_edges.hpp"
#include "line_map_merging/slam/relative_uncertainty.hpp"

using line_map_merging::edgeCovariance;
using line_map_merging::PoseGraph;
using line_map_merging::PoseGraphEdge;
using line_map_merging::relativeCovariance;
using linemap::Pose2;

namespace
{
constexpr double kStep = 0.5, kSigmaXy = 0.02, kSigmaTheta = 0.01;

/// n edges of kStep straight ahead from `start`.
PoseGraph chain(int n, const Pose2& start)
{
  PoseGraph g;
  g.addNode(start);
  for (int i = 1; i <= n; ++i)
  {
    g.addNode(start * Pose2(kStep * i, 0.0, 0.0));
    g.addEdge(graph_edges::edge(static_cast<std::size_t>(i - 1), static_cast<std::size_t>(i),
                                Pose2(kStep, 0.0, 0.0), kSigmaXy, kSigmaTheta));
  }
  return g;
}

/// The chain's covariance by hand: along it n translation variances; across it those plus the
/// heading errors of edges 1 .. n-1, edge l swinging the end by kStep (n - l); the heading n variances.
Eigen::Matrix3d chainCovariance(int n)
{
  double lever2 = 0.0, lever = 0.0;
  for (int l = 1; l < n; ++l)
  {
    lever2 += (kStep * (n - l)) * (kStep * (n - l));
    lever += kStep * (n - l);
  }
  const double t2 = kSigmaXy * kSigmaXy, h2 = kSigmaTheta * kSigmaTheta;
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c(0, 0) = n * t2;
  c(1, 1) = n * t2 + h2 * lever2;
  c(2, 2) = n * h2;
  c(1, 2) = c(2, 1) = h2 * lever;
  return c;
}
}  // namespace

TEST(RelativeUncertainty, StraightChainMatchesTheClosedForm)
{
  const int n = 12;
  const auto c = relativeCovariance(chain(n, Pose2()), 0, n);
  ASSERT_TRUE(c.has_value());
  const Eigen::Matrix3d expected = chainCovariance(n);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR((*c)(r, k), expected(r, k), 1e-12) << r << "," << k;
  // The sideways spread dwarfs the one along the chain: the heading's lever arm.
  EXPECT_GT((*c)(1, 1), 3.0 * (*c)(0, 0));
}

TEST(RelativeUncertainty, IsInTheFirstNodesFrame)
{
  const int n = 7;
  const auto c = relativeCovariance(chain(n, Pose2(3.0, -2.0, 2.2)), 0, n);
  ASSERT_TRUE(c.has_value());
  const Eigen::Matrix3d expected = chainCovariance(n);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR((*c)(r, k), expected(r, k), 1e-12) << r << "," << k;
}

TEST(RelativeUncertainty, TakesTheMoreCertainPath)
{
  const int n = 20;
  PoseGraph g = chain(n, Pose2());
  PoseGraphEdge shortcut;
  shortcut.from = 0;
  shortcut.to = n;
  shortcut.measurement = Pose2(kStep * n, 0.0, 0.0);
  shortcut.sigma_xy = 0.03;
  shortcut.sigma_theta = 0.004;
  shortcut.loop = true;
  g.addEdge(shortcut);
  const auto c = relativeCovariance(g, 0, n);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR((*c)(0, 0), 0.03 * 0.03, 1e-12);
  EXPECT_NEAR((*c)(1, 1), 0.03 * 0.03, 1e-12);
  EXPECT_NEAR((*c)(2, 2), 0.004 * 0.004, 1e-12);
  // Node 1 is still nearer node 0 along the chain than round the loop.
  const auto one = relativeCovariance(g, 0, 1);
  ASSERT_TRUE(one.has_value());
  EXPECT_NEAR((*one)(0, 0), kSigmaXy * kSigmaXy, 1e-12);
}

TEST(RelativeUncertainty, ShapedEdgeIsLooseAlongItsWeakDirection)
{
  PoseGraphEdge e;
  e.sigma_xy = 0.05;
  e.sigma_theta = 0.01;
  // Weight 0.01 along the diagonal (1, 1) / sqrt(2), 1 across it.
  const Eigen::Vector2d along(std::sqrt(0.5), std::sqrt(0.5)), across(-std::sqrt(0.5), std::sqrt(0.5));
  e.translation_weights = 0.01 * along * along.transpose() + across * across.transpose();
  const Eigen::Matrix3d c = edgeCovariance(e);
  const Eigen::Matrix2d t = c.topLeftCorner<2, 2>();
  EXPECT_NEAR(along.dot(t * along), 0.05 * 0.05 / 0.01, 1e-9);
  EXPECT_NEAR(across.dot(t * across), 0.05 * 0.05, 1e-9);
  EXPECT_NEAR(c(2, 2), 1e-4, 1e-15);
}

TEST(RelativeUncertainty, NothingWithoutAPath)
{
  PoseGraph g = chain(3, Pose2());
  g.addNode(Pose2(10.0, 0.0, 0.0));
  EXPECT_FALSE(relativeCovariance(g, 0, 4).has_value());
  EXPECT_FALSE(relativeCovariance(g, 0, 9).has_value());
  const auto same = relativeCovariance(g, 2, 2);
  ASSERT_TRUE(same.has_value());
  EXPECT_EQ(same->norm(), 0.0);
}
