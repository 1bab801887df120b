// Matching trajectory poses to keyframes by stamp, and interpolated corrections for the others.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/trajectory_correction.hpp"

using line_map_merging::correctKeyframes;
using line_map_merging::KeyframeInfo;
using line_map_merging::matchByStamp;
using linemap::Pose2;

namespace
{
std::vector<KeyframeInfo> fourKeyframes()
{
  std::vector<KeyframeInfo> k(4);
  for (int i = 0; i < 4; ++i)
  {
    k[i].index = 10 + i;
    k[i].stamp = 100.0 + i;
    k[i].pose = Pose2(i, 1.0, 0.0);
  }
  return k;
}
}  // namespace

TEST(TrajectoryCorrection, MatchByStampTakesTheNearestWithinTolerance)
{
  const auto k = fourKeyframes();
  EXPECT_EQ(matchByStamp(k, 101.004, 0.01).value(), 1u);
  EXPECT_EQ(matchByStamp(k, 101.996, 0.01).value(), 2u);
  EXPECT_FALSE(matchByStamp(k, 101.5, 0.01).has_value());
  EXPECT_FALSE(matchByStamp(k, 99.0, 0.01).has_value());
  EXPECT_EQ(matchByStamp(k, 103.009, 0.01).value(), 3u);
  EXPECT_FALSE(matchByStamp({}, 100.0, 1.0).has_value());
}

TEST(TrajectoryCorrection, UnmatchedKeyframesGetTheInterpolatedCorrection)
{
  const auto k = fourKeyframes();
  // Keyframe 10 moved by (+1, 0), keyframe 12 by (+3, 0): 11 is halfway, 13 is clamped to 12's.
  std::map<std::uint64_t, Pose2> matched{{10, Pose2(1, 1, 0)}, {12, Pose2(5, 1, 0)}};
  const auto out = correctKeyframes(k, matched);
  ASSERT_EQ(out.size(), 4u);
  const double expected_x[4] = {1, 3, 5, 6};
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_EQ(out[i].first, 10u + i);
    EXPECT_NEAR(out[i].second.x, expected_x[i], 1e-12) << i;
    EXPECT_NEAR(out[i].second.y, 1.0, 1e-12) << i;
    EXPECT_NEAR(out[i].second.theta, 0.0, 1e-12) << i;
  }
}

TEST(TrajectoryCorrection, RotationCorrectionIsInterpolatedAboutTheMapOrigin)
{
  auto k = fourKeyframes();
  // Keyframe 10 unchanged, keyframe 12 rotated by 0.2 rad about the origin: keyframe 11 gets 0.1 rad.
  const Pose2 rot(0, 0, 0.2);
  std::map<std::uint64_t, Pose2> matched{{10, k[0].pose}, {12, rot * k[2].pose}};
  const auto out = correctKeyframes(k, matched);
  const Pose2 expected = Pose2(0, 0, 0.1) * k[1].pose;
  EXPECT_NEAR(out[1].second.x, expected.x, 1e-12);
  EXPECT_NEAR(out[1].second.y, expected.y, 1e-12);
  EXPECT_NEAR(out[1].second.theta, 0.1, 1e-12);
  // Before the first match: clamped to its correction (identity here).
  EXPECT_TRUE(correctKeyframes(k, {}).empty());
}
