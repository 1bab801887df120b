// Curved walls: the arc primitive's chords (hand-computed), their mitred faces, the curves of the
// ground truth (sights, seen parts, joints that are no wall ends) and bad arc entries.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "eval_test_helpers.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_eval/simulation/wall_faces.hpp"

namespace
{
using namespace line_map_eval;
using linemap::kPi;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

constexpr double kDeg = kPi / 180.0;

/// A quarter circle of radius 2 around the origin, counter-clockwise from (2, 0) to (0, 2).
const Arc kQuarter{Vec2(0, 0), 2.0, 0.0, 90.0 * kDeg};

std::string worldError(const std::string& text)
{
  try
  {
    parseWorld(text, "arcs.yaml");
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

const char* kPath = "path:\n  waypoints: [[1, 1], [3, 1], [3, 3]]\n";
}  // namespace

TEST(ArcPieces, FewestEqualChordsWithinTheSagittaBound)
{
  // Bound 2 cm on radius 2: the step may be at most 2 acos(1 - 0.02 / 2) = 16.22 deg, so a 90 deg
  // sweep takes ceil(90 / 16.22) = 6 chords of 15 deg (5 chords of 18 deg would bulge 2.46 cm).
  const auto pieces = arcPieces(kQuarter, 0.0, 0.02, 3);
  ASSERT_EQ(pieces.size(), 6u);
  const double chord = 2.0 * 2.0 * std::sin(7.5 * kDeg);      // 0.52210 m
  const double sagitta = 2.0 * (1.0 - std::cos(7.5 * kDeg));  // 0.01711 m
  EXPECT_NEAR(chord, 0.522105, 1e-6);
  EXPECT_NEAR(sagitta, 0.017110, 1e-6);
  for (std::size_t k = 0; k < pieces.size(); ++k)
  {
    const Segment2& s = pieces[k].segment;
    EXPECT_EQ(pieces[k].arc, 3);
    EXPECT_EQ(pieces[k].thickness, 0.0);
    // Both ends on the circle, at 15 k and 15 (k + 1) degrees.
    const double a0 = 15.0 * kDeg * double(k), a1 = 15.0 * kDeg * double(k + 1);
    EXPECT_NEAR((s.start - 2.0 * Vec2(std::cos(a0), std::sin(a0))).norm(), 0.0, 1e-12) << k;
    EXPECT_NEAR((s.end - 2.0 * Vec2(std::cos(a1), std::sin(a1))).norm(), 0.0, 1e-12) << k;
    EXPECT_NEAR(s.length(), chord, 1e-12) << k;
    // The arc bulges from the chord by the sagitta, at the chord's middle, within the bound.
    EXPECT_NEAR(2.0 - s.midpoint().norm(), sagitta, 1e-12) << k;
    EXPECT_LE(2.0 - s.midpoint().norm(), 0.02);
    if (k > 0)
    {
      EXPECT_EQ(s.start, pieces[k - 1].segment.end) << "shared vertex " << k;
    }
  }
  EXPECT_EQ(pieces.front().segment.start, Vec2(2, 0));

  // Clockwise (end < start): the same circle walked the other way.
  const auto back = arcPieces({Vec2(0, 0), 2.0, 90.0 * kDeg, 0.0}, 0.0, 0.02, 0);
  ASSERT_EQ(back.size(), 6u);
  EXPECT_NEAR((back.front().segment.start - Vec2(0, 2)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((back.back().segment.end - Vec2(2, 0)).norm(), 0.0, 1e-12);
}

TEST(ArcPieces, AtLeastOneChordPer45DegreesAndClosedCircles)
{
  // A loose bound on a small radius would allow 120 deg steps: 45 deg is the most.
  EXPECT_EQ(arcPieces({Vec2(0, 0), 1.0, 0.0, 90.0 * kDeg}, 0.0, 0.5, 0).size(), 2u);
  EXPECT_EQ(arcPieces({Vec2(0, 0), 1.0, 0.0, 90.0 * kDeg}, 0.0, 5.0, 0).size(), 2u);
  // Radius 1, bound 5 mm: step <= 2 acos(0.995) = 11.46 deg, 360 / 11.46 = 31.4 -> 32 chords.
  const auto circle = arcPieces({Vec2(1, 2), 1.0, 0.0, 360.0 * kDeg}, 0.1, 0.005, 0);
  ASSERT_EQ(circle.size(), 32u);
  EXPECT_EQ(circle.back().segment.end, circle.front().segment.start);  // closed exactly
}

TEST(ArcPieces, BadArcsAreRefused)
{
  EXPECT_THROW(arcPieces({Vec2(0, 0), -1.0, 0.0, 1.0}, 0.0, 0.005, 0), std::invalid_argument);
  EXPECT_THROW(arcPieces({Vec2(0, 0), 1.0, 0.5, 0.5}, 0.0, 0.005, 0), std::invalid_argument);
  EXPECT_THROW(arcPieces({Vec2(0, 0), 1.0, 0.0, 7.0}, 0.0, 0.005, 0), std::invalid_argument);
  EXPECT_THROW(arcPieces(kQuarter, 0.0, 0.0, 0), std::invalid_argument);
}

TEST(ArcFaces, ThickArcHasTwoPolylinesMitredAtTheJoints)
{
  // 20 cm thick: the chords' solids meet on the radii of the joints, where the sides offset by
  // 0.1 m from a chord (which lies 2 cos 7.5 deg from the centre) cross: radius 2 -+ 0.1 / cos 7.5 deg.
  const auto walls = arcPieces(kQuarter, 0.2, 0.02, 0);
  const auto faces = wallFaces(walls);
  // 6 inner, 6 outer faces and the two end caps; no cap at a joint.
  ASSERT_EQ(faces.size(), 14u);
  const double inner = 2.0 - 0.1 / std::cos(7.5 * kDeg), outer = 2.0 + 0.1 / std::cos(7.5 * kDeg);
  const auto curves = curveFaces(walls, faces);
  ASSERT_EQ(curves.size(), 2u);
  for (std::size_t c = 0; c < 2; ++c)
  {
    ASSERT_EQ(curves[c].size(), 6u);
    for (std::size_t k = 1; k < curves[c].size(); ++k)
    {
      // Consecutive faces share their corner exactly, on the joint's radius at 15 k degrees.
      const Segment2& a = faces[curves[c][k - 1]].segment;
      const Segment2& b = faces[curves[c][k]].segment;
      const Vec2 corner = a.end == b.start ? a.end : a.start;
      EXPECT_TRUE(a.end == b.start || a.start == b.end) << "curve " << c << " face " << k;
      EXPECT_NEAR(corner.norm(), c == 0 ? inner : outer, 1e-12) << "curve " << c << " face " << k;
      EXPECT_NEAR(std::atan2(corner.y(), corner.x()), 15.0 * kDeg * double(k), 1e-12);
    }
  }
  // The left side of a counter-clockwise arc faces its centre: a ray from the centre along the
  // middle of the first chord stops on it, 2 cos 7.5 deg - 0.1 m away; along a joint, at the corner.
  const auto segments = faceSegments(faces);
  EXPECT_NEAR(castRay(segments, Vec2(0, 0), 7.5 * kDeg).range, 2.0 * std::cos(7.5 * kDeg) - 0.1, 1e-12);
  EXPECT_NEAR(castRay(segments, Vec2(0, 0), 30.0 * kDeg).range, inner, 1e-12);
  // From outside, the outer side: from (5, 0) towards the centre the first chord's outer face.
  const RayHit far = castRay(segments, Vec2(5, 5), -135.0 * kDeg);
  EXPECT_NEAR(far.range, 5.0 * std::sqrt(2.0) - outer, 1e-12);  // through the joint at 45 deg
}

TEST(ArcFaces, ArcContinuingAStraightWallJoinsIt)
{
  // A 10 cm wall along y = 0 up to the origin, continued by a quarter circle of radius 2 around
  // (0, 2) rising to (2, 2). Seen from the centre, every beam stops on the wall's face y = 0.05 or
  // on the arc's inner side, between the chords' middles (2 cos 7.5 deg - 0.05 from the centre)
  // and their joints (2 - 0.05 / cos 7.5 deg): no gap at the junction, no spike of a solid.
  std::vector<Wall> walls{{Segment2(Vec2(-3, 0), Vec2(0, 0)), 0.1, -1}};
  const auto arc = arcPieces({Vec2(0, 2), 2.0, -90.0 * kDeg, 0.0}, 0.1, 0.02, 0);
  ASSERT_EQ(arc.size(), 6u);
  walls.insert(walls.end(), arc.begin(), arc.end());
  const auto segments = faceSegments(wallFaces(walls));
  for (double a = -135.0; a <= -5.0; a += 0.25)
  {
    const double range = castRay(segments, Vec2(0, 2), a * kDeg).range;
    if (a <= -95.0)
      EXPECT_NEAR(range, 1.95 / std::abs(std::sin(a * kDeg)), 1e-9) << a << " deg";
    else
    {
      EXPECT_GE(range, 2.0 * std::cos(7.5 * kDeg) - 0.05 - 1e-9) << a << " deg";
      EXPECT_LE(range, a < -90.0 ? 1.96 : 2.0 - 0.05 / std::cos(7.5 * kDeg) + 1e-9) << a << " deg";
    }
  }
}

TEST(Curves, SightsJoinConsecutiveFacesOfACurve)
{
  // Faces 0-3: a polyline bending slightly, one curve; face 4 a straight wall elsewhere.
  const std::vector<Segment2> faces{Segment2(Vec2(0, 0), Vec2(1, 0)), Segment2(Vec2(1, 0), Vec2(2, 0.05)),
                                    Segment2(Vec2(2, 0.05), Vec2(3, 0.15)),
                                    Segment2(Vec2(3, 0.15), Vec2(4, 0.3)), Segment2(Vec2(0, 5), Vec2(4, 5))};
  const std::vector<std::vector<std::size_t>> curves{{0, 1, 2, 3}};
  const auto piece = [&](std::size_t w) { return VisibleWall{w, faces[w], 3, {}}; };
  // Faces 0, 1 and 3 visible (2 hidden): the runs {0, 1} and {3}; face 4 alone.
  const auto groups = sights(faces, {piece(0), piece(1), piece(3), piece(4)}, curves);
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0], (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(groups[1], (std::vector<std::size_t>{2}));
  EXPECT_EQ(groups[2], (std::vector<std::size_t>{3}));
  // Without the curve every piece is a sight of its own.
  EXPECT_EQ(sights(faces, {piece(0), piece(1), piece(3)}, {}).size(), 3u);

  // A closed curve (a square ring of faces): the last and first faces are consecutive.
  const std::vector<Segment2> ring{Segment2(Vec2(0, 0), Vec2(1, 0)), Segment2(Vec2(1, 0), Vec2(1, 1)),
                                   Segment2(Vec2(1, 1), Vec2(0, 1)), Segment2(Vec2(0, 1), Vec2(0, 0))};
  const auto seam =
      sights(ring, {VisibleWall{0, ring[0], 3, {}}, VisibleWall{3, ring[3], 3, {}}}, {{0, 1, 2, 3}});
  ASSERT_EQ(seam.size(), 1u);
  EXPECT_EQ(seam[0].size(), 2u);
  EXPECT_THROW(sights(ring, {}, {{0, 9}}), std::invalid_argument);
}

TEST(Curves, ACurveIsSeenAsAWholeAndItsJointsAreNoWallEnds)
{
  // Two chords of 1 m bending by 2.9 deg, each glimpsed over 0.5 m by 6 beams in one scan: alone
  // neither is a sight (0.6 m, 10 beams), together they are (1.0 m, 12 beams).
  GroundTruth truth;
  truth.walls = {Segment2(Vec2(0, 0), Vec2(1, 0)), Segment2(Vec2(1, 0), Vec2(2, 0.05))};
  TruthScan scan;
  scan.visible = {VisibleWall{0, Segment2(Vec2(0.5, 0), Vec2(1, 0)), 6, {}},
                  VisibleWall{1, Segment2(Vec2(1, 0), Vec2(1.5, 0.025)), 6, {}}};
  truth.scans = {scan};
  EXPECT_TRUE(seenParts(truth, 0.6, 10)[0].empty());
  truth.curves = {{0, 1}};
  const SeenParts seen = seenParts(truth, 0.6, 10);
  ASSERT_EQ(seen[0].size(), 1u);
  EXPECT_NEAR(seen[0][0].first, 0.5, 1e-12);
  EXPECT_NEAR(seen[0][0].second, 1.0, 1e-12);
  ASSERT_EQ(seen[1].size(), 1u);
  EXPECT_NEAR(seen[1][0].second - seen[1][0].first, 0.5 * std::hypot(1.0, 0.05), 1e-12);

  // One map segment along both chords, ending 2.5 cm from the curve's true end (2, 0.05). As a
  // curve, the joint (1, 0) is no wall end: the largest endpoint error is the true end's 2.5 cm.
  // As two walls, the joint is an end 1 m from the nearest map endpoint.
  GroundTruthParams params;
  const std::vector<Segment2> map{Segment2(Vec2(0, 0), Vec2(2, 0.025))};
  SeenParts all(2);
  all[0] = {{0.0, 1.0}};
  all[1] = {{0.0, truth.walls[1].length()}};
  const GroundTruthResult curve = evaluateAgainstGroundTruth(truth.walls, all, map, params, truth.curves);
  EXPECT_NEAR(curve.max_endpoint_error, 0.025, 1e-12);
  EXPECT_EQ(curve.walls[0].seen_endpoints + curve.walls[1].seen_endpoints, 2u);
  const GroundTruthResult walls = evaluateAgainstGroundTruth(truth.walls, all, map, params);
  EXPECT_NEAR(walls.max_endpoint_error, 1.0, 1e-12);
  EXPECT_EQ(walls.walls[0].seen_endpoints + walls.walls[1].seen_endpoints, 4u);
  // The coverage does not depend on it.
  EXPECT_DOUBLE_EQ(curve.coverage, walls.coverage);
}

TEST(Curves, VisiblePiecesOfACurveCountTogether)
{
  // Two chords seen by 3 beams each from the origin, min_beams 5: listed only as a curve.
  const std::vector<Segment2> faces{Segment2(Vec2(1, -1), Vec2(1, 0)), Segment2(Vec2(1, 0), Vec2(0.95, 1))};
  const std::vector<int> hit{0, 0, 0, 1, 1, 1};
  std::vector<double> range;
  const double inc = 15.0 * kDeg, a0 = -37.5 * kDeg;
  for (std::size_t i = 0; i < hit.size(); ++i)
  {
    const double a = a0 + double(i) * inc;
    range.push_back(castRay(faces, Vec2(0, 0), a).range);
  }
  EXPECT_TRUE(visibleWallPieces(faces, Pose2(0, 0, 0), a0, inc, hit, range, 5).empty());
  const auto listed = visibleWallPieces(faces, Pose2(0, 0, 0), a0, inc, hit, range, 5, {{0, 1}});
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[0].beams + listed[1].beams, 6u);
}

TEST(WorldArcs, ArcEntriesExpandAndBadOnesAreNamed)
{
  const World w =
      parseWorld(std::string("arc_sagitta: 0.02\nwalls:\n  - [5, 0, 5, 4]\n  - {arc: [0, 0, 2, 180, 270], "
                             "thickness: 0.2}\n  - {arc: [10, 10, 1, 0, 360], thickness: 0}\n") +
                     kPath,
                 "arcs.yaml");
  // 1 straight wall, 6 chords of the quarter circle, ceil(360 deg / (2 acos(0.98))) = 16 of the circle.
  ASSERT_EQ(w.walls.size(), 1u + 6u + 16u);
  EXPECT_EQ(w.walls[0].arc, -1);
  EXPECT_EQ(w.walls[1].arc, 0);
  EXPECT_EQ(w.walls[1].thickness, 0.2);
  EXPECT_EQ(w.walls[7].arc, 1);
  EXPECT_EQ(w.walls[7].thickness, 0.0);
  EXPECT_EQ(w.arc_sagitta, 0.02);

  using line_map_eval::test_helpers::expectMentions;
  expectMentions(worldError(std::string("walls:\n  - {arc: [0, 0, -2, 0, 90]}\n") + kPath),
                 {"arcs.yaml: walls[0]/arc: the radius must be > 0, got -2", "line 2"});
  expectMentions(worldError(std::string("walls:\n  - {arc: [0, 0, 2, 30, 30]}\n") + kPath),
                 {"walls[0]/arc: the arc has zero sweep"});
  expectMentions(worldError(std::string("walls:\n  - {arc: [0, 0, 2, 0, 400]}\n") + kPath), {"walls[0]/arc"});
  expectMentions(worldError(std::string("walls:\n  - {arc: [0, 0, 2, 90]}\n") + kPath),
                 {"walls[0]/arc: expected 5 numbers"});
  expectMentions(worldError(std::string("walls:\n  - {thickness: 0.2}\n") + kPath),
                 {"walls[0]/segment: missing key"});
  expectMentions(
      worldError(std::string("walls:\n  - {segment: [0, 0, 1, 0], arc: [0, 0, 2, 0, 90]}\n") + kPath),
      {"walls[0]: give either segment or arc"});
  expectMentions(worldError(std::string("arc_sagitta: 0\nwalls: [[0, 0, 4, 0]]\n") + kPath),
                 {"arc_sagitta: must be > 0"});
  // The path keeps its clearance from the chords too: the leg (1, 1) - (3, 1) runs 1.7 m from the
  // centre of a circle of radius 1.5, 0.15 m from its 10 cm wall's surface (path/clearance 0.2 m).
  expectMentions(worldError(std::string("walls:\n  - {arc: [2, 2.7, 1.5, 0, 360]}\n") + kPath),
                 {"path/waypoints[0]"});
}

TEST(WorldArcs, TruthFileKeepsArcsAndCurves)
{
  World w = parseWorld(std::string("walls:\n  - {arc: [2, 4, 1.5, 180, 360], thickness: 0.1}\n") +
                           "path:\n  waypoints: [[1, 1], [3, 1], [3, 2]]\n  scans: 5\n",
                       "arc_truth.yaml");
  const SimulationResult sim = simulate(w);
  ASSERT_EQ(sim.truth.curves.size(), 2u);
  const std::string path = ::testing::TempDir() + "/" + std::to_string(::getpid()) + "_arc.truth.yaml";
  writeGroundTruth(sim.truth, path);
  const GroundTruth back = readGroundTruth(path);
  std::remove(path.c_str());
  EXPECT_EQ(back.curves, sim.truth.curves);
  ASSERT_EQ(back.solids.size(), sim.truth.solids.size());
  for (std::size_t i = 0; i < back.solids.size(); ++i) EXPECT_EQ(back.solids[i].arc, 0);
  // The faces of the solids read back are the true lines written.
  const auto faces = faceSegments(wallFaces(back.solids));
  ASSERT_EQ(faces.size(), back.walls.size());
  for (std::size_t i = 0; i < faces.size(); ++i)
  {
    EXPECT_EQ(faces[i].start, back.walls[i].start);
    EXPECT_EQ(faces[i].end, back.walls[i].end);
  }
}
