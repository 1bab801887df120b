// Coverage, endpoint error and vertex accuracy against true faces, on hand-made cases: every face
// seen in full, and faces seen only in part (what a robot glimpses through a door).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using line_map_eval::evaluateAgainstGroundTruth;
using line_map_eval::findCorners;
using line_map_eval::GroundTruthParams;
using line_map_eval::GroundTruthResult;
using line_map_eval::SeenParts;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
GroundTruthParams defaults()
{
  GroundTruthParams p;
  p.coverage_tolerance = 0.05;
  p.sample_spacing = 0.01;
  p.association_angle = 10.0 * linemap::kPi / 180.0;
  p.association_distance = 0.2;
  p.corner_tolerance = 0.01;
  p.corner_min_angle = 20.0 * linemap::kPi / 180.0;
  p.vertex_radius = 0.3;
  return p;
}

// A: 4 m along x, B: 3 m up from A's end (corner at (4, 0)), C and D: two collinear walls far away.
const std::vector<Segment2> kWalls = {Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(4, 0), Vec2(4, 3)),
                                      Segment2(Vec2(10, 0), Vec2(12, 0)), Segment2(Vec2(12, 0), Vec2(14, 0))};
}  // namespace

TEST(GroundTruthMetrics, CornersAreWhereNonParallelWallsMeet)
{
  const std::vector<Vec2> corners = findCorners(kWalls, defaults());
  ASSERT_EQ(corners.size(), 1u);  // C meets D straight on: no corner
  EXPECT_NEAR(corners[0].x(), 4.0, 1e-12);
  EXPECT_NEAR(corners[0].y(), 0.0, 1e-12);
  // Three walls through one point are one corner.
  std::vector<Segment2> three = kWalls;
  three.push_back(Segment2(Vec2(4, 0), Vec2(6, 2)));
  EXPECT_EQ(findCorners(three, defaults()).size(), 1u);
}

TEST(GroundTruthMetrics, HandMadeCase)
{
  const std::vector<Segment2> map = {
      Segment2(Vec2(0, 0.02), Vec2(3, 0.02)),      // M1 on A, 2 cm off, stops 1 m short
      Segment2(Vec2(4.03, 0.105), Vec2(4.03, 3)),  // M2 on B, 3 cm off, starts 10.5 cm up
      Segment2(Vec2(3.5, -0.1), Vec2(3.9, -0.1)),  // M3 parallel to A, 10 cm off: covers nothing
  };
  const GroundTruthResult r = evaluateAgainstGroundTruth(kWalls, map, defaults());
  ASSERT_EQ(r.walls.size(), 4u);

  // A: samples x = 0, 0.01, ..., 4 (401); within 5 cm of M1 while x <= 3 + sqrt(0.05^2 - 0.02^2)
  // = 3.0458, i.e. x = 0 .. 3.04: 305 samples. M3 is 10 cm away everywhere.
  EXPECT_EQ(r.walls[0].associated, 2u);
  EXPECT_NEAR(r.walls[0].coverage, 305.0 / 401.0, 1e-12);
  // Start (0, 0): 2 cm to M1's start; end (4, 0): nearest is M3's end (3.9, -0.1) at 0.1 sqrt(2).
  EXPECT_NEAR(r.walls[0].endpoint_error, 0.1 * std::sqrt(2.0), 1e-12);

  // B: samples y = 0 .. 3 (301); within 5 cm of M2 when 0.105 - y <= 0.04, i.e. y >= 0.07: 294.
  EXPECT_EQ(r.walls[1].associated, 1u);
  EXPECT_NEAR(r.walls[1].coverage, 294.0 / 301.0, 1e-12);
  EXPECT_NEAR(r.walls[1].endpoint_error, std::hypot(0.03, 0.105), 1e-12);

  EXPECT_EQ(r.walls[2].associated, 0u);
  EXPECT_EQ(r.walls[2].coverage, 0.0);
  EXPECT_TRUE(std::isinf(r.walls[2].endpoint_error));
  EXPECT_EQ(r.undetected_walls, 2u);
  EXPECT_NEAR(r.max_endpoint_error, 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.coverage, (4.0 * 305.0 / 401.0 + 3.0 * 294.0 / 301.0) / 11.0, 1e-12);

  // Corner (4, 0): M2's start (0.1092 m) and M3's end (0.1414 m) lie within 0.3 m; M1's end is 1 m away.
  ASSERT_EQ(r.corners.size(), 1u);
  EXPECT_EQ(r.corners[0].endpoints, 2u);
  EXPECT_NEAR(r.corners[0].vertex_error, std::hypot(0.03, 0.105) + 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.mean_vertex_error, r.corners[0].vertex_error, 1e-12);
  EXPECT_EQ(r.missed_corners, 0u);
}

