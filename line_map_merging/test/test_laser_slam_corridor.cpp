// LaserSlam in a long corridor with rooms on both sides, odometry that overestimates the distance
// travelled (a drift along the corridor's axis, where the walls say nothing), and passes in both
// directions with an excursion into a room: closures between opposite passes hold across the
// corridor and in heading, and do not lock a drifted estimate in along it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

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

/// Doors (1 m) in both walls lead to 4 x 4 m rooms; the ends are beyond the laser's 20 m from the
/// middle, so there the walls alone fix y and the heading, not x.
std::vector<Segment2> corridorFloor()
{
  std::vector<Segment2> w = {{{0, 0}, {0, 2}}, {{kLength, 2}, {kLength, 0}}};
  const std::vector<double> south_doors = {8.0, 21.0, 33.0}, north_doors = {14.0, 27.0};
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

/// Drives through `goals`, 5 cm per scan, turning on the spot at 0.1 rad per scan.
void driveTo(std::vector<Pose2>& path, const std::vector<Vec2>& goals)
{
  Pose2 p = path.back();
  for (const Vec2& goal : goals)
  {
    const double heading = std::atan2(goal.y() - p.y, goal.x() - p.x);
    while (std::fabs(linemap::normalizeAngle(heading - p.theta)) > 1e-9)
    {
      const double d = linemap::normalizeAngle(heading - p.theta);
      p.theta = linemap::normalizeAngle(p.theta + std::clamp(d, -0.1, 0.1));
      path.push_back(p);
    }
    while ((goal - p.translation()).norm() > 1e-9)
    {
      const Vec2 step = goal - p.translation();
      const double len = std::min(0.05, step.norm());
      p.x += step.x() / step.norm() * len;
      p.y += step.y() / step.norm() * len;
      path.push_back(p);
    }
  }
}

/// East to the far end, into the room of the south door at x = 21 and back, west to the start,
/// east again: passes in both directions over the whole corridor.
std::vector<Pose2> corridorPath()
{
  std::vector<Pose2> path{Pose2(2.0, 1.0, 0.0)};
  driveTo(path, {{21.5, 1.0}, {21.5, -2.0}, {21.5, 1.0}, {38.0, 1.0}, {2.0, 1.0}, {38.0, 1.0}});
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
  double worst = 0.0, mean = 0.0, worst_odometry = 0.0;
  line_map_merging::SlamCounters counters;
};

Errors runCorridor(const LaserSlamParams& params)
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
    s.odom = odom[i];
    if (std::getenv("CORRIDOR_TRACE"))
    {
      const Pose2 t = truth[0].inverse() * truth[i];
      std::fprintf(stderr, "TRUTH %zu %.3f %.3f %.3f\n", i, t.x, t.y, t.theta);
    }
    slam.addScan(s);
    e.worst_odometry = std::max(e.worst_odometry, (odom[i].translation() - truth[i].translation()).norm());
  }
  const auto poses = slam.scanPoses();
  double sum = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i)
  {
    const Pose2 p = truth[0] * poses[i].second;
    const double d = std::hypot(p.x - truth[i].x, p.y - truth[i].y);
    e.worst = std::max(e.worst, d);
    sum += d;
    if (std::getenv("CORRIDOR_TRACE") && i % 50 == 0)
      std::printf("%zu truth %.2f %.2f %.2f slam %.2f %.2f %.2f odom %.2f %.2f err %.3f\n", i, truth[i].x, truth[i].y,
                  truth[i].theta, p.x, p.y, p.theta, odom[i].x, odom[i].y, d);
  }
  e.mean = sum / static_cast<double>(poses.size());
  e.counters = slam.counters();
  return e;
}
}  // namespace

TEST(LaserSlamCorridor, OppositePassesAgree)
{
  const Errors e = runCorridor(LaserSlamParams());
  const auto& c = e.counters;
  std::printf("matched %zu filtered %zu predicted %zu poor %zu wide %zu keyframes %zu without_odometry %zu jumps %zu\n", c.matched, c.filtered, c.predicted, c.poor_matches, c.wide_searches, c.keyframes, c.without_odometry, c.odometry_jumps);
  std::printf("corridor: worst %.3f m, mean %.3f m (odometry alone: worst %.3f m); loops accepted %zu, "
              "with an open direction %zu, ambiguous %zu, rejected by the graph %zu\n",
              e.worst, e.mean, e.worst_odometry, c.loops_accepted, c.loops_degenerate, c.loops_ambiguous,
              c.loops_rejected_graph);
  EXPECT_GT(e.worst_odometry, 1.0);  // the odometry alone is far off along the corridor
  EXPECT_GT(c.loops_accepted, 0u);
  EXPECT_LT(e.worst, 0.05);
}

TEST(LaserSlamCorridor, IsotropicForComparison)
{
  LaserSlamParams p;
  p.isotropic_ratio = 0.0;
  const Errors e = runCorridor(p);
  const auto& c = e.counters;
  std::printf("isotropic: worst %.3f m, mean %.3f m; loops accepted %zu, ambiguous %zu, rejected by the graph %zu, "
              "poor matches %zu\n",
              e.worst, e.mean, c.loops_accepted, c.loops_ambiguous, c.loops_rejected_graph, c.poor_matches);
}

TEST(LaserSlamCorridor, FrontEndOnly)
{
  LaserSlamParams p;
  p.loop_candidates = 0;
  const Errors e = runCorridor(p);
  std::printf("front end only: worst %.3f m, mean %.3f m\n", e.worst, e.mean);
}
