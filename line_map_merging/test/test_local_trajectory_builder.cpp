// The SLAM's front end alone, on a ray-cast room: a straight drive is recovered from odometry that
// under-reports every step and from no odometry at all; keyframes every keyframe_distance; a scan
// older than the last one is rejected. In a corridor without odometry the path held to the constant
// velocity is timed.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "line_map_merging/slam/local_trajectory_builder.hpp"
#include "slam_world.hpp"

using line_map_merging::LaserSlamParams;
using line_map_merging::LocalScanResult;
using line_map_merging::LocalTrajectoryBuilder;
using line_map_merging::SlamCounters;
using line_map_merging::SlamOutcome;
using line_map_merging::SlamScan;
using linemap::Pose2;

namespace
{
/// 4.5 m along the room's long axis, then a quarter turn on the spot, 5 cm / 0.1 rad per scan.
std::vector<Pose2> path()
{
  return slam_world::drive(Pose2(1.5, 4.0, 0.0), {{6.0, 4.0}, {6.0, 2.0}});
}

SlamScan scanAt(const Pose2& truth, std::size_t i)
{
  SlamScan s;
  s.stamp = 1.0 + 0.1 * static_cast<double>(i);
  s.points = slam_world::scan(slam_world::room(), truth, 180, 20.0, 0.005, static_cast<unsigned>(i));
  return s;
}

/// Runs the path through a front end; the odometry (when given) reports `odometry_scale` of each step.
/// Checks every scan's pose against the truth relative to the first; returns the keyframes' poses.
std::vector<Pose2> follow(LocalTrajectoryBuilder& builder, SlamCounters& counters, bool with_odometry,
                          double odometry_scale)
{
  const auto truth = path();
  Pose2 odom;
  std::vector<Pose2> keyframes;
  for (std::size_t i = 0; i < truth.size(); ++i)
  {
    SlamScan s = scanAt(truth[i], i);
    if (i > 0)
    {
      const Pose2 step = truth[i - 1].inverse() * truth[i];
      odom = odom * Pose2(odometry_scale * step.x, odometry_scale * step.y, odometry_scale * step.theta);
    }
    if (with_odometry) s.odom = odom;
    const LocalScanResult r = builder.addScan(s, counters);
    EXPECT_NE(r.outcome, SlamOutcome::kRejected);
    const Pose2 expected = truth.front().inverse() * truth[i];
    EXPECT_NEAR(r.pose.x, expected.x, 0.03) << "scan " << i;
    EXPECT_NEAR(r.pose.y, expected.y, 0.03) << "scan " << i;
    EXPECT_NEAR(linemap::normalizeAngle(r.pose.theta - expected.theta), 0.0, 0.01) << "scan " << i;
    if (r.keyframe) keyframes.push_back(r.pose);
  }
  return keyframes;
}

void expectKeyframeSpacing(const std::vector<Pose2>& keyframes, const LaserSlamParams& p)
{
  ASSERT_GT(keyframes.size(), 20u);  // 4.5 m at 0.2 m, and the turn
  EXPECT_EQ(keyframes.front().x, 0.0);
  for (std::size_t i = 1; i < keyframes.size(); ++i)
  {
    const Pose2 since = keyframes[i - 1].inverse() * keyframes[i];
    EXPECT_TRUE(std::hypot(since.x, since.y) >= p.keyframe_distance ||
                std::fabs(since.theta) >= p.keyframe_angle)
        << "keyframe " << i;
    // Not more than one scan's motion beyond the thresholds.
    EXPECT_LT(std::hypot(since.x, since.y), p.keyframe_distance + 0.06) << "keyframe " << i;
    EXPECT_LT(std::fabs(since.theta), p.keyframe_angle + 0.11) << "keyframe " << i;
  }
}
}  // namespace

TEST(LocalTrajectoryBuilder, RecoversMotionFromUnderReportingOdometry)
{
  const LaserSlamParams p;
  LocalTrajectoryBuilder builder(p);
  SlamCounters counters;
  const auto keyframes = follow(builder, counters, true, 0.9);
  expectKeyframeSpacing(keyframes, p);
  EXPECT_EQ(counters.poor_matches, 0u);
  EXPECT_EQ(counters.without_odometry, 0u);
  EXPECT_GT(counters.matched, 0u);
  EXPECT_FALSE(builder.localMap().empty());
}

