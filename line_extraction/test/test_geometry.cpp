// Shared geometry and parameter parsing, checked against hand-computed values.
#include <gtest/gtest.h>

#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

using namespace linemap;

TEST(Geometry, NormalizeAngleRange)
{
  EXPECT_NEAR(normalizeAngle(3.0 * kPi), kPi, 1e-12);  // (-pi, pi]: +pi stays
  EXPECT_NEAR(normalizeAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(normalizeAngle(2.0 * kPi + 0.5), 0.5, 1e-12);
  EXPECT_NEAR(normalizeAngle(-2.0 * kPi - 0.5), -0.5, 1e-12);
}

TEST(Geometry, PoseComposeAndInverse)
{
  const Pose2 a(1.0, 2.0, kPi / 2.0);
  const Pose2 b(3.0, 0.0, 0.0);
  const Pose2 ab = a * b;  // b's x axis is a's y axis: (1, 2) + (0, 3)
  EXPECT_NEAR(ab.x, 1.0, 1e-12);
  EXPECT_NEAR(ab.y, 5.0, 1e-12);
  EXPECT_NEAR(ab.theta, kPi / 2.0, 1e-12);
  const Pose2 id = a * a.inverse();
  EXPECT_NEAR(id.x, 0.0, 1e-12);
  EXPECT_NEAR(id.y, 0.0, 1e-12);
  EXPECT_NEAR(id.theta, 0.0, 1e-12);
}

TEST(Geometry, InterpolateTakesShortArc)
{
  const Pose2 p = interpolate(Pose2(0, 0, 3.0), Pose2(2, 4, -3.0), 0.5);
  EXPECT_NEAR(p.x, 1.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
  EXPECT_NEAR(std::abs(p.theta), kPi, 1e-9);  // through pi, not through 0
}

TEST(Geometry, DistancesAndHessianForm)
{
  EXPECT_NEAR(distanceToLine(Vec2(5, 3), Vec2(0, 0), Vec2(1, 0)), 3.0, 1e-12);
  EXPECT_NEAR(distanceToSegment(Vec2(5, 3), Vec2(0, 0), Vec2(1, 0)), std::hypot(4.0, 3.0), 1e-12);
  // The line y = -2 has normal angle -pi/2 and radius 2, whichever way it is traversed.
  for (const auto& h :
       {hessianFromPoints(Vec2(0, -2), Vec2(1, -2)), hessianFromPoints(Vec2(1, -2), Vec2(0, -2))})
  {
    EXPECT_NEAR(h.radius, 2.0, 1e-12);
    EXPECT_NEAR(h.angle, -kPi / 2.0, 1e-12);
  }
  EXPECT_NEAR(Segment2(Vec2(1, 1), Vec2(0, 1)).heading(), kPi, 1e-12);
}

TEST(Params, TypedGettersNameTheKey)
{
  ParamSet p;
  p.set("srg/seed_points", "6");
  p.set("srg/line_distance", "abc");
  EXPECT_EQ(p.getInt("srg/seed_points", 0), 6);
  EXPECT_DOUBLE_EQ(p.getDouble("missing", 1.5), 1.5);
  try
  {
    p.getDouble("srg/line_distance", 0.0);
    FAIL() << "malformed value accepted";
  }
  catch (const ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("srg/line_distance"), std::string::npos);
  }
}
