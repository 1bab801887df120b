// Straight structure, structure coverage and unmapped length on synthetic clouds, with expected values
// derived by hand from the definition (structure_coverage.hpp) at the defaults: sigma 5 cm, so band
// half-width g = 5 cm and RMS limit 2.5 cm; radius 0.5 m; min_length 0.4 m; length cells of 0.1 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

#include "line_map_eval/metrics/length_coverage.hpp"
#include "line_map_eval/metrics/map_metrics.hpp"
#include "line_map_eval/metrics/point_coverage.hpp"
#include "line_map_eval/metrics/structure_coverage.hpp"

using line_map_eval::classifyStructure;
using line_map_eval::computePointCoverage;
using line_map_eval::computeStructureCoverage;
using line_map_eval::structureLength;
using line_map_eval::StructureParams;
using line_map_eval::StructurePoints;
using linemap::kPi;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
const double kSigma = 0.05;

/// Uniform in [-1, 1], reproducible.
struct Jitter
{
  std::mt19937 gen{7};
  double operator()() { return 2.0 * static_cast<double>(gen()) / 4294967295.0 - 1.0; }
};

/// Points every `step` along a -> b, each moved across the line by up to `noise` (uniform).
void addLine(std::vector<Vec2>& out, const Vec2& a, const Vec2& b, double step = 0.01, double noise = 0.01,
             Jitter* jitter = nullptr)
{
  static Jitter shared;
  Jitter& j = jitter ? *jitter : shared;
  const double length = (b - a).norm();
  const Vec2 u = (b - a) / length, n(-u.y(), u.x());
  const int count = static_cast<int>(std::floor(length / step + 1e-9)) + 1;
  for (int k = 0; k < count; ++k) out.push_back(a + (k * step) * u + noise * j() * n);
}

Vec2 at(double heading, double s)
{
  return s * Vec2(std::cos(heading), std::sin(heading));
}

double share(const StructurePoints& s)
{
  return s.points ? static_cast<double>(s.indices.size()) / static_cast<double>(s.points) : 0.0;
}

bool isStructure(const StructurePoints& s, std::size_t i)
{
  return std::binary_search(s.indices.begin(), s.indices.end(), i);
}
}  // namespace

// A 4 m wall at 30 degrees, 1 cm noise: every point, free ends included (a point at an end still has
// R = 0.5 m >= min_length of wall on one side), is structure; its length is 4 m to within a cell or two.
TEST(StructureCoverage, StraightWallIsAllStructure)
{
  std::vector<Vec2> cloud;
  const double phi = kPi / 6.0;
  addLine(cloud, Vec2(1.0, 2.0), Vec2(1.0, 2.0) + at(phi, 4.0));
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  EXPECT_EQ(s.points, cloud.size());
  EXPECT_EQ(s.indices.size(), cloud.size());
  ASSERT_EQ(s.feet.size(), s.indices.size());
  ASSERT_EQ(s.headings.size(), s.indices.size());
  for (std::size_t k = 0; k < s.indices.size(); k += 50)
  {
    EXPECT_NEAR(s.headings[k], phi, 0.01);
    // The foot lies on the wall's line (the noise is across it, the fitted line through its middle).
    const Vec2 d = s.feet[k] - Vec2(1.0, 2.0);
    EXPECT_NEAR(d.x() * std::sin(phi) - d.y() * std::cos(phi), 0.0, 0.003);
  }
  EXPECT_NEAR(s.length, 4.0, 0.15);
}

// Straight pieces shorter than min_length (0.4 m) are not structure, longer ones are, wholly.
TEST(StructureCoverage, ShortPiecesAreNotStructure)
{
  std::vector<Vec2> short_piece, long_piece;
  addLine(short_piece, Vec2(0, 0), Vec2(0.3, 0.0));
  addLine(long_piece, Vec2(0, 0), Vec2(0.6, 0.0));
  EXPECT_TRUE(classifyStructure(short_piece, kSigma, {}).indices.empty());
  EXPECT_EQ(classifyStructure(long_piece, kSigma, {}).indices.size(), long_piece.size());
}