TEST(LocalTrajectoryBuilder, RecoversMotionWithoutOdometry)
{
  const LaserSlamParams p;
  LocalTrajectoryBuilder builder(p);
  SlamCounters counters;
  const auto keyframes = follow(builder, counters, false, 1.0);
  expectKeyframeSpacing(keyframes, p);
  EXPECT_EQ(counters.poor_matches, 0u);
  EXPECT_EQ(counters.without_odometry, path().size());
}

TEST(LocalTrajectoryBuilder, OlderScanIsRejectedAndChangesNothing)
{
  LocalTrajectoryBuilder builder;
  SlamCounters counters;
  const auto truth = path();
  for (std::size_t i = 0; i < 10; ++i) builder.addScan(scanAt(truth[i], i), counters);
  const Pose2 before = builder.currentLocal();
  SlamScan old = scanAt(truth[10], 10);
  old.stamp = 1.0;  // the first scan's
  EXPECT_EQ(builder.addScan(old, counters).outcome, SlamOutcome::kRejected);
  EXPECT_EQ(counters.rejected, 1u);
  EXPECT_EQ(builder.currentLocal().x, before.x);
  // The first scan has no map to match against: posed by the prediction, and the first keyframe.
  LocalTrajectoryBuilder fresh;
  const LocalScanResult first = fresh.addScan(scanAt(truth[0], 0), counters);
  EXPECT_EQ(first.outcome, SlamOutcome::kPredicted);
  EXPECT_TRUE(first.keyframe);
  EXPECT_TRUE(first.chain_matched);
  EXPECT_FALSE(first.joins.empty());
}

// In the middle of a round hall every heading sees the same scan. The robot turns 1 rad between two scans
// 0.1 s apart (a glitch, or a gap in the log the stamps do not show): the odometry's step exceeds
// max_odometry_turn and what max_odometry_turn_rate allows in 0.1 s, so it counts as a jump, and both its
// pose and the constant-velocity prediction (no turn) are searched. Both match perfectly; the odometry's
// measured motion must stand, not the assumption (which keeps the old heading, 1 rad off).
TEST(LocalTrajectoryBuilder, AcrossAnOdometryJumpTheMeasuredTurnStands)
{
  std::vector<linemap::Segment2> hall;
  constexpr int kSides = 120;
  for (int i = 0; i < kSides; ++i)
  {
    const double a = 2.0 * linemap::kPi * i / kSides, b = 2.0 * linemap::kPi * (i + 1) / kSides;
    hall.emplace_back(linemap::Vec2(4.0 * std::cos(a), 4.0 * std::sin(a)),
                      linemap::Vec2(4.0 * std::cos(b), 4.0 * std::sin(b)));
  }
  const LaserSlamParams p;
  ASSERT_GT(1.0, std::max(p.odometry_jump.turn, 0.1 * p.odometry_jump.turn_rate));
  LocalTrajectoryBuilder builder(p);
  SlamCounters counters;
  for (int i = 0; i < 3; ++i)
  {
    SlamScan s;
    s.stamp = 1.0 + 0.1 * i;
    const double heading = i < 2 ? 0.0 : 1.0;
    s.points = slam_world::scan(hall, Pose2(0.0, 0.0, heading), 180, 20.0, 0.0);
    s.odom = Pose2(0.0, 0.0, heading);
    const LocalScanResult r = builder.addScan(s, counters);
    // The hall's 120 sides look alike every 0.052 rad: within that of the truth, not 1 rad off.
    EXPECT_NEAR(linemap::normalizeAngle(r.pose.theta - heading), 0.0, 0.1) << "scan " << i;
  }
  EXPECT_EQ(counters.odometry_jumps, 1u);
}

