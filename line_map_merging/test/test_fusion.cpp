// Fusion conditions at and just beyond each threshold, and weighted fusion against hand computation.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/mergers/fusion.hpp"

using line_map_merging::fuse;
using line_map_merging::FusionParams;
using line_map_merging::meetsFusionConditions;
using linemap::kPi;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kDeg = kPi / 180.0;

Segment2 seg(double x0, double y0, double x1, double y1)
{
  return {Vec2(x0, y0), Vec2(x1, y1)};
}

Segment2 fromHeading(const Vec2& start, double heading, double length)
{
  return {start, start + length * Vec2(std::cos(heading), std::sin(heading))};
}
}  // namespace

TEST(FusionConditions, DefaultsAreThePapers)
{
  const FusionParams p;
  EXPECT_NEAR(p.max_angle, 4.0 * kDeg, 1e-15);
  EXPECT_EQ(p.max_distance, 0.10);
  EXPECT_EQ(p.min_overlap, -0.10);
  EXPECT_NEAR(p.searchPadding(), 0.20, 1e-15);
}

TEST(FusionConditions, HeadingDeviationAtAndBeyondThreshold)
{
  const FusionParams p;
  const Segment2 map = seg(0, 0, 1, 0);
  // 0.5 m long from (0.2, 0): the far endpoint is 0.5*sin(4 deg) = 0.035 m off the line, overlap 0.5 m.
  EXPECT_TRUE(meetsFusionConditions(map, fromHeading(Vec2(0.2, 0), 3.99 * kDeg, 0.5), p));
  EXPECT_FALSE(meetsFusionConditions(map, fromHeading(Vec2(0.2, 0), 4.01 * kDeg, 0.5), p));
  EXPECT_TRUE(meetsFusionConditions(map, fromHeading(Vec2(0.2, 0), -3.99 * kDeg, 0.5), p));
  EXPECT_FALSE(meetsFusionConditions(map, fromHeading(Vec2(0.2, 0), -4.01 * kDeg, 0.5), p));
}

TEST(FusionConditions, OppositeHeadingsNeverFuse)
{
  const FusionParams p;
  const Segment2 map = seg(0, 0, 1, 0);
  const Segment2 reversed = seg(1, 0, 0, 0);  // the same wall seen from the other side
  EXPECT_NEAR(line_map_merging::headingDeviation(map, reversed), kPi, 1e-12);
  EXPECT_FALSE(meetsFusionConditions(map, reversed, p));
  // Its geometry alone would fuse: the overlap does not depend on direction.
  EXPECT_NEAR(line_map_merging::horizontalOverlap(map, reversed), 1.0, 1e-12);
  EXPECT_NEAR(line_map_merging::verticalDistance(map, reversed), 0.0, 1e-12);
}

TEST(FusionConditions, HeadingWrapsAtPlusMinusPi)
{
  const FusionParams p;
  const Segment2 map = seg(0, 0, -1, 0);  // heading exactly pi
  EXPECT_NEAR(map.heading(), kPi, 1e-15);
  const Segment2 scan = fromHeading(Vec2(-0.2, 0), -kPi + 3.0 * kDeg, 0.5);  // heading -177 deg
  EXPECT_NEAR(line_map_merging::headingDeviation(map, scan), 3.0 * kDeg, 1e-12);
  EXPECT_TRUE(meetsFusionConditions(map, scan, p));
  const Segment2 map2 = fromHeading(Vec2(0, 0), kPi - 1.0 * kDeg, 1.0);         // +179 deg
  const Segment2 scan2 = fromHeading(Vec2(-0.2, 0.0), -kPi + 2.5 * kDeg, 0.5);  // -177.5 deg: 3.5 deg apart
  EXPECT_TRUE(meetsFusionConditions(map2, scan2, p));
  const Segment2 scan3 = fromHeading(Vec2(-0.2, 0.0), -kPi + 3.5 * kDeg, 0.5);  // 4.5 deg apart
  EXPECT_FALSE(meetsFusionConditions(map2, scan3, p));
}

