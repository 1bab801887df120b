#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/online/keyframe_gate.hpp"

using line_map_merging::KeyframeGate;
using line_map_merging::KeyframeGateParams;
using linemap::Pose2;

TEST(KeyframeGate, FirstScanIsAlwaysAKeyframe)
{
  KeyframeGate gate;
  EXPECT_TRUE(gate.accept(Pose2(5.0, -3.0, 2.0)));
}

TEST(KeyframeGate, TranslationThreshold)
{
  KeyframeGate gate;  // 0.2 m, 10 deg
  ASSERT_TRUE(gate.accept(Pose2(0, 0, 0)));
  EXPECT_FALSE(gate.accept(Pose2(0.12, 0.12, 0)));  // 0.1697 m
  EXPECT_TRUE(gate.accept(Pose2(0.12, 0.17, 0)));   // 0.208 m
  // The reference moved to (0.12, 0.17): 0.15 m further is not enough.
  EXPECT_FALSE(gate.accept(Pose2(0.27, 0.17, 0)));
  EXPECT_TRUE(gate.accept(Pose2(0.33, 0.17, 0)));  // 0.21 m from the reference
}

TEST(KeyframeGate, RotationThresholdWrapsAround)
{
  KeyframeGate gate;
  const double deg = M_PI / 180.0;
  ASSERT_TRUE(gate.accept(Pose2(0, 0, 175 * deg)));
  EXPECT_FALSE(gate.accept(Pose2(0, 0, -176 * deg)));  // 9 deg across the +-pi seam
  EXPECT_TRUE(gate.accept(Pose2(0, 0, -174 * deg)));   // 11 deg across the seam
  EXPECT_FALSE(gate.accept(Pose2(0, 0, -165 * deg)));  // 9 deg from the new reference
}

TEST(KeyframeGate, ParametersAndReset)
{
  linemap::ParamSet params;
  params.set("keyframe_distance", "1.0");
  params.set("keyframe_angle", "0.5");
  KeyframeGate gate(KeyframeGateParams::fromParams(params));
  EXPECT_DOUBLE_EQ(gate.params().distance, 1.0);
  EXPECT_DOUBLE_EQ(gate.params().angle, 0.5);
  ASSERT_TRUE(gate.accept(Pose2(0, 0, 0)));
  EXPECT_FALSE(gate.wouldAccept(Pose2(0.9, 0, 0.4)));
  gate.reset();
  EXPECT_TRUE(gate.accept(Pose2(0.1, 0, 0)));

  linemap::ParamSet bad;
  bad.set("keyframe_distance", "-1");
  try
  {
    KeyframeGateParams::fromParams(bad);
    FAIL() << "a negative distance was accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("keyframe_distance"), std::string::npos);
  }
}
