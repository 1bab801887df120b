// Correlation quality q: closed-form cases and a synthetic room.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "eval_test_helpers.hpp"
#include "line_map_eval/metrics/map_quality.hpp"

using line_map_eval::computeMapQuality;
using line_map_eval::directionBin;
using line_map_eval::LookupTable;
using line_map_eval::LookupTableParams;
using line_map_eval::QualityParams;
using line_map_eval::QualityResult;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// The table every case here samples: 5 cm cells, 5 cm sigma.
LookupTableParams tableParams()
{
  return line_map_eval::test_helpers::lookupTableParams(0.05, 0.05);
}

QualityParams qualityParams(double w, bool directed = true)
{
  QualityParams p;
  p.directed = directed;
  p.direction_bins = directed ? 16 : 8;
  p.redundancy_penalty = w;
  return p;
}

// Sum of L over the five cells (-2..2, 0) around a single point in cell (0, 0), sigma = 1 cell.
const double kRowSum = 1.0 + 2.0 * std::exp(-0.5) + 2.0 * std::exp(-2.0);
}  // namespace

TEST(DirectionBin, UndirectedEightBinsCentredOnTheAxes)
{
  // Bins of 22.5 deg centred on 0, 22.5, 45, ... deg: bin 0 = [-11.25, 11.25) deg.
  const double pi = linemap::kPi, deg = pi / 180.0;
  EXPECT_EQ(directionBin(0.0, 8, false), 0);
  EXPECT_EQ(directionBin(pi, 8, false), 0);  // the same wall walked the other way
  EXPECT_EQ(directionBin(-pi, 8, false), 0);
  EXPECT_EQ(directionBin(-0.5 * deg, 8, false), 0);  // a hair below horizontal stays with horizontal
  EXPECT_EQ(directionBin(pi - 0.5 * deg, 8, false), 0);
  EXPECT_EQ(directionBin(11.0 * deg, 8, false), 0);
  EXPECT_EQ(directionBin(-11.0 * deg, 8, false), 0);
  EXPECT_EQ(directionBin(12.0 * deg, 8, false), 1);
  EXPECT_EQ(directionBin(-12.0 * deg, 8, false), 7);
  EXPECT_EQ(directionBin(pi / 2, 8, false), 4);
  EXPECT_EQ(directionBin(-pi / 2, 8, false), 4);
  EXPECT_EQ(directionBin(3.0 * pi / 4, 8, false), 6);
  EXPECT_EQ(directionBin(-pi / 4, 8, false), 6);
  EXPECT_EQ(directionBin(1.0, 1, false), 0);
}

TEST(DirectionBin, DirectedSixteenBinsOverTheFullCircle)
{
  // Bins of 22.5 deg over 360 deg centred on 0, 22.5, ... deg: opposite headings are 8 bins apart.
  const double pi = linemap::kPi, deg = pi / 180.0;
  EXPECT_EQ(directionBin(0.0, 16, true), 0);
  EXPECT_EQ(directionBin(pi, 16, true), 8);
  EXPECT_EQ(directionBin(-pi, 16, true), 8);
  EXPECT_EQ(directionBin(-0.5 * deg, 16, true), 0);
  EXPECT_EQ(directionBin(11.0 * deg, 16, true), 0);
  EXPECT_EQ(directionBin(12.0 * deg, 16, true), 1);
  EXPECT_EQ(directionBin(-12.0 * deg, 16, true), 15);
  EXPECT_EQ(directionBin(pi / 2, 16, true), 4);
  EXPECT_EQ(directionBin(-pi / 2, 16, true), 12);
  EXPECT_EQ(directionBin(pi - 0.5 * deg, 16, true), 8);
  EXPECT_EQ(directionBin(1.0, 1, true), 0);
}

TEST(MapQuality, TwoFacesOfAThinWallAreNotRedundantButASecondCopyIs)
{
  // A 10 cm wall between y = 0 and y = 0.1 seen from both sides: its faces run in opposite directions
  // (free side on the left). With 5 cm cells both faces' rows are distinct anyway, so draw the faces
  // into one row as a wall thinner than a cell would: a 2 cm wall, faces at y = 0.015 and 0.035.
  const LookupTable t = LookupTable::build({Vec2(0.025, 0.025)}, tableParams());
  const Segment2 lower(Vec2(0.125, 0.015), Vec2(-0.075, 0.015));  // free side below: runs -x
  const Segment2 upper(Vec2(-0.075, 0.035), Vec2(0.125, 0.035));  // free side above: runs +x
  const QualityResult faces = computeMapQuality(t, {lower, upper}, qualityParams(1.0));
  EXPECT_EQ(faces.pixel_count, 10u);
  EXPECT_EQ(faces.redundant_pixels, 0u);
  EXPECT_NEAR(faces.quality, 100.0 * 2.0 * kRowSum / 10.0, 1e-4);
  // The same face drawn twice in one direction is redundant: the copy cancels it (w = 1).
  const QualityResult twice = computeMapQuality(t, {upper, upper}, qualityParams(1.0));
  EXPECT_EQ(twice.redundant_pixels, 5u);
  EXPECT_NEAR(twice.quality, 0.0, 1e-9);
  // The undirected variant calls the two faces redundant.
  const QualityResult undirected = computeMapQuality(t, {lower, upper}, qualityParams(1.0, false));
  EXPECT_EQ(undirected.redundant_pixels, 5u);
}

