// Matching trajectory poses to keyframes by stamp, and interpolated corrections for the others.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "line_map_merging/online/trajectory_correction.hpp"

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

TEST(TrajectoryCorrection, MatchByStampLeavesPosesOfNearerScansAlone)
{
  // Keyframe 1 (t = 101) had scans 2 ms before and 4 ms after it that did not become keyframes:
  // a pose stamped 101.003 belongs to the scan at 101.004, not to the keyframe, although it is
  // within the 10 ms tolerance; one stamped 101.0015 is nearer the keyframe's scan.
  auto k = fourKeyframes();
  k[1].scan_gap_before = 0.002;
  k[1].scan_gap_after = 0.004;
  EXPECT_EQ(matchByStamp(k, 101.0, 0.01).value(), 1u);
  EXPECT_EQ(matchByStamp(k, 101.0015, 0.01).value(), 1u);
  EXPECT_FALSE(matchByStamp(k, 101.003, 0.01).has_value());
  EXPECT_FALSE(matchByStamp(k, 101.0021, 0.01).has_value());  // just nearer to the next scan
  EXPECT_EQ(matchByStamp(k, 100.9995, 0.01).value(), 1u);
  EXPECT_FALSE(matchByStamp(k, 100.9985, 0.01).has_value());  // the scan at 100.998 is nearer
  // Two scans with one stamp: the exact stamp still matches the keyframe.
  k[1].scan_gap_before = 0.0;
  EXPECT_EQ(matchByStamp(k, 101.0, 0.01).value(), 1u);
  // Unknown gaps (infinite): the tolerance alone decides, as before.
  EXPECT_EQ(matchByStamp(k, 102.009, 0.01).value(), 2u);
}

TEST(TrajectoryCorrection, ScanGapTrackerLearnsTheGapsAroundKeyframes)
{
  line_map_merging::ScanGapTracker gaps;
  auto k = fourKeyframes();  // indices 10..13
  const double inf = std::numeric_limits<double>::infinity();
  // Scans at 100.000 (keyframe 10), 100.002, 100.010 (keyframe 11), 100.013 (keyframe 12).
  gaps.scan(100.000);
  gaps.keyframe(10);
  gaps.scan(100.002);
  gaps.scan(100.010);
  gaps.keyframe(11);
  gaps.scan(100.013);
  gaps.keyframe(12);
  // Time jumps back: the next keyframe's gap before is unknown.
  gaps.scan(50.0);
  gaps.keyframe(13);
  gaps.fill(k);
  EXPECT_EQ(k[0].scan_gap_before, inf);  // the first scan
  EXPECT_NEAR(k[0].scan_gap_after, 0.002, 1e-9);
  EXPECT_NEAR(k[1].scan_gap_before, 0.008, 1e-9);
  EXPECT_NEAR(k[1].scan_gap_after, 0.003, 1e-9);  // to keyframe 12's scan
  EXPECT_NEAR(k[2].scan_gap_before, 0.003, 1e-9);
  EXPECT_EQ(k[2].scan_gap_after, inf);  // the next stamp went back
  EXPECT_EQ(k[3].scan_gap_before, inf);
  EXPECT_EQ(k[3].scan_gap_after, inf);  // no scan after it yet
  EXPECT_EQ(gaps.size(), 4u);
  gaps.clear();
  EXPECT_EQ(gaps.size(), 0u);
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

namespace
{
// Six keyframes driving along x in the odometry frame; the back end's map->odom was the identity
// until keyframe 3, where it jumped to the corrected map->odom `d` (as carmen_to_bag's bags do at
// each trajectory emission): the keyframes before the jump were registered on raw odometry.
struct JumpCase
{
  Pose2 d{0.5, -0.2, 0.1};
  Pose2 jump_map_to_odom{12.0, 5.0, 2.1};
  std::vector<KeyframeInfo> keyframes;
  std::map<std::uint64_t, Pose2> odom;
  std::map<std::uint64_t, Pose2> matched;

  JumpCase()
  {
    for (int i = 0; i < 6; ++i)
    {
      KeyframeInfo k;
      k.index = 20 + i;
      k.stamp = 50.0 + i;
      const Pose2 o(i, 0.1 * i, 0.05 * i);
      k.pose = (i < 3 ? Pose2() : jump_map_to_odom) * o;
      keyframes.push_back(k);
      odom[k.index] = o;
    }
    // The trajectory (the truth d * odom) holds keyframes 0, 3 and 5.
    for (int i : {0, 3, 5}) matched[20 + i] = d * odom.at(20 + i);
  }
};

double poseError(const Pose2& a, const Pose2& b)
{
  return std::hypot(a.x - b.x, a.y - b.y) + std::abs(linemap::normalizeAngle(a.theta - b.theta));
}
}  // namespace

TEST(TrajectoryCorrection, OdometryPosesCarryTheCorrectionAcrossAMapToOdomJump)
{
  const JumpCase c;
  const auto out = correctKeyframes(c.keyframes, c.matched, c.odom);
  ASSERT_EQ(out.size(), 6u);
  for (int i = 0; i < 6; ++i)
  {
    EXPECT_EQ(out[i].first, 20u + i);
    EXPECT_LT(poseError(out[i].second, c.d * c.odom.at(20 + i)), 1e-9) << "keyframe " << i;
  }
  // In the map frame the correction jumps at keyframe 3: keyframes 1 and 2, registered before the
  // jump, are moved by a blend of the two corrections, metres off (what the nodelets did on Intel).
  const auto map_frame = correctKeyframes(c.keyframes, c.matched);
  EXPECT_GT(poseError(map_frame[2].second, c.d * c.odom.at(22)), 1.0);
}

TEST(TrajectoryCorrection, KeyframesWithoutOdometryTakeTheirNeighboursMapToOdom)
{
  JumpCase c;
  // Keyframe 1 (before the jump) and 4 (after it) lack odometry; keyframe 0's too, so it takes the
  // map->odom of the first keyframe with one (keyframe 1 is missing, so keyframe 2: identity).
  for (int i : {0, 1, 4}) c.odom.erase(20 + i);
  const JumpCase truth;
  const auto out = correctKeyframes(c.keyframes, c.matched, c.odom);
  ASSERT_EQ(out.size(), 6u);
  for (int i = 0; i < 6; ++i)
    EXPECT_LT(poseError(out[i].second, truth.d * truth.odom.at(20 + i)), 1e-9) << "keyframe " << i;
}

TEST(TrajectoryCorrection, WithoutOdometryPosesTheCorrectionIsInterpolatedInTheMapFrame)
{
  const JumpCase c;
  const auto a = correctKeyframes(c.keyframes, c.matched);
  const auto b = correctKeyframes(c.keyframes, c.matched, {});
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_EQ(a[i].first, b[i].first);
    EXPECT_LT(poseError(a[i].second, b[i].second), 1e-12);
  }
  EXPECT_TRUE(correctKeyframes(c.keyframes, {}, c.odom).empty());
}
