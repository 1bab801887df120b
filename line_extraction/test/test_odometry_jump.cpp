#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "linemap/odometry_jump.hpp"

using linemap::OdometryJumpLimits;
using linemap::Pose2;

// Limits 0.5 m / 0.5 rad per reading, or 2 m/s / 2 rad/s over the time between readings.
TEST(OdometryJumpLimits, AStepIsMotionWithinTheStepOrTheSpeedOverTheElapsedTime)
{
  const OdometryJumpLimits limits{0.5, 0.5, 2.0, 2.0};
  EXPECT_TRUE(limits.isMotion(Pose2(0.3, 0.4, 0.0), 0.1));    // 0.5 m: the step limit, whatever the time
  EXPECT_FALSE(limits.isMotion(Pose2(0.3, 0.41, 0.0), 0.1));  // beyond 0.5 m and beyond 2 m/s x 0.1 s
  EXPECT_TRUE(limits.isMotion(Pose2(1.2, 1.6, 0.0), 1.0));    // 2 m in 1 s: at the speed limit
  EXPECT_FALSE(limits.isMotion(Pose2(1.2, 1.6, 0.0), 0.99));
  EXPECT_TRUE(limits.isMotion(Pose2(0.0, 0.0, -1.0), 0.5));   // 1 rad in 0.5 s
  EXPECT_FALSE(limits.isMotion(Pose2(0.0, 0.0, -1.0), 0.4));  // only 0.8 rad allowed then
  EXPECT_FALSE(limits.isMotion(Pose2(1.0, 0.0, 1.5), 0.6));   // the step within 1.2 m, the turn not
}

TEST(OdometryJumpLimits, TimeGoingBackOrUnknownAllowsOnlyTheStep)
{
  const OdometryJumpLimits limits{0.5, 0.5, 2.0, 2.0};
  EXPECT_FALSE(limits.isMotion(Pose2(1.0, 0.0, 0.0), -3.0));
  EXPECT_FALSE(limits.isMotion(Pose2(1.0, 0.0, 0.0), std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(limits.isMotion(Pose2(1.0, 0.0, 0.0), std::numeric_limits<double>::infinity()));
  EXPECT_TRUE(limits.isMotion(Pose2(0.5, 0.0, 0.5), -3.0));
}