// A log of keyframes: scans 2 s apart, the robot moving 0.8 m and turning 0.6 rad between them (0.4 m/s,
// 0.3 rad/s). Each step exceeds max_odometry_step and max_odometry_turn but not what the speed limits
// allow in 2 s, so it is motion: a scan too sparse to match is posed by the odometry. Counted as a jump,
// it would be posed by the constant velocity, which is zero from rest. The same step 0.1 s after the last
// scan (an odometry glitch) is a jump and moves nothing.
TEST(LocalTrajectoryBuilder, OdometryOverScansFarApartInTimeIsMotionNotAJump)
{
  const LaserSlamParams p;
  const Pose2 step(0.8, 0.0, 0.6);
  ASSERT_GT(std::hypot(step.x, step.y), p.odometry_jump.step);
  ASSERT_GT(step.theta, p.odometry_jump.turn);
  LocalTrajectoryBuilder builder(p);
  SlamCounters counters;
  Pose2 odom, truth;
  const std::vector<linemap::Vec2> sparse{{3.0, 0.0}, {3.0, 0.5}, {3.0, -0.5}};  // below min_points
  ASSERT_LT(sparse.size(), p.min_points);
  double stamp = 10.0;
  for (int i = 0; i < 5; ++i)
  {
    SlamScan s;
    s.stamp = stamp;
    s.points = sparse;
    s.odom = odom;
    const LocalScanResult r = builder.addScan(s, counters);
    EXPECT_NEAR(r.pose.x, truth.x, 1e-9) << "scan " << i;
    EXPECT_NEAR(r.pose.y, truth.y, 1e-9) << "scan " << i;
    EXPECT_NEAR(linemap::normalizeAngle(r.pose.theta - truth.theta), 0.0, 1e-9) << "scan " << i;
    odom = odom * step;
    truth = truth * step;
    stamp += 2.0;
  }
  EXPECT_EQ(counters.odometry_jumps, 0u);

  SlamScan glitch;
  glitch.stamp = stamp - 2.0 + 0.1;
  glitch.points = sparse;
  glitch.odom = odom;  // one more step of odometry, 0.1 s after the last scan
  const Pose2 before = truth * step.inverse();
  const LocalScanResult r = builder.addScan(glitch, counters);
  EXPECT_EQ(counters.odometry_jumps, 1u);
  EXPECT_LT(std::hypot(r.pose.x - before.x, r.pose.y - before.y), 0.1);
}

// A pier on one side of a corridor fixes the motion along it while the 180-degree scan sees its front face
// or its far corner; past it the walls run on beyond the scans' reach and fix nothing along the axis.
// Without odometry the front end then holds the constant velocity along the axis: the longest held run is
// the drive from the pier (its faces at x = -0.5 and 0.5 m) to the end at 5 m, at 1 m/s. With odometry
// nothing is held to an assumption.
TEST(LocalTrajectoryBuilder, TheTimeHeldToTheConstantVelocityIsCounted)
{
  LaserSlamParams p;
  p.max_range = 4.0;  // the walls within reach at every beam's angle beyond 17 degrees
  const std::vector<linemap::Segment2> corridor = {{{-5.0, -1.2}, {100.0, -1.2}}, {{-5.0, 1.2}, {-0.5, 1.2}},
                                                   {{-0.5, 1.2}, {-0.5, 0.4}},    {{-0.5, 0.4}, {0.5, 0.4}},
                                                   {{0.5, 0.4}, {0.5, 1.2}},      {{0.5, 1.2}, {100.0, 1.2}}};
  for (const bool with_odometry : {false, true})
  {
    LocalTrajectoryBuilder builder(p);
    SlamCounters counters;
    for (int i = 0; i <= 80; ++i)
    {
      const Pose2 truth(-3.0 + 0.1 * i, 0.0, 0.0);
      SlamScan s;
      s.stamp = 1.0 + 0.1 * i;
      s.points = slam_world::scan(corridor, truth, 360, 20.0, 0.002, static_cast<unsigned>(i));
      if (with_odometry) s.odom = truth;
      const LocalScanResult r = builder.addScan(s, counters);
      ASSERT_NE(r.outcome, SlamOutcome::kRejected);
    }
    EXPECT_EQ(counters.poor_matches, 0u);
    if (with_odometry)
      EXPECT_EQ(counters.longest_held_time, 0.0);
    else
    {
      // The last feature along the axis leaves the scan between the pier's faces: 4.5-5.5 s to go.
      EXPECT_GE(counters.longest_held_time, 4.4);
      EXPECT_LE(counters.longest_held_time, 5.6);
      EXPECT_NEAR(counters.held_time, counters.longest_held_time, 1e-9);  // the run lasts to the end
    }
  }
}
