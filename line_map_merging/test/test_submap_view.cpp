// What a submap looked at, alone: a keyframe's view cone spans its returns' bearings and range, and a point
// is in view when some keyframe's cone holds it (range widened by a margin); a laser seeing all around
// sees every bearing.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "line_map_merging/slam/submap_view.hpp"
#include "slam_world.hpp"

using line_map_merging::inView;
using line_map_merging::viewCone;
using line_map_merging::ViewCone;
using linemap::Pose2;
using linemap::Vec2;

TEST(SubmapView, TheConeSpansTheReturnsBearingsAndRange)
{
  // A 180-degree scan facing +x in a 10 x 8 m room, from (2, 4): its returns span -90..90 degrees.
  const auto points = slam_world::scan(slam_world::room(), Pose2(2.0, 4.0, 0.0), 181, 20.0, 0.0, 1);
  const ViewCone cone = viewCone(points);
  EXPECT_NEAR(cone.min_bearing, -linemap::kPi / 2, 0.02);
  EXPECT_NEAR(cone.max_bearing, linemap::kPi / 2, 0.02);
  EXPECT_FALSE(cone.full_circle);
  double farthest = 0.0;
  for (const auto& p : points) farthest = std::max(farthest, p.norm());
  EXPECT_DOUBLE_EQ(cone.max_range, farthest);
  // All around: every bearing is seen.
  std::vector<Vec2> around;
  for (int i = 0; i < 360; ++i)
  {
    const double a = linemap::kPi * (i + 0.5) / 180.0;
    around.emplace_back(3.0 * std::cos(a), 3.0 * std::sin(a));
  }
  EXPECT_TRUE(viewCone(around).full_circle);
  EXPECT_TRUE(inView({{-2.0, 0.1}}, {{Pose2(), viewCone(around)}}, 0.0).front());
}

TEST(SubmapView, APointBehindOrBeyondEveryKeyframeIsOutOfView)
{
  ViewCone front;  // facing +x, 180 degrees, 5 m
  front.min_bearing = -linemap::kPi / 2;
  front.max_bearing = linemap::kPi / 2;
  front.max_range = 5.0;
  const std::vector<std::pair<Pose2, ViewCone>> views{{Pose2(2.0, 0.0, 0.0), front},
                                                      {Pose2(3.0, 0.0, 0.0), front}};
  const std::vector<Vec2> points{{4.0, 1.0},    // ahead of both
                                 {1.5, 0.5},    // behind both: a place the submap never looked at
                                 {2.5, -1.0},   // behind the second, ahead of the first
                                 {7.5, 0.0},    // 5.5 m from the first, 4.5 m from the second
                                 {8.5, 0.0},    // 5.5 m from the nearer: within a 1 m margin only
                                 {2.0, 10.0}};  // 90 degrees off the first, 10 m away
  const std::vector<bool> seen = inView(points, views, 0.0);
  EXPECT_EQ(seen, (std::vector<bool>{true, false, true, true, false, false}));
  const std::vector<bool> widened = inView(points, views, 1.0);
  EXPECT_EQ(widened, (std::vector<bool>{true, false, true, true, true, false}));
  // Turned to face -x, the second keyframe sees what lies behind them.
  const std::vector<std::pair<Pose2, ViewCone>> turned{{Pose2(3.0, 0.0, linemap::kPi), front}};
  EXPECT_TRUE(inView({{1.5, 0.5}}, turned, 0.0).front());
}