// An L corner with 2 m arms. A point s >= R = 0.5 m from the vertex sees only its own arm: structure.
// Nearer, its neighbourhood holds a stub of the other arm; the band, refitted, settles on one arm (the
// diagonal between two arms is no resting place once they differ by a voxel), where the stub within g
// adds an RMS of about 1 cm: structure, and a point within g of the vertex lies within g of either
// arm's line. Only the voxels at the vertex (5 cm squares) see two nearly equal stubs and may keep a
// diagonal band, too short: the corner is structure but for points within two voxels (0.1 m, 19
// points) of the vertex, and measures 4 m.
TEST(StructureCoverage, CornerIsStructureUpToTheVertex)
{
  std::vector<Vec2> cloud;
  addLine(cloud, Vec2(0, 0), Vec2(2.0, 0.0), 0.01, 0.0);
  addLine(cloud, Vec2(0, 0.01), Vec2(0.0, 2.0), 0.01, 0.0);
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  for (std::size_t i = 0; i < cloud.size(); ++i)
  {
    if (cloud[i].norm() >= 0.1)
    {
      EXPECT_TRUE(isStructure(s, i)) << cloud[i].transpose();
    }
  }
  EXPECT_GE(s.indices.size(), cloud.size() - 19);
  EXPECT_NEAR(s.length, 4.0, 0.15);
}

// Both faces of a partition 10 cm thick: the band through a point of one face (half-width 5 cm) leaves
// the other face out, so both are structure, each with its own line.
TEST(StructureCoverage, BothFacesOfAThinWallAreStructure)
{
  std::vector<Vec2> cloud;
  addLine(cloud, Vec2(0, 0), Vec2(3.0, 0.0));
  addLine(cloud, Vec2(0, 0.10), Vec2(3.0, 0.10));
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  EXPECT_EQ(s.indices.size(), cloud.size());
  for (std::size_t k = 0; k < s.indices.size(); ++k)
    EXPECT_NEAR(s.feet[k].y(), cloud[s.indices[k]].y() < 0.05 ? 0.0 : 0.10, 0.01);
  // Two walls of 3 m.
  EXPECT_NEAR(s.length, 6.0, 0.3);
}

// A wall smeared into a uniformly filled band of full width t (a registration error): the band's RMS
// across is t / sqrt(12), structure up to t = sqrt(12) * 2.5 cm = 8.7 cm. A 6 cm band (RMS 1.7 cm) is
// all structure; a 16 cm one is not: the band of +-5 cm through any point is filled, RMS 10 / sqrt(12)
// = 2.9 cm > 2.5 cm. Its length counts the band once (feet on the line), not per row of cells.
TEST(StructureCoverage, ThickBandWithinToleranceOnly)
{
  const auto band = [](double width)
  {
    std::vector<Vec2> cloud;
    const double phi = 0.3;
    const Vec2 u = at(phi, 1.0), n(-u.y(), u.x());
    for (double across = -0.5 * width; across <= 0.5 * width + 1e-9; across += 0.005)
      for (double along = 0.0; along <= 3.0 + 1e-9; along += 0.01) cloud.push_back(along * u + across * n);
    return cloud;
  };
  StructureParams fine_only;
  fine_only.smear_band = 0.0;
  const auto thin = band(0.06);
  const StructurePoints s = classifyStructure(thin, kSigma, fine_only);
  EXPECT_EQ(s.indices.size(), thin.size());
  EXPECT_NEAR(s.length, 3.0, 0.2);
  EXPECT_TRUE(classifyStructure(band(0.16), kSigma, fine_only).indices.empty());
  // At the smeared scale (the defaults) 16 cm is a smeared wall (RMS 4.6 cm, under 8 cm), none of it
  // fine; a band 60 cm thick (RMS 17 cm) is no structure at either scale.
  const auto smeared = band(0.16);
  const StructurePoints wide = classifyStructure(smeared, kSigma, {});
  EXPECT_EQ(wide.indices.size(), smeared.size());
  EXPECT_EQ(std::count(wide.fine.begin(), wide.fine.end(), 1), 0);
  EXPECT_TRUE(classifyStructure(band(0.6), kSigma, {}).indices.empty());
}

