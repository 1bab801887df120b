// Occupancy grid from a line map: hand-counted cells of one keyframe seeing one wall, walls over
// free, keyframe poses placing the originals, 4-connected walls, the grid of a CaeRlsm (withheld
// segments give free space but no wall), and bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "line_map_merging/map/occupancy_grid.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

using line_map_merging::buildOccupancyGrid;
using line_map_merging::CaeRlsm;
using line_map_merging::KeyframeInfo;
using line_map_merging::Leaf;
using line_map_merging::OccupancyGrid;
using line_map_merging::OccupancyGridParams;
using line_map_merging::Sighting;
using line_map_merging::sightingsOf;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
// One keyframe at the origin seeing the wall x = 2, y in [-1, 1]. At 0.3 m with a 1.05 m margin the
// grid spans columns floor(-1.05 / 0.3) = -4 .. floor(3.05 / 0.3) = 10 (15) and rows
// floor(-2.05 / 0.3) = -7 .. floor(2.05 / 0.3) = 6 (14): origin (-1.2, -2.1), cell centres at
// ±0.15, ±0.45, ... on both axes.
const Segment2 kWall(Vec2(2.0, -1.0), Vec2(2.0, 1.0));
OccupancyGridParams handParams()
{
  OccupancyGridParams p;
  p.resolution = 0.3;
  p.margin = 1.05;
  return p;
}

OccupancyGrid handGrid()
{
  return buildOccupancyGrid({kWall}, {{Vec2(0.0, 0.0), kWall}}, handParams());
}
}  // namespace

TEST(OccupancyGrid, OneKeyframeSeeingOneWallByHand)
{
  const OccupancyGrid g = handGrid();
  EXPECT_NEAR(g.origin.x(), -1.2, 1e-9);
  EXPECT_NEAR(g.origin.y(), -2.1, 1e-9);
  EXPECT_EQ(g.width, 15);
  EXPECT_EQ(g.height, 14);
  ASSERT_EQ(g.cells.size(), 15u * 14u);

  // The wall lies in the column x in [1.8, 2.1) and the rows holding y = -1 ([-1.2, -0.9)) up to
  // y = 1 ([0.9, 1.2)): 8 cells.
  EXPECT_EQ(g.count(OccupancyGrid::kOccupied), 8u);
  for (double y = -0.95; y <= 0.95; y += 0.1)
    EXPECT_EQ(g.valueAt(Vec2(2.0, y)), OccupancyGrid::kOccupied) << y;
  // Free: the cell centres inside |y| <= x / 2, x < 1.8. Column centres 0.15: none (|y| <= 0.075);
  // 0.45 and 0.75: y = ±0.15 (2 + 2); 1.05 and 1.35: ±0.15, ±0.45 (4 + 4); 1.65: ±0.15, ±0.45, ±0.75 (6).
  EXPECT_EQ(g.count(OccupancyGrid::kFree), 18u);
  EXPECT_EQ(g.count(OccupancyGrid::kUnknown), 15u * 14u - 8u - 18u);

  EXPECT_EQ(g.valueAt(Vec2(1.0, 0.0)), OccupancyGrid::kFree);
  EXPECT_EQ(g.valueAt(Vec2(1.65, 0.75)), OccupancyGrid::kFree);     // centre 0.075 inside the edge
  EXPECT_EQ(g.valueAt(Vec2(0.15, 0.15)), OccupancyGrid::kUnknown);  // at the apex, centre outside
  EXPECT_EQ(g.valueAt(Vec2(3.0, 0.0)), OccupancyGrid::kUnknown);    // behind the wall
  EXPECT_EQ(g.valueAt(Vec2(1.0, 0.9)), OccupancyGrid::kUnknown);    // beside the triangle
  EXPECT_EQ(g.valueAt(Vec2(-0.5, 0.0)), OccupancyGrid::kUnknown);   // behind the robot
  EXPECT_EQ(g.valueAt(Vec2(2.0, 1.5)), OccupancyGrid::kUnknown);    // beyond the wall's end
  EXPECT_EQ(g.valueAt(Vec2(50.0, 0.0)), OccupancyGrid::kUnknown);   // outside the grid

  // cellOf and cellCentre agree.
  int column, row;
  g.cellOf(Vec2(1.0, 0.1), column, row);
  EXPECT_EQ(column, 7);
  EXPECT_EQ(row, 7);
  EXPECT_NEAR(g.cellCentre(column, row).x(), 1.05, 1e-9);
  EXPECT_NEAR(g.cellCentre(column, row).y(), 0.15, 1e-9);
}