TEST(GroundTruthMetrics, PerfectMapAndEmptyMap)
{
  const std::vector<Segment2> walls(kWalls.begin(), kWalls.begin() + 2);
  const GroundTruthResult perfect = evaluateAgainstGroundTruth(walls, walls, defaults());
  EXPECT_DOUBLE_EQ(perfect.coverage, 1.0);
  EXPECT_DOUBLE_EQ(perfect.max_endpoint_error, 0.0);
  ASSERT_EQ(perfect.corners.size(), 1u);
  EXPECT_EQ(perfect.corners[0].endpoints, 2u);  // A's end and B's start, both exactly on the corner
  EXPECT_DOUBLE_EQ(perfect.corners[0].vertex_error, 0.0);

  const GroundTruthResult empty = evaluateAgainstGroundTruth(walls, {}, defaults());
  EXPECT_EQ(empty.coverage, 0.0);
  EXPECT_EQ(empty.undetected_walls, 2u);
  EXPECT_EQ(empty.missed_corners, 1u);
}

TEST(GroundTruthMetrics, BadInput)
{
  const std::vector<Segment2> zero = {Segment2(Vec2(1, 1), Vec2(1, 1))};
  EXPECT_THROW(evaluateAgainstGroundTruth(zero, {}, defaults()), std::invalid_argument);
  const std::vector<Segment2> nan = {Segment2(Vec2(0, 0), Vec2(std::nan(""), 1))};
  EXPECT_THROW(evaluateAgainstGroundTruth(kWalls, nan, defaults()), std::invalid_argument);
  linemap::ParamSet ps;
  ps.set("eval/gt_vertex_radius", "0");
  EXPECT_THROW(GroundTruthParams::fromParams(ps), linemap::ParameterError);
  ps.set("eval/gt_vertex_radius", "0.5");
  ps.set("eval/gt_association_angle_deg", "5");
  const GroundTruthParams p = GroundTruthParams::fromParams(ps);
  EXPECT_DOUBLE_EQ(p.vertex_radius, 0.5);
  EXPECT_NEAR(p.association_angle, 5.0 * linemap::kPi / 180.0, 1e-15);
}