// A 6 m wall registered from 8 poses that disagree across it by up to 10 cm (offsets evenly spaced in
// [-0.1, 0.1] m: RMS 6.5 cm, so the band's reach is sqrt(3) x 6.5 = 11.3 cm): every point is structure,
// a segment on the central line covers all of them (those beyond 5 cm through their foot on the
// smeared line), and a parallel segment 0.5 m away none.
TEST(StructureCoverage, SmearedWallIsStructureAndItsLineCoversIt)
{
  std::vector<Vec2> cloud;
  Jitter j;
  for (int k = 0; k < 8; ++k)
  {
    const double offset = -0.1 + 0.2 * k / 7.0;
    addLine(cloud, Vec2(0.0, offset), Vec2(6.0, offset), 0.02, 0.01, &j);
  }
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  EXPECT_EQ(s.indices.size(), cloud.size());
  const auto coverOf = [&](double y)
  {
    const std::vector<Segment2> map{{Vec2(0.0, y), Vec2(6.0, y)}};
    return computeStructureCoverage(s, computePointCoverage(cloud, map, kSigma), map, kSigma);
  };
  EXPECT_EQ(coverOf(0.0).fraction(), 1.0);
  EXPECT_EQ(coverOf(0.5).fraction(), 0.0);
  // Fine structure alone: only the copies within 5 cm of the line would count as covered.
  StructureParams fine_only;
  fine_only.smear_band = 0.0;
  const StructurePoints f = classifyStructure(cloud, kSigma, fine_only);
  const std::vector<Segment2> centre{{Vec2(0.0, 0.0), Vec2(6.0, 0.0)}};
  EXPECT_LT(computeStructureCoverage(f, computePointCoverage(cloud, centre, kSigma), centre, kSigma).covered,
            cloud.size() * 3 / 4);
}

// The two faces of a 10 cm partition, 6 m long, are two thin lines, not one smear: a segment on one face
// covers its half of the structure and not the other face's (a smeared band between them would let one
// segment in the middle cover both).
TEST(StructureCoverage, PartitionFacesAreNotOneSmear)
{
  std::vector<Vec2> cloud;
  Jitter j;
  addLine(cloud, Vec2(0.0, 0.0), Vec2(6.0, 0.0), 0.01, 0.01, &j);
  const std::size_t first = cloud.size();
  addLine(cloud, Vec2(0.0, 0.1), Vec2(6.0, 0.1), 0.01, 0.01, &j);
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  EXPECT_EQ(s.indices.size(), cloud.size());
  const std::vector<Segment2> one_face{{Vec2(0.0, 0.0), Vec2(6.0, 0.0)}};
  const auto c = computeStructureCoverage(s, computePointCoverage(cloud, one_face, kSigma), one_face, kSigma);
  EXPECT_NEAR(c.pointFraction(), static_cast<double>(first) / static_cast<double>(cloud.size()), 0.01);
  EXPECT_NEAR(c.fraction(), 0.5, 0.05);
}

// A wall seen only from afar: 40 points at random along 6 m (one per 15 cm on average, 1 cm noise),
// too sparse for the fine band's fill, straight at the smeared scale: structure. A filled 1 x 3 m
// table top is not (RMS 29 cm).
TEST(StructureCoverage, SparseWallSeenFromAfarIsStructure)
{
  std::vector<Vec2> sparse;
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> along(0.0, 6.0), across(-0.01, 0.01);
  for (int k = 0; k < 40; ++k) sparse.emplace_back(along(gen), across(gen));
  StructureParams fine_only;
  fine_only.smear_band = 0.0;
  EXPECT_LT(classifyStructure(sparse, kSigma, fine_only).indices.size(), sparse.size() / 2);
  EXPECT_EQ(classifyStructure(sparse, kSigma, {}).indices.size(), sparse.size());

  std::vector<Vec2> table;
  for (double x = 0.0; x <= 3.0 + 1e-9; x += 0.02)
    for (double y = 0.0; y <= 1.0 + 1e-9; y += 0.02) table.emplace_back(x, y);
  EXPECT_TRUE(classifyStructure(table, kSigma, {}).indices.empty());
}