TEST(OccupancyGrid, WallsWinOverFreeSeenFromBehind)
{
  // A second keyframe at (4, 0) sees the same wall from the other side: both triangles are free, the
  // wall column stays occupied.
  const Segment2 from_behind(Vec2(2.0, 1.0), Vec2(2.0, -1.0));
  const OccupancyGrid g =
      buildOccupancyGrid({kWall}, {{Vec2(0.0, 0.0), kWall}, {Vec2(4.0, 0.0), from_behind}}, handParams());
  EXPECT_EQ(g.count(OccupancyGrid::kOccupied), 8u);
  EXPECT_EQ(g.valueAt(Vec2(2.0, 0.0)), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.valueAt(Vec2(1.0, 0.0)), OccupancyGrid::kFree);
  EXPECT_EQ(g.valueAt(Vec2(3.0, 0.0)), OccupancyGrid::kFree);
  EXPECT_EQ(g.valueAt(Vec2(3.0, 0.9)), OccupancyGrid::kUnknown);

  // Free space without a wall (an original whose map segment is not shown) stays free.
  const OccupancyGrid no_wall = buildOccupancyGrid({}, {{Vec2(0.0, 0.0), kWall}}, handParams());
  EXPECT_EQ(no_wall.count(OccupancyGrid::kOccupied), 0u);
  // The wall column adds its centres inside |y| <= 1.95 / 2: ±0.15, ±0.45, ±0.75.
  EXPECT_EQ(no_wall.count(OccupancyGrid::kFree), 18u + 6u);
  EXPECT_EQ(no_wall.valueAt(Vec2(2.0, 0.0)), OccupancyGrid::kFree);
}

TEST(OccupancyGrid, SightingsArePlacedByTheLaserPose)
{
  // Laser at (1, 1) facing +y: the local segment x = 2, y in [-1, 1] is the world wall y = 3,
  // x from 2 down to 0.
  const std::vector<KeyframeInfo> keyframes = {{7, 0.0, Pose2(1.0, 1.0, linemap::kPi / 2), Pose2()}};
  const std::vector<Sighting> s = sightingsOf(keyframes, {{7, kWall}});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(s[0].viewpoint.x(), 1.0, 1e-12);
  EXPECT_NEAR(s[0].viewpoint.y(), 1.0, 1e-12);
  EXPECT_NEAR(s[0].seen.start.x(), 2.0, 1e-12);
  EXPECT_NEAR(s[0].seen.start.y(), 3.0, 1e-12);
  EXPECT_NEAR(s[0].seen.end.x(), 0.0, 1e-12);
  EXPECT_NEAR(s[0].seen.end.y(), 3.0, 1e-12);

  OccupancyGridParams p;
  p.resolution = 0.1;
  const OccupancyGrid g = buildOccupancyGrid({s[0].seen}, s, p);
  EXPECT_EQ(g.valueAt(Vec2(1.0, 2.0)), OccupancyGrid::kFree);
  EXPECT_EQ(g.valueAt(s[0].seen.midpoint()), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.valueAt(Vec2(1.0, 3.2)), OccupancyGrid::kUnknown);
  EXPECT_EQ(g.valueAt(Vec2(3.0, 2.0)), OccupancyGrid::kUnknown);

  EXPECT_THROW(sightingsOf(keyframes, {{8, kWall}}), std::invalid_argument);
}