TEST(GroundTruthMetrics, OnlyTheSeenPartsCount)
{
  // Face F: 10 m along x (free side up, +y on its left). The scans saw [2, 5] and [6, 10]; face G,
  // 3 m up from F's end, was seen in full; face H never. Map: M1 over [2, 5], M2 over [6, 9.8]
  // 2 cm off, both directed like F; M3 on F's line but directed the other way (the far face of a
  // wall drawn onto this one) and M4 along G.
  const std::vector<Segment2> faces = {Segment2(Vec2(0, 0), Vec2(10, 0)), Segment2(Vec2(10, 0), Vec2(10, 3)),
                                       Segment2(Vec2(20, 0), Vec2(25, 0))};
  const SeenParts seen = {{{2.0, 5.0}, {6.0, 10.0}}, {{0.0, 3.0}}, {}};
  const std::vector<Segment2> map = {
      Segment2(Vec2(2, 0), Vec2(5, 0)),            // M1
      Segment2(Vec2(6, 0.02), Vec2(9.8, 0.02)),    // M2
      Segment2(Vec2(5, 0), Vec2(0, 0)),            // M3: opposite direction
      Segment2(Vec2(10, 0.105), Vec2(10, 2.895)),  // M4 on G
  };
  const GroundTruthResult r = evaluateAgainstGroundTruth(faces, seen, map, defaults());
  ASSERT_EQ(r.walls.size(), 2u);  // H is not scored
  EXPECT_EQ(r.unseen_walls, 1u);
  EXPECT_EQ(r.undetected_walls, 0u);

  // F: M1 and M2 associated (directed), M3 not. Samples: [2, 5] every 1 cm, 301, all within M1;
  // [6, 10], 401, within 5 cm of M2 while x <= 9.8 + sqrt(0.05^2 - 0.02^2) = 9.8458: x = 6 .. 9.84,
  // 385. Only F's end is seen (the first seen part begins 2 m from its start): error 0.2 m to M2's
  // end, at distance hypot(0.2, 0.02).
  const auto& f = r.walls[0];
  EXPECT_EQ(f.face, 0u);
  EXPECT_EQ(f.associated, 2u);
  EXPECT_DOUBLE_EQ(f.seen_length, 7.0);
  EXPECT_NEAR(f.coverage, (301.0 + 385.0) / (301.0 + 401.0), 1e-12);
  EXPECT_EQ(f.seen_endpoints, 1u);
  EXPECT_NEAR(f.endpoint_error, std::hypot(0.2, 0.02), 1e-12);

  // G: M4 on its line, 10.5 cm short at both ends: samples y = 0.06 .. 2.94 covered, 289 of 301;
  // both ends seen: (10, 0) to M4's start 0.105 m, (10, 3) to M4's end 0.105 m.
  const auto& g = r.walls[1];
  EXPECT_EQ(g.face, 1u);
  EXPECT_NEAR(g.coverage, 289.0 / 301.0, 1e-12);
  EXPECT_EQ(g.seen_endpoints, 2u);
  EXPECT_NEAR(g.endpoint_error, 0.105, 1e-12);

  EXPECT_NEAR(r.max_endpoint_error, std::hypot(0.2, 0.02), 1e-12);
  EXPECT_NEAR(r.mean_endpoint_error, (std::hypot(0.2, 0.02) + 0.105 + 0.105) / 3.0, 1e-12);
  EXPECT_NEAR(r.coverage, (7.0 * f.coverage + 3.0 * g.coverage) / 10.0, 1e-12);

  // The corner (10, 0): F's end and G's start, both seen. Its vertices are the endpoints of the
  // segments associated with F or G within 0.3 m: M2's end (0.2010 m) and M4's start (0.105 m).
  ASSERT_EQ(r.corners.size(), 1u);
  EXPECT_EQ(r.corners[0].endpoints, 2u);
  EXPECT_NEAR(r.corners[0].vertex_error, std::hypot(0.2, 0.02) + 0.105, 1e-12);

  EXPECT_EQ(r.unmapped_ends, 0u);
  EXPECT_EQ(f.mapped_endpoints, 1u);

  // Scored over the whole faces instead, H is undetected and F's start, 2 m from M1, is seen but
  // unmapped: a gap in the coverage, not a 2 m endpoint error.
  const GroundTruthResult whole = evaluateAgainstGroundTruth(faces, map, defaults());
  EXPECT_EQ(whole.undetected_walls, 1u);
  EXPECT_EQ(whole.unmapped_ends, 1u);
  EXPECT_NEAR(whole.max_endpoint_error, std::hypot(0.2, 0.02), 1e-12);
  // Reached within vertex_radius (0.3 m) it counts: M1 extended to start 0.29 m from F's start.
  std::vector<Segment2> longer = map;
  longer[0].start = Vec2(0.29, 0);
  EXPECT_NEAR(evaluateAgainstGroundTruth(faces, longer, defaults()).max_endpoint_error, 0.29, 1e-12);

  // Undirected association takes M3 in (adding nothing: the seen [2, 5] is M1's already).
  GroundTruthParams undirected = defaults();
  undirected.directed = false;
  const GroundTruthResult u = evaluateAgainstGroundTruth(faces, seen, map, undirected);
  EXPECT_EQ(u.walls[0].associated, 3u);
  EXPECT_NEAR(u.walls[0].coverage, (301.0 + 385.0) / (301.0 + 401.0), 1e-12);  // M3 only adds [2, 5] again

  // A corner whose second face was not seen at its end is no seen corner.
  const SeenParts half = {{{6.0, 10.0}}, {{1.0, 3.0}}, {}};
  EXPECT_TRUE(evaluateAgainstGroundTruth(faces, half, map, defaults()).corners.empty());
  EXPECT_THROW(evaluateAgainstGroundTruth(faces, SeenParts(2), map, defaults()), std::invalid_argument);
}