// A wall registered twice, the copies 3 cm apart: one band of RMS 1.5 cm, structure, and its length
// counts once. 8 cm apart (more than g) the copies are two lines, as the two faces of a partition: two
// bands, both structure, 6 m. (Smeared into a filled band instead, a wall is too thick from 8.7 cm on:
// ThickBandWithinToleranceOnly.)
TEST(StructureCoverage, WallRegisteredTwice)
{
  const auto twice = [](double offset)
  {
    std::vector<Vec2> cloud;
    Jitter j;
    addLine(cloud, Vec2(0, 0), Vec2(3.0, 0.0), 0.01, 0.01, &j);
    addLine(cloud, Vec2(0, offset), Vec2(3.0, offset), 0.01, 0.01, &j);
    return cloud;
  };
  const auto close = twice(0.03);
  const StructurePoints s = classifyStructure(close, kSigma, {});
  EXPECT_EQ(s.indices.size(), close.size());
  EXPECT_NEAR(s.length, 3.0, 0.15);
  const auto apart = twice(0.08);
  const StructurePoints two = classifyStructure(apart, kSigma, {});
  EXPECT_EQ(two.indices.size(), apart.size());
  EXPECT_NEAR(two.length, 6.0, 0.3);
}

// Clutter: filled blobs (a 0.3 m and a 0.6 m disc: a band through them is filled, RMS 2.9 cm, or
// shorter than 0.4 m) and a sparse scatter (a band of 10 cm through a 0.5 m disc of scattered points
// holds about 4g / (pi R) = 13 % of them, below min_share 30 %).
TEST(StructureCoverage, ClutterIsNotStructure)
{
  std::vector<Vec2> blobs;
  for (const auto& [centre, radius] : {std::pair<Vec2, double>{Vec2(0, 0), 0.15}, {Vec2(3, 0), 0.3}})
    for (double x = -radius; x <= radius; x += 0.01)
      for (double y = -radius; y <= radius; y += 0.01)
        if (x * x + y * y <= radius * radius) blobs.push_back(centre + Vec2(x, y));
  EXPECT_TRUE(classifyStructure(blobs, kSigma, {}).indices.empty());

  // A row of chair legs: 4 cm blobs every 0.3 m along a line, as straight as a wall but fills 2 of
  // each 6 voxel bins of its extent, under min_fill 50 %.
  std::vector<Vec2> legs;
  for (int leg = 0; leg < 8; ++leg)
    for (double x = 0.0; x <= 0.04 + 1e-9; x += 0.005)
      for (double y = 0.0; y <= 0.04 + 1e-9; y += 0.005) legs.emplace_back(0.3 * leg + x, y);
  EXPECT_TRUE(classifyStructure(legs, kSigma, {}).indices.empty());

  std::vector<Vec2> scatter;
  Jitter j;
  for (int k = 0; k < 2000; ++k) scatter.emplace_back(1.5 * j(), 1.5 * j());
  EXPECT_LT(share(classifyStructure(scatter, kSigma, {})), 0.02);
}

// A curved wall: the band of half-width g through a point holds a chord of 2 sqrt(2 rho g - g^2) of an
// arc of radius rho. rho = 5 m (sagitta 2.5 cm over the 1 m neighbourhood) is structure throughout; a
// pillar of rho = 0.25 m (chord 0.3 m < min_length) is not.
TEST(StructureCoverage, LargeRadiusWallIsStructurePillarIsNot)
{
  std::vector<Vec2> wall, pillar;
  for (double a = 0.0; a <= kPi / 2.0; a += 0.01 / 5.0) wall.push_back(5.0 * Vec2(std::cos(a), std::sin(a)));
  for (double a = 0.0; a < 2.0 * kPi; a += 0.01 / 0.25)
    pillar.push_back(0.25 * Vec2(std::cos(a), std::sin(a)));
  const StructurePoints s = classifyStructure(wall, kSigma, {});
  EXPECT_EQ(s.indices.size(), wall.size());
  EXPECT_NEAR(s.length, 5.0 * kPi / 2.0, 0.3);
  EXPECT_TRUE(classifyStructure(pillar, kSigma, {}).indices.empty());
}