TEST(MapQuality, SingleSegmentOverOnePointInClosedForm)
{
  const LookupTable t = LookupTable::build({Vec2(0.025, 0.025)}, tableParams());
  // Cells x = -2..2 (x from -1.5 to 2.5 cells) of row 0: L = e^-2, e^-1/2, 1, e^-1/2, e^-2.
  const std::vector<Segment2> map = {Segment2(Vec2(-0.075, 0.025), Vec2(0.125, 0.025))};
  const QualityResult r = computeMapQuality(t, map, qualityParams(1.0));
  EXPECT_EQ(r.pixel_count, 5u);
  EXPECT_EQ(r.redundant_pixels, 0u);
  EXPECT_NEAR(r.nonredundant_sum, kRowSum, 1e-6);
  EXPECT_NEAR(r.quality, 100.0 * kRowSum / 5.0, 1e-4);
}

TEST(MapQuality, UndirectedReversedDuplicateIsRedundantAndPenalised)
{
  const LookupTable t = LookupTable::build({Vec2(0.025, 0.025)}, tableParams());
  const Segment2 s(Vec2(-0.075, 0.025), Vec2(0.125, 0.025));
  const std::vector<Segment2> map = {s, Segment2(s.end, s.start)};
  // w = 0.5: q = 100 (S - 0.5 S) / 10.
  const QualityResult r = computeMapQuality(t, map, qualityParams(0.5, false));
  EXPECT_EQ(r.pixel_count, 10u);
  EXPECT_EQ(r.redundant_pixels, 5u);
  EXPECT_NEAR(r.redundant_sum, kRowSum, 1e-6);
  EXPECT_NEAR(r.quality, 100.0 * 0.5 * kRowSum / 10.0, 1e-4);
  // w = 1 cancels the duplicate completely; w = 0 only dilutes by N.
  EXPECT_NEAR(computeMapQuality(t, map, qualityParams(1.0, false)).quality, 0.0, 1e-9);
  EXPECT_NEAR(computeMapQuality(t, map, qualityParams(0.0, false)).quality, 100.0 * kRowSum / 10.0, 1e-4);
  // Directed, the reversed copy is another face: nothing is redundant.
  EXPECT_EQ(computeMapQuality(t, map, qualityParams(1.0)).redundant_pixels, 0u);
}

TEST(MapQuality, CopyTiltedToTheOtherSideOfHorizontalIsStillRedundant)
{
  const LookupTable t = LookupTable::build({Vec2(0.025, 0.025)}, tableParams());
  // Headings +0.57 and -0.57 deg, both within row 0 over cells -2..2.
  const std::vector<Segment2> map = {Segment2(Vec2(-0.075, 0.024), Vec2(0.125, 0.026)),
                                     Segment2(Vec2(-0.075, 0.026), Vec2(0.125, 0.024))};
  const QualityResult r = computeMapQuality(t, map, qualityParams(1.0));
  EXPECT_EQ(r.pixel_count, 10u);
  EXPECT_EQ(r.redundant_pixels, 5u);
  EXPECT_NEAR(r.quality, 0.0, 1e-9);
}

TEST(MapQuality, CrossingSegmentOfOtherDirectionIsNotRedundant)
{
  const LookupTable t = LookupTable::build({Vec2(0.025, 0.025)}, tableParams());
  const std::vector<Segment2> map = {Segment2(Vec2(-0.075, 0.025), Vec2(0.125, 0.025)),
                                     Segment2(Vec2(0.025, -0.075), Vec2(0.025, 0.125))};
  const QualityResult r = computeMapQuality(t, map, qualityParams(1.0));
  EXPECT_EQ(r.pixel_count, 10u);
  EXPECT_EQ(r.redundant_pixels, 0u);  // they share cell (0, 0) but not the direction bin
  EXPECT_NEAR(r.quality, 100.0 * 2.0 * kRowSum / 10.0, 1e-4);
}

