// The placement of a fleet's robots, its parts with closed forms: points along segments, and the length of
// the fleet's walls that a robot's scans see through under a placement.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/localization/fleet_placement.hpp"

using namespace line_map_merging;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

TEST(FleetPlacement, PointsAlongASegmentAreEvenlySpacedAndMoved)
{
  const auto points =
      segmentPoints({Segment2(Vec2(0.0, 0.0), Vec2(1.0, 0.0))}, Pose2(2.0, 0.0, M_PI / 2), 0.25);
  ASSERT_EQ(points.size(), 5u);  // 0, 0.25, ..., 1 along x, then turned a quarter and moved 2 m along x
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    EXPECT_NEAR(points[i].x(), 2.0, 1e-12);
    EXPECT_NEAR(points[i].y(), 0.25 * static_cast<double>(i), 1e-12);
  }
}

// A robot at its origin saw a wall 4 m ahead, x = 4 for |y| <= 2. Placed where it is, a fleet wall at x = 2
// (|y| <= 3) lies in the free triangle: the part the beams crossed, the triangle's width at x = 2 less the
// 0.3 m margin on each ray's side, is seen through: |y| <= 1 narrowed by the margin measured across the rays.
// Placed 3 m further on, the fleet wall lies behind the robot: nothing is seen through.
TEST(FleetPlacement, AWallInsideTheFreeSpaceASightCrossedIsSeenThrough)
{
  LocalizerParams params;
  FleetPlacement placement(params);
  const std::vector<Segment2> seen{Segment2(Vec2(4.0, -2.0), Vec2(4.0, 2.0))};
  placement.addScan(1, 1.0, seen, Pose2(), Pose2());
  const std::vector<Segment2> fleet{Segment2(Vec2(2.0, -3.0), Vec2(2.0, 3.0))};
  // The rays y = +-x/2 at x = 2 reach |y| = 1; eroded by 0.3 m perpendicular to a ray of slope 1/2, the edge
  // moves in by 0.3 * sqrt(1 + 1/4) = 0.335 m along y. Bins of 0.1 m along the 6 m wall round that to the
  // bin.
  const double expected = 2.0 * (1.0 - 0.3 * std::sqrt(1.25));
  EXPECT_NEAR(placement.seenThroughLength(1, Pose2(), fleet), expected, 0.2);
  EXPECT_EQ(placement.seenThroughLength(1, Pose2(3.0, 0.0, 0.0), fleet), 0.0);
  // The wall seen in place by the same sight is no contradiction.
  EXPECT_EQ(placement.seenThroughLength(1, Pose2(), seen), 0.0);
  EXPECT_EQ(placement.seenThroughLength(2, Pose2(), fleet), 0.0) << "a robot never seen saw nothing";
}

namespace
{
/// The four walls of a 10 x 4 m room (corner at the origin) and, with `box`, a 1 m square crate at (7.5..8.5,
/// 0.5..1.5): the room alone looks the same turned half a turn about its centre, the crate tells the two
/// apart.
std::vector<Segment2> room(bool box)
{
  std::vector<Segment2> out{Segment2(Vec2(0, 0), Vec2(10, 0)), Segment2(Vec2(10, 0), Vec2(10, 4)),
                            Segment2(Vec2(10, 4), Vec2(0, 4)), Segment2(Vec2(0, 4), Vec2(0, 0))};
  if (box)
    for (const auto& [a, b] : {std::pair{Vec2(7.5, 0.5), Vec2(8.5, 0.5)},
                               {Vec2(8.5, 0.5), Vec2(8.5, 1.5)},
                               {Vec2(8.5, 1.5), Vec2(7.5, 1.5)},
                               {Vec2(7.5, 1.5), Vec2(7.5, 0.5)}})
      out.emplace_back(a, b);
  return out;
}
}  // namespace

// A robot that has seen the whole room from (2, 2), its map frame the fleet's: placed at the identity, the
// same room turned half a turn about (5, 2) explains its scans as well, so the place is ambiguous. With the
// crate in the room and in its scans (4 m of faces, 80 points) the turned room misses the crate: no longer
// ambiguous. A wrong placement (the turned one) is ambiguous against the right one.
TEST(FleetPlacement, ALookAlikePlacementHalfATurnAwayLeavesThePlaceOpen)
{
  LocalizerParams params;
  const Pose2 laser(2.0, 2.0, 0.0);
  for (const bool box : {false, true})
  {
    FleetPlacement placement(params);
    std::vector<Segment2> seen;
    for (const Segment2& s : room(box)) seen.push_back(s.transformed(laser.inverse()));
    placement.addScan(1, 1.0, seen, laser, Pose2());
    EXPECT_EQ(placement.ambiguous(1, Pose2(), room(box)), !box) << (box ? "with" : "without") << " the crate";
    EXPECT_TRUE(placement.ambiguous(1, Pose2(10.0, 4.0, M_PI), room(box)));
  }
}