TEST(OccupancyGrid, DiagonalWallIsFourConnected)
{
  // Through the cell corners from (0.05, 0.05) to (0.95, 0.95) at 0.1 m: the 10 diagonal cells plus
  // one cell for each of the 9 corners (no diagonal gap a planner could slip through).
  OccupancyGridParams p;
  p.resolution = 0.1;
  p.margin = 0.0;
  const OccupancyGrid g = buildOccupancyGrid({Segment2(Vec2(0.05, 0.05), Vec2(0.95, 0.95))}, {}, p);
  ASSERT_EQ(g.width, 10);
  ASSERT_EQ(g.height, 10);
  EXPECT_EQ(g.count(OccupancyGrid::kOccupied), 19u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(g.at(i, i), OccupancyGrid::kOccupied) << i;
  for (int i = 0; i + 1 < 10; ++i)
    EXPECT_TRUE(g.at(i + 1, i) == OccupancyGrid::kOccupied || g.at(i, i + 1) == OccupancyGrid::kOccupied)
        << i;
  EXPECT_EQ(g.count(OccupancyGrid::kFree), 0u);

  // A shallow wall: one cell per column and per row crossed, 0.05 + 0.9 m over 0.1 m cells.
  const OccupancyGrid shallow = buildOccupancyGrid({Segment2(Vec2(0.05, 0.02), Vec2(0.95, 0.28))}, {}, p);
  EXPECT_EQ(shallow.count(OccupancyGrid::kOccupied), 10u + 2u);
}

TEST(OccupancyGrid, FromCaeRlsmWithheldSegmentsGiveFreeSpaceOnly)
{
  CaeRlsm cae;
  line_map_merging::Keyframe k;
  k.index = 0;
  k.pose = Pose2(0.0, 0.0, 0.0);
  k.segments = {kWall, Segment2(Vec2(1.0, 2.0), Vec2(1.3, 2.0))};  // the 0.3 m piece is seen once: withheld
  cae.addKeyframe(k);
  ASSERT_EQ(cae.map().size(), 1u);

  OccupancyGridParams p;
  p.resolution = 0.05;
  const OccupancyGrid g = buildOccupancyGrid(cae, p);
  EXPECT_EQ(g.valueAt(Vec2(1.0, 0.0)), OccupancyGrid::kFree);
  EXPECT_EQ(g.valueAt(Vec2(1.15, 1.9)), OccupancyGrid::kFree);  // in front of the withheld piece
  EXPECT_NE(g.valueAt(Vec2(1.15, 2.0)), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.valueAt(Vec2(1.15, 2.1)), OccupancyGrid::kUnknown);
  // The wall is 2 m at 0.05 m: one column, 40 rows plus the one or two its ends touch.
  const Segment2 wall = cae.map()[0].segment;
  EXPECT_NEAR(wall.start.x(), 2.0, 1e-9);
  EXPECT_NEAR(wall.end.x(), 2.0, 1e-9);
  for (double t = 0.0; t <= 1.0; t += 0.01)
    EXPECT_EQ(g.valueAt(wall.start + t * (wall.end - wall.start)), OccupancyGrid::kOccupied) << t;
  EXPECT_GE(g.count(OccupancyGrid::kOccupied), 40u);
  EXPECT_LE(g.count(OccupancyGrid::kOccupied), 42u);
}

TEST(OccupancyGrid, EmptyInputAndBadParameters)
{
  const OccupancyGrid empty = buildOccupancyGrid(std::vector<Segment2>{}, {});
  EXPECT_EQ(empty.width, 0);
  EXPECT_TRUE(empty.cells.empty());

  OccupancyGridParams p;
  p.resolution = 0.0;
  EXPECT_THROW(buildOccupancyGrid({kWall}, {}, p), std::invalid_argument);
  p.resolution = std::nan("");
  EXPECT_THROW(buildOccupancyGrid({kWall}, {}, p), std::invalid_argument);
  p = OccupancyGridParams();
  p.margin = -1.0;
  EXPECT_THROW(buildOccupancyGrid({kWall}, {}, p), std::invalid_argument);
  // A corrupt far coordinate: refused rather than allocated.
  p = OccupancyGridParams();
  EXPECT_THROW(buildOccupancyGrid({Segment2(Vec2(0, 0), Vec2(1e7, 1e7))}, {}, p), std::invalid_argument);
  // Non-finite input is skipped.
  const double nan = std::nan("");
  const OccupancyGrid g = buildOccupancyGrid({kWall, Segment2(Vec2(nan, 0), Vec2(1, 1))}, {}, handParams());
  EXPECT_EQ(g.count(OccupancyGrid::kOccupied), 8u);
}