TEST(FusionConditions, VerticalDistanceAtAndBeyondThreshold)
{
  FusionParams p;
  p.max_distance = 0.125;  // exactly representable, so "at" is exact
  const Segment2 map = seg(0, 0, 1, 0);
  EXPECT_TRUE(meetsFusionConditions(map, seg(0.2, 0.125, 0.8, 0.125), p));
  EXPECT_FALSE(meetsFusionConditions(map, seg(0.2, 0.1251, 0.8, 0.1251), p));
  EXPECT_TRUE(meetsFusionConditions(map, seg(0.2, -0.125, 0.8, -0.125), p));
  EXPECT_FALSE(meetsFusionConditions(map, seg(0.2, -0.1251, 0.8, -0.1251), p));

  // The LARGER endpoint distance counts (the mean, 0.06 m, would pass).
  const FusionParams d;
  const Segment2 wall = seg(0, 0, 10, 0);
  EXPECT_NEAR(line_map_merging::verticalDistance(wall, seg(1, 0.02, 5, 0.101)), 0.101, 1e-12);
  EXPECT_FALSE(meetsFusionConditions(wall, seg(1, 0.02, 5, 0.101), d));
  EXPECT_TRUE(meetsFusionConditions(wall, seg(1, 0.02, 5, 0.099), d));
  // Distance to the infinite line: beyond the map segment's end the line still counts.
  EXPECT_NEAR(line_map_merging::verticalDistance(seg(0, 0, 1, 0), seg(1.05, 0.05, 2, 0.05)), 0.05, 1e-12);
}

TEST(FusionConditions, HorizontalOverlapAtAndBeyondThreshold)
{
  FusionParams p;
  p.min_overlap = -0.125;
  const Segment2 map = seg(0, 0, 1, 0);
  EXPECT_EQ(line_map_merging::horizontalOverlap(map, seg(1.125, 0, 2, 0)), -0.125);
  EXPECT_TRUE(meetsFusionConditions(map, seg(1.125, 0, 2, 0), p));    // gap exactly |p_min|
  EXPECT_FALSE(meetsFusionConditions(map, seg(1.1251, 0, 2, 0), p));  // just beyond
  EXPECT_TRUE(meetsFusionConditions(map, seg(-2, 0, -0.125, 0), p));  // gap before the start
  EXPECT_FALSE(meetsFusionConditions(map, seg(-2, 0, -0.1251, 0), p));

  // Defaults: a gap of 0.0999 m fuses, 0.1001 m does not.
  const FusionParams d;
  EXPECT_TRUE(meetsFusionConditions(map, seg(1.0999, 0, 2, 0), d));
  EXPECT_FALSE(meetsFusionConditions(map, seg(1.1001, 0, 2, 0), d));

  // Positive overlaps, including a scan segment that covers the whole map segment.
  EXPECT_NEAR(line_map_merging::horizontalOverlap(map, seg(0.5, 0, 3, 0)), 0.5, 1e-12);
  EXPECT_NEAR(line_map_merging::horizontalOverlap(map, seg(-1, 0, 3, 0)), 1.0, 1e-12);
  EXPECT_NEAR(line_map_merging::horizontalOverlap(map, seg(0.25, 0.05, 0.5, 0.05)), 0.25, 1e-12);
  // A positive p_min demands a real overlap.
  FusionParams strict;
  strict.min_overlap = 0.3;
  EXPECT_FALSE(meetsFusionConditions(map, seg(0.75, 0, 2, 0), strict));
  EXPECT_TRUE(meetsFusionConditions(map, seg(0.5, 0, 2, 0), strict));
}

TEST(FusionConditions, SearchPaddingCoversEveryFusableSegment)
{
  // A scan segment touching the extremes allowed by d_max and p_min still meets the padded box.
  const FusionParams p;
  const Segment2 map = seg(0, 0, 1, 0);
  const Segment2 far = seg(1.0999, 0.0999, 1.5, 0.0999);
  ASSERT_TRUE(meetsFusionConditions(map, far, p));
  EXPECT_LE(far.start.x(), 1.0 + p.searchPadding());
  EXPECT_LE(far.start.y(), 0.0 + p.searchPadding());
}

