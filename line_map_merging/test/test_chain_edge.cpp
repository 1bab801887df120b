// The translation weights of a matched chain edge (chain_edge.hpp) against hand computation. The match's
// shape is in the local frame, the edge's measurement in the previous keyframe's: at a heading other than
// 0 or pi a rotation applied the wrong way round (R W R^T instead of R^T W R) flips the sign of the
// off-diagonal entries, and a shape left in the local frame puts the weight on the wrong direction.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/slam/chain_edge.hpp"
#include "linemap/geometry.hpp"

using line_map_merging::chainEdgeTranslationWeights;

namespace
{
constexpr double kEdgeSigma = 0.02, kOdometrySigma = 0.2;
constexpr double kFloor = (kEdgeSigma / kOdometrySigma) * (kEdgeSigma / kOdometrySigma);  // 0.01
constexpr double kDeg = linemap::kPi / 180.0;
}  // namespace

// The match fixed the local x axis and left y to the odometry: diag(1, 0) in the local frame. Seen from
// a keyframe heading 30 degrees the local x axis points at -30 degrees, u = (c, -s) with c = cos 30,
// s = sin 30, and the left direction is v = (s, c). The weights are u u^T + floor v v^T:
//   [ c^2 + floor s^2        -(1 - floor) c s ]   [ 0.7525     -0.4286816 ]
//   [ -(1 - floor) c s    s^2 + floor c^2     ] = [ -0.4286816  0.2575    ]
TEST(ChainEdge, WeightsInThePreviousKeyframesFrameAtThirtyDegrees)
{
  Eigen::Matrix2d match;
  match << 1.0, 0.0, 0.0, 0.0;
  const Eigen::Matrix2d w = chainEdgeTranslationWeights(match, 30.0 * kDeg, kEdgeSigma, kOdometrySigma);
  const double c = std::sqrt(3.0) / 2.0, s = 0.5;
  EXPECT_NEAR(w(0, 0), c * c + kFloor * s * s, 1e-12);
  EXPECT_NEAR(w(0, 1), -(1.0 - kFloor) * c * s, 1e-12);
  EXPECT_NEAR(w(1, 0), -(1.0 - kFloor) * c * s, 1e-12);
  EXPECT_NEAR(w(1, 1), s * s + kFloor * c * c, 1e-12);
  // The same as directions: full weight along the local x axis, the floor across it.
  const Eigen::Vector2d u(c, -s), v(s, c);
  EXPECT_NEAR(u.dot(w * u), 1.0, 1e-12);
  EXPECT_NEAR(v.dot(w * v), kFloor, 1e-12);
  EXPECT_NEAR(u.dot(w * v), 0.0, 1e-12);
}

// A match whose fixed direction is oblique in the local frame (45 degrees, weight 1; across it 0.5, above
// the floor, so it stays), from a keyframe heading -100 degrees: in the keyframe's frame the fixed
// direction lies at 45 + 100 = 145 degrees.
TEST(ChainEdge, ObliqueShapeKeepsItsEigenvaluesAndTurnsByTheHeading)
{
  const Eigen::Vector2d a(std::cos(45.0 * kDeg), std::sin(45.0 * kDeg)), b(-a.y(), a.x());
  const Eigen::Matrix2d match = a * a.transpose() + 0.5 * b * b.transpose();
  const Eigen::Matrix2d w = chainEdgeTranslationWeights(match, -100.0 * kDeg, kEdgeSigma, kOdometrySigma);
  const Eigen::Vector2d u(std::cos(145.0 * kDeg), std::sin(145.0 * kDeg)), v(-u.y(), u.x());
  EXPECT_NEAR(u.dot(w * u), 1.0, 1e-12);
  EXPECT_NEAR(v.dot(w * v), 0.5, 1e-12);
  EXPECT_NEAR(u.dot(w * v), 0.0, 1e-12);
  EXPECT_NEAR(w(0, 1), w(1, 0), 1e-15);
}

// A match that fixed both directions gives the isotropic edge at any heading; one that fixed none the
// odometry's looseness in both.
TEST(ChainEdge, IsotropicShapesStayIsotropic)
{
  for (double heading : {0.0, 0.7, 2.0, -2.9})
  {
    const Eigen::Matrix2d full =
        chainEdgeTranslationWeights(Eigen::Matrix2d::Identity(), heading, kEdgeSigma, kOdometrySigma);
    EXPECT_TRUE(full.isApprox(Eigen::Matrix2d::Identity(), 1e-12)) << heading;
    const Eigen::Matrix2d none =
        chainEdgeTranslationWeights(Eigen::Matrix2d::Zero(), heading, kEdgeSigma, kOdometrySigma);
    EXPECT_TRUE(none.isApprox(kFloor * Eigen::Matrix2d::Identity(), 1e-12)) << heading;
  }
}