// The length estimate: a thin line of length L at an angle delta to the nearest of the 8 grid headings
// crosses L cos(delta) / h columns, each worth h / cos(delta); within two cells of L at any heading.
TEST(StructureCoverage, LengthFromCellsAtAnyHeading)
{
  for (const double phi : {0.0, 0.3, kPi / 4.0, 1.2, kPi / 2.0, 2.5})
  {
    SCOPED_TRACE(phi);
    std::vector<Vec2> feet;
    for (double s = 0.0; s <= 3.0 + 1e-9; s += 0.005) feet.push_back(Vec2(0.013, 0.027) + at(phi, s));
    const std::vector<double> headings(feet.size(), std::fmod(phi, kPi));
    EXPECT_NEAR(structureLength(feet, headings, 0.1), 3.0, 0.2);
  }
  // On a cell border, the feet scattered by a millimetre to either side: still one run per column.
  std::vector<Vec2> border;
  for (double s = 0.0; s <= 2.0 + 1e-9; s += 0.005)
    border.emplace_back(s, (static_cast<int>(s * 200) % 2 ? 1 : -1) * 1e-3);
  const std::vector<double> zero(border.size(), 0.0);
  EXPECT_NEAR(structureLength(border, zero, 0.1), 2.0, 0.15);
  // Two faces 10 cm apart are two lines; with a third of the feet of one of them flagged uncovered,
  // no run is mostly uncovered: nothing unmapped; all flagged: that face's 2 m.
  std::vector<Vec2> faces = border;
  for (const Vec2& p : border) faces.push_back(p + Vec2(0.0, 0.1));
  const std::vector<double> zeros(faces.size(), 0.0);
  EXPECT_NEAR(structureLength(faces, zeros, 0.1), 4.0, 0.3);
  std::vector<std::uint8_t> half(faces.size(), 0), face(faces.size(), 0);
  for (std::size_t i = border.size(); i < faces.size(); ++i)
  {
    half[i] = i % 3 == 0;  // one of every three feet: a third of each column
    face[i] = 1;
  }
  EXPECT_NEAR(structureLength(faces, zeros, 0.1, half), 0.0, 1e-12);
  EXPECT_NEAR(structureLength(faces, zeros, 0.1, face), 2.0, 0.15);
  EXPECT_EQ(structureLength({}, {}, 0.1), 0.0);
  EXPECT_THROW(structureLength({Vec2(0, 0)}, {}, 0.1), std::invalid_argument);
  EXPECT_THROW(structureLength({Vec2(0, 0)}, {0.0}, 0.0), std::invalid_argument);
}

// A map covering the first half of a 4 m wall. Covered: the points within 5 cm of the segment, i.e.
// up to 2 m + 5 cm along (the noise of 1 cm across shortens that by under 1 mm): 2.05 / 4 = 51.25 %.
// Unmapped: the remaining 1.95 m. Clutter beside the wall changes point coverage, not these.
TEST(StructureCoverage, HalfMappedWall)
{
  std::vector<Vec2> cloud;
  const double phi = 0.5;
  const Vec2 a(-1.0, 0.5);
  addLine(cloud, a, a + at(phi, 4.0), 0.005);
  const std::size_t wall_points = cloud.size();
  for (double x = -0.1; x <= 0.1; x += 0.01)
    for (double y = -0.1; y <= 0.1; y += 0.01) cloud.push_back(Vec2(3.0, -1.0) + Vec2(x, y));
  const std::vector<Segment2> map{{a, a + at(phi, 2.0)}};
  const StructurePoints s = classifyStructure(cloud, kSigma, {});
  EXPECT_EQ(s.indices.size(), wall_points);
  const auto points = computePointCoverage(cloud, map, kSigma);
  const auto c = computeStructureCoverage(s, points, map, kSigma);
  EXPECT_EQ(c.points, wall_points);
  EXPECT_NEAR(c.pointFraction(), 2.05 / 4.0, 0.005);
  // By length: the unmapped 1.95 m of 4 m, each to the 0.1 m columns of the length grid.
  EXPECT_DOUBLE_EQ(c.fraction(), 1.0 - c.unmapped_length / c.length);
  EXPECT_NEAR(c.fraction(), 2.05 / 4.0, 0.06);
  EXPECT_NEAR(c.unmapped_length, 1.95, 0.15);
  EXPECT_NEAR(c.length, 4.0, 0.15);
  EXPECT_EQ(c.covered + c.uncovered.size(), c.points);
  for (const std::size_t i : c.uncovered) EXPECT_GT((cloud[i] - a).dot(at(phi, 1.0)), 2.0);
  // Point coverage counts the 441 clutter points as misses too (the structure's covered points are the
  // same but for the few just past the segment's end whose feet on the wall's line, 1 cm nearer, are
  // within reach).
  EXPECT_NEAR(points.fraction(), c.covered / static_cast<double>(cloud.size()), 2e-3);

  // An empty map leaves the whole wall unmapped; a map on the whole wall none of it.
  const auto none = computeStructureCoverage(s, computePointCoverage(cloud, {}, kSigma), {}, kSigma);
  EXPECT_EQ(none.fraction(), 0.0);
  EXPECT_NEAR(none.unmapped_length, 4.0, 0.15);
  const std::vector<Segment2> whole{{a, a + at(phi, 4.0)}};
  const auto all = computeStructureCoverage(s, computePointCoverage(cloud, whole, kSigma), whole, kSigma);
  EXPECT_EQ(all.fraction(), 1.0);
  EXPECT_EQ(all.unmapped_length, 0.0);
  EXPECT_THROW(computeStructureCoverage(s, computePointCoverage({}, map, kSigma), map, kSigma),
               std::invalid_argument);
}

