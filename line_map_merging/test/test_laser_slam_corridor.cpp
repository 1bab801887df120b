// LaserSlam in a ray-cast 40 m corridor with rooms on both sides, odometry that overestimates the
// distance travelled (a drift along the corridor's axis, where the walls say nothing), and passes in
// both directions with an excursion into a room. Ground truth gives the error of every scan's pose.
// The front end must follow the corridor: a matcher that holds the pose of the keyframe it matches
// against stays at its first keyframe (tens of metres off), one that takes the odometry along the
// axis drifts with it (metres).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "line_map_merging/slam/laser_slam.hpp"
#include "slam_world.hpp"

using line_map_merging::LaserSlam;
using line_map_merging::LaserSlamParams;
using line_map_merging::SlamScan;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kLength = 40.0;  // corridor along x, 2 m wide (y in [0, 2])
constexpr double kRoomDoor = 21.0;

/// Doors (1 m) in both walls lead to 4 x 4 m rooms; the ends are beyond the laser's 20 m from the
/// middle, so there the walls alone fix y and the heading, not x.
std::vector<Segment2> corridorFloor()
{
  std::vector<Segment2> w = {{{0, 0}, {0, 2}}, {{kLength, 2}, {kLength, 0}}};
  const std::vector<double> south_doors = {8.0, kRoomDoor, 33.0}, north_doors = {14.0, 27.0};
  auto wallWithDoors = [&](double y, const std::vector<double>& doors)
  {
    double x = 0.0;
    for (double d : doors)
    {
      w.push_back({{x, y}, {d, y}});
      x = d + 1.0;
    }
    w.push_back({{x, y}, {kLength, y}});
  };
  wallWithDoors(0.0, south_doors);
  wallWithDoors(2.0, north_doors);
  auto room = [&](double door, double y0, double y1)
  {
    const double x0 = door - 1.5, x1 = door + 2.5;
    w.push_back({{x0, y0}, {door, y0}});
    w.push_back({{door + 1.0, y0}, {x1, y0}});
    w.push_back({{x0, y0}, {x0, y1}});
    w.push_back({{x1, y0}, {x1, y1}});
    w.push_back({{x0, y1}, {x1, y1}});
    w.push_back({{x0 + 0.5, y1 + (y0 - y1) * 0.3}, {x0 + 1.2, y1 + (y0 - y1) * 0.3}});  // a cupboard
  };
  for (double d : south_doors) room(d, 0.0, -4.0);
  for (double d : north_doors) room(d, 2.0, 6.0);
  return w;
}

/// East to the far end, into the room of the south door at x = 21 and back, west to the start,
/// east again: passes in both directions over the whole corridor.
std::vector<Pose2> corridorPath()
{
  const Pose2 start(2.0, 1.0, 0.0);
  std::vector<Pose2> path{start};
  const auto rest = slam_world::drive(start, {{kRoomDoor + 0.5, 1.0},
                                              {kRoomDoor + 0.5, -2.0},
                                              {kRoomDoor + 0.5, 1.0},
                                              {38.0, 1.0},
                                              {2.0, 1.0},
                                              {38.0, 1.0}});
  path.insert(path.end(), rest.begin(), rest.end());
  return path;
}

/// Odometry that overestimates every forward step by 4 % and turns 0.005 rad per metre too far.
std::vector<Pose2> overestimating(const std::vector<Pose2>& truth)
{
  std::vector<Pose2> odom{truth[0]};
  for (std::size_t i = 1; i < truth.size(); ++i)
  {
    Pose2 step = truth[i - 1].inverse() * truth[i];
    const double length = std::hypot(step.x, step.y);
    step.x *= 1.04;
    step.y *= 1.04;
    step.theta += 0.005 * length;
    odom.push_back(odom.back() * step);
  }
  return odom;
}

struct Errors
{
  double worst = 0.0, mean = 0.0;
  double worst_first_pass = 0.0;  ///< up to the room: no revisit yet
  double worst_odometry = 0.0;
  double worst_revisit = 0.0, mean_revisit = 0.0;  ///< relative error of scan pairs on different passes
  std::size_t revisits = 0;
  line_map_merging::SlamCounters counters;
};