TEST(GroundTruthMetrics, SeenPartsAreTheUnionOfLongEnoughPieces)
{
  line_map_eval::GroundTruth truth;
  truth.walls = {Segment2(Vec2(0, 0), Vec2(10, 0)), Segment2(Vec2(0, 5), Vec2(0, 0))};
  const auto piece = [](std::size_t wall, double x0, double y0, double x1, double y1) {
    return line_map_eval::VisibleWall{wall, Segment2(Vec2(x0, y0), Vec2(x1, y1)), 10, {}};
  };
  truth.scans.resize(2);
  truth.scans[0].visible = {piece(0, 1, 0, 3, 0), piece(1, 0, 4, 0, 3.7)};  // the second: 0.3 m
  truth.scans[1].visible = {piece(0, 4, 0, 2.5, 0), piece(0, 6, 0, 9, 0), piece(1, 0, 2, 0, 0)};
  const SeenParts s = line_map_eval::seenParts(truth, 0.6);
  ASSERT_EQ(s.size(), 2u);
  ASSERT_EQ(s[0].size(), 2u);  // [1, 3] and [2.5, 4] overlap: [1, 4]; then [6, 9]
  EXPECT_DOUBLE_EQ(s[0][0].first, 1.0);
  EXPECT_DOUBLE_EQ(s[0][0].second, 4.0);
  EXPECT_DOUBLE_EQ(s[0][1].first, 6.0);
  EXPECT_DOUBLE_EQ(s[0][1].second, 9.0);
  // Face 1 runs from (0, 5) down: the 0.3 m glimpse is dropped, (0, 2) -> (0, 0) is [3, 5].
  ASSERT_EQ(s[1].size(), 1u);
  EXPECT_DOUBLE_EQ(s[1][0].first, 3.0);
  EXPECT_DOUBLE_EQ(s[1][0].second, 5.0);
  EXPECT_EQ(line_map_eval::seenParts(truth, 0.0)[1].size(), 2u);  // without the minimum it stays
  // Sights need beams too: the [6, 9] piece hit by 4 beams is no sight with a minimum of 5.
  truth.scans[1].visible[1].beams = 4;
  EXPECT_EQ(line_map_eval::seenParts(truth, 0.6, 5)[0].size(), 1u);
  EXPECT_EQ(line_map_eval::seenParts(truth, 0.6, 4)[0].size(), 2u);
}

// A face 4 m long seen by scans hitting [1, 3] with 4 beams each (2 hits per metre): no single sight
// (10 beams per 0.6 m). Ten such scans give 20 hits per metre: a bin of 5 cm is dense where its
// window of 13 bins (+-6, 0.65 m) holds 10 bins inside [1, 3], i.e. from bin 23 to bin 56: [1.15, 2.85].
// Five scans give 10 per metre, 6.5 hits at most in a window: nothing.
TEST(GroundTruthMetrics, SightingsAccumulateOverScans)
{
  line_map_eval::GroundTruth truth;
  truth.walls = {Segment2(Vec2(0, 0), Vec2(4, 0))};
  const line_map_eval::VisibleWall glimpse{0, Segment2(Vec2(1, 0), Vec2(3, 0)), 4, {}};
  truth.scans.resize(10);
  for (auto& scan : truth.scans) scan.visible = {glimpse};
  EXPECT_TRUE(line_map_eval::seenParts(truth, 0.6, 10)[0].empty());
  const SeenParts ten = line_map_eval::accumulatedSeenParts(truth, 0.6, 10);
  ASSERT_EQ(ten[0].size(), 1u);
  EXPECT_NEAR(ten[0][0].first, 1.15, 0.051);
  EXPECT_NEAR(ten[0][0].second, 2.85, 0.051);
  truth.scans.resize(5);
  EXPECT_TRUE(line_map_eval::accumulatedSeenParts(truth, 0.6, 10)[0].empty());
  // The union keeps both kinds.
  const SeenParts other{{{0.0, 0.5}}};
  const SeenParts both = line_map_eval::unionOfSeenParts(other, ten);
  ASSERT_EQ(both[0].size(), 2u);
  EXPECT_DOUBLE_EQ(both[0][0].second, 0.5);
}

// Under a registration error, a face seen from 10 m is scored with 2 x hypot(0.03, 0.01 x 10) =
// 0.2088 m of slack: a segment 0.15 m off it covers it then, and not without the error.
TEST(GroundTruthMetrics, RegistrationErrorGivesSlackByRange)
{
  line_map_eval::GroundTruth truth;
  truth.walls = {Segment2(Vec2(0, 0), Vec2(4, 0))};
  truth.scans.resize(1);
  truth.scans[0].pose = linemap::Pose2(2.0, 10.0, 0.0);
  truth.scans[0].visible = {line_map_eval::VisibleWall{0, truth.walls[0], 40, {}}};
  const std::vector<Segment2> map{Segment2(Vec2(0, 0.15), Vec2(4, 0.15))};
  EXPECT_DOUBLE_EQ(line_map_eval::registrationSlack(truth, 2.0)[0], 0.0);
  EXPECT_DOUBLE_EQ(evaluateAgainstGroundTruth(truth, map, defaults()).coverage, 0.0);
  truth.registration_position = 0.03;
  truth.registration_heading = 0.01;
  EXPECT_NEAR(line_map_eval::registrationSlack(truth, 2.0)[0], 2.0 * std::hypot(0.03, 0.1), 1e-12);
  EXPECT_DOUBLE_EQ(evaluateAgainstGroundTruth(truth, map, defaults()).coverage, 1.0);
}