TEST(LiesWithin, ShortSegmentInsideTheBandWhateverItsHeading)
{
  using line_map_merging::liesWithin;
  const FusionParams p;  // d_max = 0.1 m
  const Segment2 wall = seg(0, 0, 5, 0);
  // 0.7 m at 6 deg (beyond theta_max = 4 deg) centred on the wall: its ends lie 0.35 sin 6 deg =
  // 0.0366 m from the line and project onto [2.152, 2.848] of [0, 5].
  const Vec2 mid(2.5, 0.0);
  const Segment2 tilted =
      fromHeading(mid - 0.35 * Vec2(std::cos(6 * kDeg), std::sin(6 * kDeg)), 6 * kDeg, 0.7);
  ASSERT_FALSE(meetsFusionConditions(wall, tilted, p));
  EXPECT_TRUE(liesWithin(wall, tilted, p));
  EXPECT_FALSE(liesWithin(tilted, wall, p));  // the wall projects far beyond the short one
  // Raised by 0.06 m: its upper end is at 0.0966 m (inside), by 0.07 m at 0.1066 m (outside).
  EXPECT_TRUE(liesWithin(
      wall, seg(tilted.start.x(), tilted.start.y() + 0.06, tilted.end.x(), tilted.end.y() + 0.06), p));
  EXPECT_FALSE(liesWithin(
      wall, seg(tilted.start.x(), tilted.start.y() + 0.07, tilted.end.x(), tilted.end.y() + 0.07), p));
  // The other face of a 5 cm thick wall: inside the band, but facing the other way.
  EXPECT_FALSE(liesWithin(wall, seg(3, 0.05, 2, 0.05), p));
  // Reaching 1 cm past the wall's end: not inside, though the fusion conditions would allow a gap.
  EXPECT_TRUE(liesWithin(wall, seg(4.3, 0.02, 5.0, 0.02), p));
  EXPECT_FALSE(liesWithin(wall, seg(4.31, 0.02, 5.01, 0.02), p));
  EXPECT_FALSE(liesWithin(wall, seg(-0.01, 0.02, 0.69, 0.02), p));
}

TEST(FusionParams, RejectsBadValuesNamingTheKey)
{
  linemap::ParamSet params;
  params.set("fusion/max_distance", "-1");
  try
  {
    FusionParams::fromParams(params);
    FAIL() << "negative max_distance accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("fusion/max_distance"), std::string::npos) << e.what();
  }
  linemap::ParamSet bad;
  bad.set("fusion/max_angle", "abc");
  EXPECT_THROW(FusionParams::fromParams(bad), linemap::ParameterError);
}

TEST(Fusion, WeightedSegmentsMatchHandComputation)
{
  // A: (0,0)-(2,0) weight 3; B: (1,1)-(1,3) weight 1.
  // Barycentre (3*(1,0) + (1,2)) / 4 = (1, 0.5); heading vector 3*(1,0) + (0,1) = (3,1).
  // Projections t = (p - c).(3,1)/sqrt(10): A.start -3.5/sqrt10 (min), A.end and B.end 2.5/sqrt10 (max).
  // start = (1,0.5) - 0.35*(3,1) = (-0.05, 0.15); end = (1,0.5) + 0.25*(3,1) = (1.75, 0.75).
  const Segment2 f = fuse({{seg(0, 0, 2, 0), 3.0}, {seg(1, 1, 1, 3), 1.0}});
  EXPECT_NEAR(f.start.x(), -0.05, 1e-12);
  EXPECT_NEAR(f.start.y(), 0.15, 1e-12);
  EXPECT_NEAR(f.end.x(), 1.75, 1e-12);
  EXPECT_NEAR(f.end.y(), 0.75, 1e-12);
  EXPECT_NEAR(f.heading(), std::atan2(1.0, 3.0), 1e-12);
}

TEST(Fusion, EqualWeightsOfParallelSegments)
{
  // y = 0 over [0,2] and y = 0.04 over [1,3], weights 1 and 3: line y = 0.03 over [0,3].
  const Segment2 f = fuse({{seg(0, 0, 2, 0), 1.0}, {seg(1, 0.04, 3, 0.04), 3.0}});
  EXPECT_NEAR(f.start.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.end.x(), 3.0, 1e-12);
  EXPECT_NEAR(f.start.y(), 0.03, 1e-12);
  EXPECT_NEAR(f.end.y(), 0.03, 1e-12);
}

TEST(Fusion, HeadingsAcrossPlusMinusPiAverageToPi)
{
  // Headings pi - a and -pi + a: as angles their mean is 0 (wrong), as unit vectors it is pi.
  const double a = 0.05;
  const Segment2 up(Vec2(0, 0), Vec2(-2 * std::cos(a), 2 * std::sin(a)));
  const Segment2 down(Vec2(0, 0), Vec2(-2 * std::cos(a), -2 * std::sin(a)));
  const Segment2 f = fuse({{up, 1.0}, {down, 1.0}});
  EXPECT_NEAR(std::abs(f.heading()), kPi, 1e-12);
  EXPECT_NEAR(f.start.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.start.y(), 0.0, 1e-12);
  EXPECT_NEAR(f.end.x(), -2 * std::cos(a), 1e-12);
  EXPECT_NEAR(f.end.y(), 0.0, 1e-12);
}

