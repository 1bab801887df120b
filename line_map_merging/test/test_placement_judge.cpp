// The placement judge against a saved map whose free space is known: a place where part of the way runs out
// of the map explains less of it than a look-alike place inside the map, which puts some of the way's points
// where the map's scans saw free space. Hand-built: two copies of one room 20 m apart; only beside the second
// copy did the map see a wall to the west (which the way also saw) and the open space to the north (where the
// way saw a piece of wall). The truth is the first copy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "line_map_merging/localization/placement_judge.hpp"

using namespace line_map_merging;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kSpacing = 0.1;  // [m] between the way's points

/// The room, its west side open, its north wall shorter than its south wall (it looks like itself only
/// unturned). Each wall's free (left) side faces the room's middle, where it was seen from.
std::vector<Segment2> room(const Vec2& at)
{
  return {Segment2(at + Vec2(0.0, 0.0), at + Vec2(8.0, 0.0)),
          Segment2(at + Vec2(8.0, 0.0), at + Vec2(8.0, 4.0)),
          Segment2(at + Vec2(8.0, 4.0), at + Vec2(5.0, 4.0))};
}

struct Scene
{
  std::vector<Segment2> map;
  std::vector<Sighting> sightings;
  Pose2 truth, look_alike;
};

Scene scene()
{
  Scene s;
  s.truth = Pose2(4.0, 2.0, 0.0);  // the robot's frame at its laser, in the room's middle
  s.look_alike = Pose2(24.0, 2.0, 0.0);
  const Vec2 second(20.0, 0.0);
  for (const Segment2& w : room(Vec2(0.0, 0.0))) s.sightings.push_back({Vec2(4.0, 2.0), w});
  for (const Segment2& w : room(second)) s.sightings.push_back({second + Vec2(4.0, 2.0), w});
  s.sightings.push_back({Vec2(19.0, 2.0), Segment2(Vec2(18.0, 3.0), Vec2(18.0, 1.0))});  // west of the copy
  s.sightings.push_back({Vec2(22.5, 4.5), Segment2(Vec2(25.0, 9.0), Vec2(20.0, 9.0))});  // north, open
  for (const Sighting& sighting : s.sightings) s.map.push_back(sighting.seen);
  return s;
}

Segment2 northWall(double length)
{
  return Segment2(Vec2(2.5 + 0.5 * length, 7.0), Vec2(2.5 - 0.5 * length, 7.0));
}

/// How many of the way's points (the robot's frame at `truth`) lie on its north wall.
std::size_t northPoints(const std::vector<Vec2>& points, const Pose2& truth)
{
  return static_cast<std::size_t>(
      std::count_if(points.begin(), points.end(), [&](const Vec2& p) { return truth.apply(p).y() > 6.9; }));
}

/// The way: one sight from the room's middle (the robot's frame) of its walls, 2 m of wall 2 m west of the
/// room and `north` m of wall 3 m north of it (in the map's free space at the look-alike, unknown at the
/// truth), the space in front of each seen free.
Way way(const Pose2& truth, double north)
{
  std::vector<Segment2> seen = room(Vec2(0.0, 0.0));
  seen.emplace_back(Vec2(-2.0, 3.0), Vec2(-2.0, 1.0));
  if (north > 0.0) seen.push_back(northWall(north));
  for (Segment2& s : seen) s = s.transformed(truth.inverse());
  Way w;
  w.add(segmentSight(Pose2(), seen, kSpacing));
  return w;
}

bool near(const Pose2& a, const Pose2& b)
{
  const Pose2 d = a.inverse() * b;
  return std::hypot(d.x, d.y) < 0.1 && std::fabs(d.theta) < 0.02;
}
}  // namespace

// At the look-alike the way's west wall fits too, so it explains a tenth more than the truth; but the points
// of 1.5 m of its north wall (16 or 17 at the spacing) lie where the map saw free space, against none at the
// truth: the judge places the robot at the truth, held by tracking at the look-alike or not.
TEST(PlacementJudge, AFitInsideTheMapYieldsToOneWhereTheWayRunsOutOfItWhenItsPointsLieInFreeSpace)
{
  const Scene s = scene();
  PlacementJudge judge(s.map, LocalizerParams());
  judge.setMapFreeSpace(s.sightings);
  const Way w = way(s.truth, 1.5);
  const std::vector<Vec2> points = w.points();
  ASSERT_EQ(judge.pointsInFreeSpace(points, s.truth), 0u);
  ASSERT_EQ(judge.pointsInFreeSpace(points, s.look_alike), northPoints(points, s.truth));
  ASSERT_GT(judge.explained(points, s.look_alike), 1.1 * judge.explained(points, s.truth));
  for (const Pose2& held : {s.look_alike, s.truth})
  {
    const PlacementJudge::Verdict verdict = judge.judge(w, held, 10.0, 0.5, {s.truth, s.look_alike});
    std::string rivals;
    for (const Pose2& r : verdict.rivals)
      rivals +=
          " (" + std::to_string(r.x) + ", " + std::to_string(r.y) + ", " + std::to_string(r.theta) + ")";
    EXPECT_EQ(verdict.outcome, PlacementJudge::Outcome::kPlaced) << "rivals:" << rivals;
    EXPECT_TRUE(near(verdict.place, s.truth)) << verdict.place.x << " " << verdict.place.y;
  }
}

// Half a metre of the way in the look-alike's free space (6 or 7 points, below the judge's minimum evidence
// of 10) is what registration error or a passer-by leaves: that does not rule it out, and the place stays
// open.
TEST(PlacementJudge, AFewPointsInFreeSpaceLeaveTheLookAlikeOpen)
{
  const Scene s = scene();
  PlacementJudge judge(s.map, LocalizerParams());
  judge.setMapFreeSpace(s.sightings);
  const Way w = way(s.truth, 0.5);
  ASSERT_EQ(judge.pointsInFreeSpace(w.points(), s.look_alike), northPoints(w.points(), s.truth));
  ASSERT_LT(northPoints(w.points(), s.truth), 10u);
  const PlacementJudge::Verdict verdict = judge.judge(w, s.look_alike, 10.0, 0.5, {s.truth, s.look_alike});
  EXPECT_EQ(verdict.outcome, PlacementJudge::Outcome::kAmbiguous);
}