TEST(GroundTruthMetrics, ASegmentAcrossAPartitionBelongsToBothFaces)
{
  // Faces P (6 m) and Q (1.9 m) on the line y = 0, 10 cm apart where a partition meets the wall;
  // the map bridges them with one segment 1 cm off. Its midpoint (4, 0.01) is 2.1 m from Q, yet it
  // runs along Q: it covers both, and what it gets wrong is where they end: P's end (6, 0) and Q's
  // start (6.1, 0) are 2 and 1.9 m from the nearest map endpoint.
  const std::vector<Segment2> faces = {Segment2(Vec2(0, 0), Vec2(6, 0)), Segment2(Vec2(6.1, 0), Vec2(8, 0))};
  const std::vector<Segment2> map = {Segment2(Vec2(0, 0.01), Vec2(8, 0.01))};
  const GroundTruthResult r = evaluateAgainstGroundTruth(faces, map, defaults());
  ASSERT_EQ(r.walls.size(), 2u);
  EXPECT_EQ(r.undetected_walls, 0u);
  EXPECT_EQ(r.walls[1].associated, 1u);
  EXPECT_DOUBLE_EQ(r.walls[0].coverage, 1.0);
  EXPECT_DOUBLE_EQ(r.walls[1].coverage, 1.0);
  EXPECT_NEAR(r.walls[0].endpoint_error, std::hypot(2.0, 0.01), 1e-12);
  EXPECT_NEAR(r.walls[1].endpoint_error, std::hypot(1.9, 0.01), 1e-12);
  EXPECT_NEAR(r.max_endpoint_error, std::hypot(2.0, 0.01), 1e-12);
  EXPECT_NEAR(r.mean_endpoint_error, (0.01 + std::hypot(2.0, 0.01) + std::hypot(1.9, 0.01) + 0.01) / 4.0,
              1e-12);
  // Off the line by more than association_distance over the overlap: not associated.
  const std::vector<Segment2> off = {Segment2(Vec2(0, 0.25), Vec2(8, 0.25))};
  EXPECT_EQ(evaluateAgainstGroundTruth(faces, off, defaults()).undetected_walls, 2u);
}

TEST(GroundTruthMetrics, APerfectMapOfWhatWasSeenScoresPerfectlyOnTheOffice)
{
  // The map that draws exactly the seen parts of every face of the simulated office (the
  // metric's own definition of what could be mapped): full coverage, nothing undetected, and every
  // seen end within coverage_tolerance (the seen part's end) of a map endpoint. Scored against the
  // whole faces instead, the same map loses metres at the ends it never saw: the old puzzle.
  line_map_eval::SimulationOptions opt;
  opt.scans = 200;
  const auto sim = line_map_eval::simulate(
      line_map_eval::loadWorld(std::string(LINEMAP_SOURCE_DIR) + "/config/worlds/office.yaml"), opt);
  const GroundTruthParams p = defaults();
  // Seen: in one scan's sight, or by all scans together (accumulate_sightings).
  const SeenParts seen = line_map_eval::unionOfSeenParts(
      line_map_eval::seenParts(sim.truth, p.min_seen_length, p.min_seen_beams),
      line_map_eval::accumulatedSeenParts(sim.truth, p.min_seen_length, p.min_seen_beams));
  std::vector<Segment2> map;
  std::size_t seen_faces = 0;
  for (std::size_t f = 0; f < seen.size(); ++f)
  {
    const Segment2& face = sim.truth.walls[f];
    const Vec2 u = (face.end - face.start).normalized();
    seen_faces += !seen[f].empty();
    for (const auto& [from, to] : seen[f]) map.emplace_back(face.start + from * u, face.start + to * u);
  }
  ASSERT_GT(seen_faces, 30u);
  const GroundTruthResult r = evaluateAgainstGroundTruth(sim.truth, map, p);
  EXPECT_EQ(r.walls.size(), seen_faces);
  EXPECT_EQ(r.unseen_walls, sim.truth.walls.size() - seen_faces);
  EXPECT_DOUBLE_EQ(r.coverage, 1.0);
  EXPECT_EQ(r.undetected_walls, 0u);
  EXPECT_EQ(r.unmapped_ends, 0u);
  EXPECT_LE(r.max_endpoint_error, p.coverage_tolerance + 1e-9);
  EXPECT_EQ(r.missed_corners, 0u);

  const GroundTruthResult whole = evaluateAgainstGroundTruth(sim.truth.walls, map, p);
  EXPECT_LT(whole.coverage, 0.9);
  EXPECT_GT(whole.undetected_walls, 0u);
  EXPECT_GT(whole.unmapped_ends, 0u);
}