TEST(Fusion, SingleSegmentIsItselfAndEmptyInputThrows)
{
  const Segment2 s = seg(0.3, -1.2, 2.5, 0.7);
  const Segment2 f = fuse({{s, 2.0}});
  EXPECT_NEAR((f.start - s.start).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.end - s.end).norm(), 0.0, 1e-12);
  EXPECT_THROW(fuse({}), std::invalid_argument);
  EXPECT_THROW(fuse({{s, 0.0}}), std::invalid_argument);
}

TEST(Fusion, LengthWeightingIsTheTotalLeastSquaresLineOfTheMembersMass)
{
  // y = 0 over [0, 4] (4 m) and y = 0.06 over [1, 3] (2 m), weight 1 each. Length weighting: centre
  // of mass y = (4 * 0 + 2 * 0.06) / 6 = 0.02, principal axis along x. Count weighting: y = 0.03.
  const std::vector<line_map_merging::WeightedSegment> members = {{seg(0, 0, 4, 0), 1.0},
                                                                  {seg(1, 0.06, 3, 0.06), 1.0}};
  const Segment2 by_length = fuse(members, line_map_merging::FusionWeighting::length);
  EXPECT_NEAR(by_length.start.y(), 0.02, 1e-12);
  EXPECT_NEAR(by_length.end.y(), 0.02, 1e-12);
  EXPECT_NEAR(by_length.start.x(), 0.0, 1e-12);
  EXPECT_NEAR(by_length.end.x(), 4.0, 1e-12);
  EXPECT_NEAR(fuse(members, line_map_merging::FusionWeighting::count).start.y(), 0.03, 1e-12);
  // Both members reversed: the same line, running the other way.
  const Segment2 reversed =
      fuse({{seg(4, 0, 0, 0), 1.0}, {seg(3, 0.06, 1, 0.06), 1.0}}, line_map_merging::FusionWeighting::length);
  EXPECT_NEAR(reversed.start.x(), 4.0, 1e-12);
  EXPECT_NEAR(reversed.end.x(), 0.0, 1e-12);
}

TEST(Fusion, LengthWeightedHeadingOfTiltedMembers)
{
  // Two 2 m members on the line y = x tan(0.3), one shifted along it: the TLS axis is the line itself.
  const double a = 0.3;
  const Vec2 u(std::cos(a), std::sin(a));
  const Segment2 f = fuse({{Segment2(Vec2(0, 0), 2 * u), 1.0}, {Segment2(5 * u, 7 * u), 1.0}},
                          line_map_merging::FusionWeighting::length);
  EXPECT_NEAR(f.heading(), a, 1e-12);
  EXPECT_NEAR((f.start - Vec2(0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.end - 7 * u).norm(), 0.0, 1e-12);
}

TEST(FusionMoments, AddingGroupMomentsEqualsAddingTheMembers)
{
  // Groups with different reference points: the parallel axis shift must reproduce the members' sums.
  const Segment2 a = seg(100.0, 50.0, 103.0, 50.2), b = seg(101.0, 50.1, 104.5, 50.0),
                 c = seg(-20.0, 7.0, -18.0, 7.5);
  line_map_merging::FusionMoments all, left, right;
  all.add(a, 2.0);
  all.add(b);
  all.add(c, 0.5);
  left.add(a, 2.0);
  right.add(b);
  right.add(c, 0.5);
  left.add(right);
  EXPECT_NEAR(left.mass, all.mass, 1e-12);
  EXPECT_NEAR((left.centroid(line_map_merging::FusionWeighting::length) -
               all.centroid(line_map_merging::FusionWeighting::length))
                  .norm(),
              0.0, 1e-9);
  EXPECT_NEAR((left.direction(line_map_merging::FusionWeighting::length) -
               all.direction(line_map_merging::FusionWeighting::length))
                  .norm(),
              0.0, 1e-12);
  EXPECT_NEAR((left.second - all.second).norm(), 0.0, 1e-6);
}
