#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/online/keyframe_gate.hpp"
#include "line_map_merging/online/node_keyframes.hpp"

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

// The policy at a back end's trajectory (the merger's and the evaluator's stores follow it).
TEST(NodeKeyframes, FirstTrajectoryRebuildsOnlyWhenEveryScanSinceTheOldestKeyframeIsHeld)
{
  using Nodes = line_map_merging::NodeKeyframes<int>;
  const KeyframeGateParams gate;
  {
    Nodes nodes(gate, 0.01, 100.0);
    nodes.addScan(1.0, 1);  // held since 1 s; the store's oldest keyframe is at 1 s
    EXPECT_FALSE(nodes.rebuildAtFirstTrajectory(false, 1.0));  // names no scan seen
    EXPECT_FALSE(nodes.active());
    EXPECT_FALSE(nodes.rebuildAtFirstTrajectory(true, std::nullopt));  // an empty store
    EXPECT_TRUE(nodes.rebuildAtFirstTrajectory(true, 1.0));
    EXPECT_TRUE(nodes.active());
    EXPECT_FALSE(nodes.rebuildAtFirstTrajectory(true, 1.0));  // only at the first trajectory
    // Rebuilt from the start: the node at the held scan makes it a keyframe.
    EXPECT_EQ(nodes.addTrajectory({{1.0, Pose2(0, 0, 0)}}).size(), 1u);
  }
  {
    Nodes nodes(gate, 0.01, 100.0);
    nodes.addScan(2.0, 2);  // the scans before the keyframe at 1 s are gone
    EXPECT_FALSE(nodes.rebuildAtFirstTrajectory(true, 1.0));
    nodes.takeOver(false, 1.5, std::nullopt);
    EXPECT_FALSE(nodes.active());
    nodes.takeOver(true, 2.0, Pose2(0, 0, 0));  // after the newest keyframe, at 2 s
    EXPECT_TRUE(nodes.active());
    EXPECT_DOUBLE_EQ(nodes.horizon(), 2.0);
    EXPECT_TRUE(nodes.addTrajectory({{2.0, Pose2(0, 0, 0)}}).empty());  // done with: a keyframe exists
  }
}
