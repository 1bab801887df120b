// Redundant pairs: map segments meeting the fusion conditions with each other, with expected
// counts and overlaps computed by hand from the default fusion thresholds (4 deg, 0.10 m, -0.10 m).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "line_map_eval/metrics/redundant_pairs.hpp"

using line_map_eval::findRedundantPairs;
using line_map_merging::FusionParams;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
double deg(double d)
{
  return d * linemap::kPi / 180.0;
}
}  // namespace

TEST(RedundantPairs, ParallelSegmentsFiveCentimetresApartOverlappingOneMetre)
{
  const auto r =
      findRedundantPairs({{Vec2(0, 0), Vec2(2, 0)}, {Vec2(1, 0.05), Vec2(3, 0.05)}}, FusionParams{});
  EXPECT_EQ(r.pairs, 1u);
  EXPECT_NEAR(r.overlap_length, 1.0, 1e-12);
  ASSERT_EQ(r.pair_indices.size(), 1u);
  EXPECT_EQ(r.pair_indices[0], std::make_pair(std::size_t{0}, std::size_t{1}));
}

// The two faces of a wall run in opposite directions: not redundant.
TEST(RedundantPairs, OppositeDirectionsAreNoPair)
{
  const auto r =
      findRedundantPairs({{Vec2(0, 0), Vec2(2, 0)}, {Vec2(3, 0.05), Vec2(1, 0.05)}}, FusionParams{});
  EXPECT_EQ(r.pairs, 0u);
  EXPECT_EQ(r.overlap_length, 0.0);
}

TEST(RedundantPairs, FartherThanDmaxOrTurnedMoreThanThetaMaxIsNoPair)
{
  EXPECT_EQ(
      findRedundantPairs({{Vec2(0, 0), Vec2(2, 0)}, {Vec2(1, 0.15), Vec2(3, 0.15)}}, FusionParams{}).pairs,
      0u);
  // 0.5 m at 5 deg: 4.4 cm off the line (within d_max) but 1 deg over theta_max.
  const Vec2 dir5(std::cos(deg(5)), std::sin(deg(5)));
  EXPECT_EQ(
      findRedundantPairs({{Vec2(0, 0), Vec2(2, 0)}, {Vec2(1, 0), Vec2(1, 0) + 0.5 * dir5}}, FusionParams{})
          .pairs,
      0u);
}

// At 3 deg the short segment pairs with the long one; the overlap is measured along the longer
// segment's line: the short one's projection, 0.5 cos 3 deg.
TEST(RedundantPairs, OverlapIsAlongTheLongerSegment)
{
  const Vec2 dir3(std::cos(deg(3)), std::sin(deg(3)));
  const auto r =
      findRedundantPairs({{Vec2(1, 0), Vec2(1, 0) + 0.5 * dir3}, {Vec2(0, 0), Vec2(2, 0)}}, FusionParams{});
  EXPECT_EQ(r.pairs, 1u);
  EXPECT_NEAR(r.overlap_length, 0.5 * std::cos(deg(3)), 1e-12);
}

// A 4 m segment and a 0.5 m one at 3 deg, 2 cm off its middle: with the long one as M the short one
// is within d_max; with the short one as M the long one's far end is 12.5 cm off its line. One way
// suffices.
TEST(RedundantPairs, ConditionsHoldingOneWayMakeAPair)
{
  const Segment2 a(Vec2(-2, 0), Vec2(2, 0));
  const Segment2 b(Vec2(0, 0.02), Vec2(0.5, 0.02 + 0.5 * std::tan(deg(3))));
  ASSERT_TRUE(line_map_merging::meetsFusionConditions(a, b, FusionParams{}));
  ASSERT_FALSE(line_map_merging::meetsFusionConditions(b, a, FusionParams{}));
  const auto r = findRedundantPairs({a, b}, FusionParams{});
  EXPECT_EQ(r.pairs, 1u);
  EXPECT_NEAR(r.overlap_length, 0.5, 1e-12);
}

// Collinear pieces 5 cm apart fuse (p_min = -0.10) but overlap by nothing.
TEST(RedundantPairs, APairAcrossAGapOverlapsByZero)
{
  const auto r = findRedundantPairs({{Vec2(0, 0), Vec2(1, 0)}, {Vec2(1.05, 0), Vec2(2, 0)}}, FusionParams{});
  EXPECT_EQ(r.pairs, 1u);
  EXPECT_EQ(r.overlap_length, 0.0);
}

// Three copies of a wall's pieces: [0, 2], [1, 3], [1.5, 2.5] pairwise overlap 1, 0.5 and 1 m.
TEST(RedundantPairs, EveryPairIsCountedOnce)
{
  const auto r = findRedundantPairs(
      {{Vec2(0, 0), Vec2(2, 0)}, {Vec2(1, 0.02), Vec2(3, 0.02)}, {Vec2(1.5, -0.03), Vec2(2.5, -0.03)}},
      FusionParams{});
  EXPECT_EQ(r.pairs, 3u);
  EXPECT_NEAR(r.overlap_length, 1.0 + 0.5 + 1.0, 1e-12);
}

// The R-tree search finds exactly the pairs of the all-pairs loop.
TEST(RedundantPairs, AgreesWithAllPairs)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(0.0, 3.0), len(0.05, 1.5), angle(-0.1, 0.1);
  std::vector<Segment2> map;
  for (int i = 0; i < 300; ++i)
  {
    const Vec2 a(pos(rng), pos(rng));
    const double h = (i % 4) * linemap::kPi / 2 + angle(rng);
    map.emplace_back(a, a + len(rng) * Vec2(std::cos(h), std::sin(h)));
  }
  const FusionParams params;
  std::size_t expected = 0;
  for (std::size_t i = 0; i < map.size(); ++i)
    for (std::size_t j = i + 1; j < map.size(); ++j)
      expected += line_map_merging::meetEachOther(map[i], map[j], params);
  ASSERT_GT(expected, 20u);  // the test must exercise the search
  EXPECT_EQ(findRedundantPairs(map, params).pairs, expected);
}

TEST(RedundantPairs, NonFiniteSegmentIsNamed)
{
  try
  {
    findRedundantPairs({{Vec2(0, 0), Vec2(1, 0)}, {Vec2(0, NAN), Vec2(1, 0)}}, FusionParams{});
    FAIL() << "no exception";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("map segment 1"), std::string::npos) << e.what();
  }
}
