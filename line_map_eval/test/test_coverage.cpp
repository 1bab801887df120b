// Point and length coverage, with expected values computed by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "line_map_eval/metrics/length_coverage.hpp"
#include "line_map_eval/metrics/point_coverage.hpp"

using line_map_eval::computeLengthCoverage;
using line_map_eval::computePointCoverage;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
const double kDmax = 0.10;
const double kThetaMax = 4.0 * linemap::kPi / 180.0;
}  // namespace

// Radius 5 cm around the segment (0,0)-(1,0): the distance is to the segment, not its line.
TEST(PointCoverage, PointsAtKnownDistances)
{
  const std::vector<Vec2> points{
      Vec2(0.5, 0.04),   // 4 cm above the middle: covered
      Vec2(0.5, -0.06),  // 6 cm below: not
      Vec2(1.03, 0.0),   // 3 cm past the end: covered
      Vec2(1.04, 0.04),  // 4 cm from the line but 5.66 cm from the end: not
      Vec2(-0.5, 0.0),   // on the line, 0.5 m before the start: not
  };
  const auto c = computePointCoverage(points, {{Vec2(0, 0), Vec2(1, 0)}}, 0.05);
  EXPECT_EQ(c.points, 5u);
  EXPECT_EQ(c.covered, 2u);
  EXPECT_DOUBLE_EQ(c.fraction(), 0.4);
  EXPECT_EQ(c.uncovered, (std::vector<std::size_t>{1, 3, 4}));
}

TEST(PointCoverage, EveryPointNearOneOfManySegments)
{
  // 100 unit segments along x at y = 0, 1, ..., 9 (10 per row); points 3 cm above each row, one per
  // 10 cm, plus the same number half-way between the rows (50 cm from any): exactly half covered.
  std::vector<Segment2> map;
  std::vector<Vec2> points;
  for (int row = 0; row < 10; ++row)
    for (int k = 0; k < 10; ++k)
    {
      map.emplace_back(Vec2(k, row), Vec2(k + 1, row));
      for (int s = 0; s < 10; ++s)
      {
        points.emplace_back(k + 0.05 + 0.1 * s, row + 0.03);
        points.emplace_back(k + 0.05 + 0.1 * s, row + 0.5);
      }
    }
  const auto c = computePointCoverage(points, map, 0.05);
  EXPECT_EQ(c.covered, 1000u);
  EXPECT_EQ(c.uncovered.size(), 1000u);
}

TEST(PointCoverage, EmptyInputs)
{
  EXPECT_EQ(computePointCoverage({}, {{Vec2(0, 0), Vec2(1, 0)}}, 0.05).fraction(), 0.0);
  const auto c = computePointCoverage({Vec2(0, 0)}, {}, 0.05);
  EXPECT_EQ(c.covered, 0u);
  EXPECT_EQ(c.uncovered.size(), 1u);
}

TEST(PointCoverage, BadInputIsNamed)
{
  EXPECT_THROW(computePointCoverage({Vec2(0, 0)}, {}, -1.0), std::invalid_argument);
  try
  {
    computePointCoverage({Vec2(0, 0), Vec2(NAN, 0)}, {{Vec2(0, 0), Vec2(1, 0)}}, 0.05);
    FAIL() << "no exception";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("scan point 1"), std::string::npos) << e.what();
  }
}

// A 2 m original with a 1 m map segment 5 cm beside its middle: half its length is represented.
TEST(LengthCoverage, MapSegmentBesideHalfTheOriginal)
{
  const std::vector<Segment2> originals{{Vec2(0, 0), Vec2(2, 0)}};
  const auto c = computeLengthCoverage(originals, {{Vec2(0.5, 0.05), Vec2(1.5, 0.05)}}, kDmax, kThetaMax);
  EXPECT_DOUBLE_EQ(c.total, 2.0);
  EXPECT_NEAR(c.covered, 1.0, 1e-12);
  EXPECT_NEAR(c.fraction(), 0.5, 1e-12);
}

TEST(LengthCoverage, OppositeDirectionFarOrTurnedRepresentsNothing)
{
  const std::vector<Segment2> originals{{Vec2(0, 0), Vec2(2, 0)}};
  EXPECT_EQ(computeLengthCoverage(originals, {{Vec2(1.5, 0.05), Vec2(0.5, 0.05)}}, kDmax, kThetaMax).covered,
            0.0);
  EXPECT_EQ(computeLengthCoverage(originals, {{Vec2(0.5, 0.15), Vec2(1.5, 0.15)}}, kDmax, kThetaMax).covered,
            0.0);
  const double h = 5.0 * linemap::kPi / 180.0;  // over theta_max
  EXPECT_EQ(computeLengthCoverage(originals, {{Vec2(0.5, 0), Vec2(0.5 + std::cos(h), std::sin(h))}}, kDmax,
                                  kThetaMax)
                .covered,
            0.0);
}

// Map segments over [0.5, 1.5] and [1.0, 1.8] of the original: their union, 1.3 m, counts once.
TEST(LengthCoverage, OverlappingMapSegmentsCountOnce)
{
  const auto c = computeLengthCoverage(
      {{Vec2(0, 0), Vec2(2, 0)}}, {{Vec2(0.5, 0.05), Vec2(1.5, 0.05)}, {Vec2(1.0, -0.02), Vec2(1.8, -0.02)}},
      kDmax, kThetaMax);
  EXPECT_NEAR(c.covered, 1.3, 1e-12);
}

// A map segment from the original's start at 3 deg: the original's point (x, 0) is x sin 3 deg from
// the map's line, so it is represented up to x = d_max / sin 3 deg = 1.9107 m of its 2 m.
TEST(LengthCoverage, TiltedMapSegmentLeavesTheBand)
{
  const double h = 3.0 * linemap::kPi / 180.0;
  const auto c = computeLengthCoverage({{Vec2(0, 0), Vec2(2, 0)}}, {{Vec2(0, 0), Vec2(2, 2 * std::tan(h))}},
                                       kDmax, kThetaMax);
  EXPECT_NEAR(c.covered, kDmax / std::sin(h), 1e-9);
}

// Two originals, 2 m and 1 m; only the first is mapped, from 0.25 m to its end: 1.75 of 3 m.
TEST(LengthCoverage, ShareOfTheTotalLength)
{
  const auto c = computeLengthCoverage({{Vec2(0, 0), Vec2(2, 0)}, {Vec2(0, 3), Vec2(0, 4)}},
                                       {{Vec2(0.25, 0.01), Vec2(2.5, 0.01)}}, kDmax, kThetaMax);
  EXPECT_DOUBLE_EQ(c.total, 3.0);
  EXPECT_NEAR(c.covered, 1.75, 1e-12);
  EXPECT_NEAR(c.fraction(), 1.75 / 3.0, 1e-12);
}

TEST(LengthCoverage, BadInputIsNamed)
{
  EXPECT_THROW(computeLengthCoverage({}, {}, -0.1, kThetaMax), std::invalid_argument);
  try
  {
    computeLengthCoverage({{Vec2(0, 0), Vec2(1, 0)}},
                          {{Vec2(0, 0), Vec2(1, 0)}, {Vec2(INFINITY, 0), Vec2(1, 0)}}, kDmax, kThetaMax);
    FAIL() << "no exception";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("map segment 1"), std::string::npos) << e.what();
  }
}