TEST(MapQuality, EmptyMapAndBadInput)
{
  const LookupTable t = LookupTable::build({Vec2(0.0, 0.0)}, tableParams());
  const QualityResult r = computeMapQuality(t, {}, qualityParams(1.0));
  EXPECT_EQ(r.pixel_count, 0u);
  EXPECT_EQ(r.quality, 0.0);
  const std::vector<Segment2> bad = {Segment2(Vec2(0, 0), Vec2(std::nan(""), 1.0))};
  EXPECT_THROW(computeMapQuality(t, bad, qualityParams(1.0)), std::invalid_argument);
  QualityParams p = qualityParams(1.0);
  p.direction_bins = 0;
  EXPECT_THROW(computeMapQuality(t, {}, p), linemap::ParameterError);
  linemap::ParamSet ps;
  ps.set("eval/redundancy_penalty", "-1");
  EXPECT_THROW(QualityParams::fromParams(ps), linemap::ParameterError);
}

namespace
{
// A 8 m x 6 m room with a 2 m inner wall, the corner off the grid lines.
std::vector<Segment2> room()
{
  const Vec2 a(0.31, 0.17), b(8.31, 0.17), c(8.31, 6.17), d(0.31, 6.17);
  return {Segment2(a, b), Segment2(b, c), Segment2(c, d), Segment2(d, a),
          Segment2(Vec2(4.31, 0.17), Vec2(4.31, 2.17))};
}

// Points every 1.5 cm on every wall, 5 mm Gaussian noise across the wall.
std::vector<Vec2> sampleWalls(const std::vector<Segment2>& walls)
{
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<Vec2> pts;
  for (const Segment2& w : walls)
  {
    const Vec2 dir = (w.end - w.start).normalized();
    const Vec2 normal(-dir.y(), dir.x());
    const int n = static_cast<int>(w.length() / 0.015);
    for (int i = 0; i <= n; ++i) pts.push_back(w.start + (i * 0.015) * dir + noise(rng) * normal);
  }
  return pts;
}

std::vector<Segment2> transformed(const std::vector<Segment2>& map, const linemap::Pose2& p)
{
  std::vector<Segment2> out;
  for (const Segment2& s : map) out.push_back(s.transformed(p));
  return out;
}
}  // namespace

TEST(MapQuality, TrueWallsScoreHigherThanShiftedRotatedOrDuplicatedMaps)
{
  const std::vector<Segment2> walls = room();
  const LookupTable t = LookupTable::build(sampleWalls(walls), tableParams());
  const QualityParams qp = qualityParams(1.0);
  const QualityResult truth = computeMapQuality(t, walls, qp);
  // Every wall cell holds a point (or is next to one at 1/4 of a cell noise): q close to 100 %.
  EXPECT_GT(truth.quality, 90.0);
  EXPECT_EQ(truth.redundant_pixels, 0u);

  // Shifted 0.1 m = 2 sigma across the vertical walls: their pixels drop to about e^-2.
  const QualityResult shifted = computeMapQuality(t, transformed(walls, linemap::Pose2(0.1, 0.0, 0.0)), qp);
  EXPECT_LT(shifted.quality, truth.quality - 20.0);
  const QualityResult shifted_xy =
      computeMapQuality(t, transformed(walls, linemap::Pose2(0.07, 0.07, 0.0)), qp);
  EXPECT_LT(shifted_xy.quality, truth.quality - 20.0);

  // Rotated 2 degrees about the room centre: up to 0.14 m off at the ends of the long walls.
  const Vec2 centre(4.31, 3.17);
  const linemap::Pose2 to_centre(centre.x(), centre.y(), 0.0);
  const linemap::Pose2 rot =
      to_centre * linemap::Pose2(0, 0, 2.0 * linemap::kPi / 180.0) * to_centre.inverse();
  const QualityResult rotated = computeMapQuality(t, transformed(walls, rot), qp);
  EXPECT_LT(rotated.quality, truth.quality - 20.0);

  // Every segment twice: all N pixels of the copy are redundant and cancel the original's.
  std::vector<Segment2> doubled = walls;
  doubled.insert(doubled.end(), walls.begin(), walls.end());
  const QualityResult dup = computeMapQuality(t, doubled, qp);
  EXPECT_EQ(dup.pixel_count, 2 * truth.pixel_count);
  EXPECT_EQ(dup.redundant_pixels, truth.pixel_count);
  EXPECT_NEAR(dup.quality, 0.0, 1e-9);
  // With a milder penalty it still loses: q_dup = (1 - w) / 2 * q_true.
  const QualityResult dup_half = computeMapQuality(t, doubled, qualityParams(0.5));
  EXPECT_NEAR(dup_half.quality, 0.25 * truth.quality, 1e-6);
}