/// Every scan's position error (the SLAM's map frame is the first pose).
Errors runCorridor(const LaserSlamParams& params, bool with_odometry)
{
  const auto walls = corridorFloor();
  const auto truth = corridorPath();
  const auto odom = overestimating(truth);
  LaserSlam slam(params);
  Errors e;
  for (std::size_t i = 0; i < truth.size(); ++i)
  {
    SlamScan s;
    s.stamp = 1.0 + 0.1 * static_cast<double>(i);
    s.points = slam_world::scan(walls, truth[i], 180, 20.0, 0.005, static_cast<unsigned>(i));
    if (with_odometry) s.odom = odom[i];
    slam.addScan(s);
    e.worst_odometry = std::max(e.worst_odometry, (odom[i].translation() - truth[i].translation()).norm());
  }
  const auto poses = slam.scanPoses();
  EXPECT_EQ(poses.size(), truth.size());
  double sum = 0.0;
  bool first_pass = true;
  for (std::size_t i = 0; i < poses.size() && i < truth.size(); ++i)
  {
    const Pose2 p = truth[0] * poses[i].second;
    const double d = std::hypot(p.x - truth[i].x, p.y - truth[i].y);
    first_pass &= truth[i].y > 0.0;  // until the robot enters the room
    e.worst = std::max(e.worst, d);
    if (first_pass) e.worst_first_pass = std::max(e.worst_first_pass, d);
    sum += d;
  }
  e.mean = sum / static_cast<double>(poses.size());
  // Revisits: scan pairs within 1 m of each other with at least 10 m driven between them.
  std::vector<double> path_at(truth.size(), 0.0);
  for (std::size_t i = 1; i < truth.size(); ++i)
    path_at[i] = path_at[i - 1] + (truth[i].translation() - truth[i - 1].translation()).norm();
  double revisit_sum = 0.0;
  std::size_t revisits = 0;
  for (std::size_t i = 0; i < poses.size(); i += 5)
    for (std::size_t j = i + 5; j < poses.size(); j += 5)
    {
      if (path_at[j] - path_at[i] < 10.0 || (truth[i].translation() - truth[j].translation()).norm() > 1.0)
        continue;
      const Pose2 t = truth[i].inverse() * truth[j];
      const Pose2 est = poses[i].second.inverse() * poses[j].second;
      const double d = std::hypot(t.x - est.x, t.y - est.y);
      e.worst_revisit = std::max(e.worst_revisit, d);
      revisit_sum += d;
      ++revisits;
    }
  e.mean_revisit = revisits > 0 ? revisit_sum / static_cast<double>(revisits) : 0.0;
  e.revisits = revisits;
  e.counters = slam.counters();
  return e;
}
}  // namespace

// The front end alone (no loop closure), on the field of the keyframes' surfaces: along the axis the
// odometry's 4 % would put the robot metres off over the 110 m driven; the doors, the rooms and the
// corridor's ends seen now and then must keep it within a fraction of that.
TEST(LaserSlamCorridor, FrontEndFollowsTheCorridor)
{
  LaserSlamParams front_end_only;
  front_end_only.loop_candidates = 0;
  front_end_only.surfaces.lambda = 10.0 * linemap::kPi / 180.0;  // the field of the keyframes' surfaces
  const Errors e = runCorridor(front_end_only, true);
  std::printf(
      "front end, odometry: worst %.3f m, mean %.3f m, first pass worst %.3f m (odometry alone: worst %.3f "
      "m); "
      "matches leaving a direction to the odometry %zu of %zu\n",
      e.worst, e.mean, e.worst_first_pass, e.worst_odometry, e.counters.degenerate_matches,
      e.counters.matched);
  EXPECT_GT(e.worst_odometry, 4.0);  // the odometry alone is far off along the corridor
  EXPECT_GT(e.counters.degenerate_matches, 0u);
  EXPECT_LT(e.worst_first_pass, 0.1);
  EXPECT_LT(e.worst, 0.5);
  EXPECT_LT(e.mean, 0.25);
}

// The whole SLAM with its defaults: closures between passes in both directions must correct the front
// end's drift where the doors fix the axis and leave it alone where the walls alone are seen. Pairs of scans
// on different passes within a metre of each other must agree with the truth; a field of points alone
// (the front end stuck at its first keyframe) misses by tens of metres, closures without the consistency
// test or held along the axis they slid on by metres, chain edges as stiff along the axis as across it
// (where the odometry, not the match, set the motion) by over a decimetre. The floors lie between the
// SLAM and the SLAM with chain edges of identity translation weights (chainEdgeTranslationWeights patched
// out), measured 2026-11-27 on 4f9fdb2: revisits worst 0.080 / 0.118 m, mean 0.020 / 0.042 m; every scan
// worst 0.084 / 0.147 m.
TEST(LaserSlamCorridor, RevisitsAgreeInBothDirections)
{
  const Errors e = runCorridor(LaserSlamParams(), true);
  std::printf(
      "whole SLAM, odometry: %zu revisit pairs, worst %.3f m, mean %.3f m; every scan: worst %.3f m, mean "
      "%.3f "
      "m; closures %zu accepted, %zu inconsistent, %zu ambiguous of %zu attempts\n",
      e.revisits, e.worst_revisit, e.mean_revisit, e.worst, e.mean, e.counters.loops_accepted,
      e.counters.loops_inconsistent, e.counters.loops_ambiguous, e.counters.loop_attempts);
  EXPECT_GT(e.revisits, 1000u);
  EXPECT_GT(e.counters.loops_accepted, 10u);
  EXPECT_LT(e.worst_revisit, 0.1);
  EXPECT_LT(e.mean_revisit, 0.03);
  EXPECT_LT(e.worst, 0.12);
}