// computeMapMetrics classifies when not given the classification, with the same result.
TEST(StructureCoverage, MapMetricsReuseTheClassification)
{
  std::vector<Vec2> cloud;
  addLine(cloud, Vec2(0, 0), Vec2(3.0, 0.0));
  addLine(cloud, Vec2(3.0, 0.01), Vec2(3.0, 3.0));
  const line_map_eval::LookupTable table = line_map_eval::LookupTable::build(cloud, {});
  const std::vector<Segment2> map{{Vec2(0, 0), Vec2(3.0, 0.0)}};
  const line_map_eval::MapMetricParams params;
  const StructurePoints s = classifyStructure(cloud, table.params().sigma, params.coverage.structure);
  const auto given = line_map_eval::computeMapMetrics(table, cloud, {}, map, params, nullptr, &s);
  const auto computed = line_map_eval::computeMapMetrics(table, cloud, {}, map, params);
  EXPECT_EQ(given.structure_coverage.covered, computed.structure_coverage.covered);
  EXPECT_EQ(given.structure_coverage.points, computed.structure_coverage.points);
  EXPECT_DOUBLE_EQ(given.structure_coverage.unmapped_length, computed.structure_coverage.unmapped_length);
  // The horizontal wall is mapped, the vertical one (3 m less the 5 cm the map covers at the vertex)
  // not: whether the wall lies on a cell border (x = 3.0) or not, it is one run per column.
  EXPECT_NEAR(computed.structure_coverage.unmapped_length, 2.95, 0.15);
  EXPECT_NEAR(computed.structure_coverage.length, 6.0, 0.2);
}

TEST(StructureCoverage, RejectsBadInput)
{
  EXPECT_THROW(classifyStructure({Vec2(0, 0), Vec2(NAN, 0)}, kSigma, {}), std::invalid_argument);
  EXPECT_THROW(classifyStructure({Vec2(0, 0)}, 0.0, {}), linemap::ParameterError);
  StructureParams p;
  p.min_length = 1.5;  // more than the neighbourhood's diameter
  EXPECT_THROW(classifyStructure({Vec2(0, 0)}, kSigma, p), linemap::ParameterError);
  linemap::ParamSet set;
  set.set("eval/structure_radius", "-1");
  EXPECT_THROW(StructureParams::fromParams(set), linemap::ParameterError);
  set.set("eval/structure_radius", "0.8");
  EXPECT_DOUBLE_EQ(StructureParams::fromParams(set).radius, 0.8);
  EXPECT_TRUE(classifyStructure({}, kSigma, {}).indices.empty());
}
