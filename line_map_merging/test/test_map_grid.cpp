// The live map's grid: its input matches buildOccupancyGrid(const CaeRlsm&) cell for cell (withheld
// segments' free space included), a merger without provenance gives walls in unknown space, the
// newest keyframe stamps the grid; and the schedule publishes after a change, only while subscribed,
// at most once per period, and catches up when the first subscriber comes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "line_map_merging/map/map_grid.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

using line_map_merging::buildOccupancyGrid;
using line_map_merging::GridInput;
using line_map_merging::gridInputOf;
using line_map_merging::GridSchedule;
using line_map_merging::Keyframe;
using line_map_merging::OccupancyGrid;
using line_map_merging::OccupancyGridParams;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
// Two keyframes in a 4 m wide corridor along x; the second also glimpses a 0.3 m piece once (withheld
// by CAE-RLSM's single-view rule).
Keyframe corridorKeyframe(std::uint64_t index, double x, double stamp, bool glimpse)
{
  Keyframe k;
  k.index = index;
  k.stamp = stamp;
  k.pose = Pose2(x, 0.0, 0.0);
  // In the laser frame; free side on the left (the laser sees both walls from between them).
  k.segments = {Segment2(Vec2(-1.0 - x, -2.0), Vec2(5.0 - x, -2.0)),
                Segment2(Vec2(5.0 - x, 2.0), Vec2(-1.0 - x, 2.0))};
  if (glimpse) k.segments.push_back(Segment2(Vec2(6.3 - x, 1.0), Vec2(6.0 - x, 1.0)));
  return k;
}

OccupancyGridParams params()
{
  OccupancyGridParams p;
  p.resolution = 0.05;
  return p;
}
}  // namespace

TEST(MapGrid, CaeInputMatchesTheCaeGridCellForCell)
{
  line_map_merging::CaeRlsm cae;
  cae.addKeyframe(corridorKeyframe(0, 0.0, 10.0, false));
  cae.addKeyframe(corridorKeyframe(1, 1.0, 12.5, true));
  ASSERT_EQ(cae.map().size(), 2u);  // the glimpse is withheld

  const GridInput input = gridInputOf(cae);
  EXPECT_EQ(input.walls.size(), 2u);
  EXPECT_EQ(input.sightings.size(), 5u);  // the withheld glimpse's original included
  EXPECT_DOUBLE_EQ(input.newest_stamp, 12.5);
  const OccupancyGrid mine = buildOccupancyGrid(input, params());
  const OccupancyGrid reference = buildOccupancyGrid(cae, params());
  EXPECT_EQ(mine.width, reference.width);
  EXPECT_EQ(mine.height, reference.height);
  EXPECT_EQ(mine.origin, reference.origin);
  EXPECT_EQ(mine.cells, reference.cells);
  // Free between the walls and in front of the glimpse; the glimpse is no wall.
  EXPECT_EQ(mine.valueAt(Vec2(2.0, 1.0)), OccupancyGrid::kFree);
  EXPECT_EQ(mine.valueAt(Vec2(2.0, -1.0)), OccupancyGrid::kFree);
  EXPECT_EQ(mine.valueAt(Vec2(4.77, 0.72)), OccupancyGrid::kFree);  // only the glimpse's triangle covers it
  EXPECT_NE(mine.valueAt(Vec2(6.15, 1.0)), OccupancyGrid::kOccupied);
  EXPECT_EQ(mine.valueAt(Vec2(2.0, 2.0)), OccupancyGrid::kOccupied);
  EXPECT_EQ(mine.valueAt(Vec2(2.0, -2.0)), OccupancyGrid::kOccupied);
}

TEST(MapGrid, WithoutProvenanceWallsInUnknownSpace)
{
  const auto oto = line_map_merging::makeMerger("oto", linemap::ParamSet());
  ASSERT_FALSE(oto->hasProvenance());
  oto->addKeyframe(corridorKeyframe(0, 0.0, 3.0, false));
  oto->addKeyframe(corridorKeyframe(1, 1.0, 4.0, false));
  const GridInput input = gridInputOf(*oto);
  EXPECT_EQ(input.walls.size(), oto->map().size());
  EXPECT_TRUE(input.sightings.empty());
  EXPECT_DOUBLE_EQ(input.newest_stamp, 4.0);
  const OccupancyGrid g = buildOccupancyGrid(input, params());
  EXPECT_EQ(g.count(OccupancyGrid::kFree), 0u);
  // Two walls of 6 m at 0.05 m: 120 cells each, plus the one their far ends may touch.
  EXPECT_GE(g.count(OccupancyGrid::kOccupied), 240u);
  EXPECT_LE(g.count(OccupancyGrid::kOccupied), 242u);
  EXPECT_EQ(g.valueAt(Vec2(2.0, 2.0)), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.valueAt(Vec2(2.0, 1.0)), OccupancyGrid::kUnknown);
}

TEST(MapGrid, EmptyMapHasNoStampAndAnEmptyGrid)
{
  line_map_merging::CaeRlsm cae;
  const GridInput input = gridInputOf(cae);
  EXPECT_TRUE(input.walls.empty());
  EXPECT_EQ(input.newest_stamp, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(buildOccupancyGrid(input, params()).width, 0);
}

TEST(MapGrid, ScheduleAfterChangeWhileSubscribedAtBoundedRate)
{
  GridSchedule s(2.0);
  // The first grid: at once, but only for a subscriber.
  EXPECT_FALSE(s.due(100.0, false));
  EXPECT_TRUE(s.due(100.0, true));
  s.started(100.0);
  EXPECT_FALSE(s.due(100.1, true));  // nothing changed
  s.mapChanged();
  EXPECT_FALSE(s.due(101.9, true));  // within the period
  EXPECT_TRUE(s.due(102.0, true));
  s.started(102.0);
  // Changes while nobody listens wait; the first subscriber then gets the map at once (the period
  // since the last grid has passed), and again only one grid for many changes.
  for (int i = 0; i < 50; ++i) s.mapChanged();
  EXPECT_FALSE(s.due(150.0, false));
  EXPECT_TRUE(s.stale());
  EXPECT_TRUE(s.due(150.0, true));
  s.started(150.0);
  EXPECT_FALSE(s.due(160.0, true));
  // A change while a grid is being made (after started) makes the next one due.
  s.mapChanged();
  EXPECT_TRUE(s.due(160.0, true));
  // A clock that went back does not hold the grids up.
  s.started(160.0);
  s.mapChanged();
  EXPECT_TRUE(s.due(10.0, true));
}

TEST(MapGrid, ScheduleZeroPeriodAndBadPeriods)
{
  GridSchedule s(0.0);
  s.started(5.0);
  s.mapChanged();
  EXPECT_TRUE(s.due(5.0, true));
  EXPECT_THROW(GridSchedule(-1.0), std::invalid_argument);
  EXPECT_THROW(GridSchedule(std::nan("")), std::invalid_argument);
  EXPECT_THROW(GridSchedule(std::numeric_limits<double>::infinity()), std::invalid_argument);
}
