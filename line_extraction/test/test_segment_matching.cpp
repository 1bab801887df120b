// Ground-truth matching on hand-made lines: gate, one-to-one greed, the
// equivalent parametrisation near the origin, and the statistics.
#include <gtest/gtest.h>

#include <cmath>

#include "line_extraction/segment_matching.hpp"

using namespace line_extraction;
using linemap::HessianLine;
using linemap::kPi;

namespace
{
HessianLine line(double radius, double angle)
{
  HessianLine l;
  l.radius = radius;
  l.angle = angle;
  return l;
}
}  // namespace

TEST(SegmentMatching, GateIsChiSquareOnDiagonalMahalanobis)
{
  // (dr / 0.03)^2 + (da / 0.03)^2 against 2.77.
  const std::vector<HessianLine> truth{line(2.0, 0.3)};
  EXPECT_EQ(matchLines({line(2.04, 0.3)}, truth).size(), 1u);   // 1.78
  EXPECT_EQ(matchLines({line(2.05, 0.3)}, truth).size(), 0u);   // 2.78
  EXPECT_EQ(matchLines({line(2.0, 0.349)}, truth).size(), 1u);  // 2.67
  EXPECT_EQ(matchLines({line(2.0, 0.25)}, truth).size(), 0u);   // 2.78
  EXPECT_EQ(matchLines({line(2.03, 0.33)}, truth).size(), 1u);  // 2.00
  EXPECT_EQ(matchLines({line(2.04, 0.33)}, truth).size(), 0u);  // 2.78

  const LineMatch m = compareLines(line(2.03, 0.33), truth[0], MatchingOptions());
  EXPECT_NEAR(m.radius_error, 0.03, 1e-12);
  EXPECT_NEAR(m.angle_error, 0.03, 1e-12);
  EXPECT_NEAR(m.distance2, 2.0, 1e-9);
}

TEST(SegmentMatching, AngleWrapsAndOriginFlip)
{
  // Angles either side of +-pi are 0.02 rad apart.
  LineMatch m = compareLines(line(1.0, -kPi + 0.01), line(1.0, kPi - 0.01), MatchingOptions());
  EXPECT_NEAR(m.angle_error, 0.02, 1e-12);
  EXPECT_NEAR(m.radius_error, 0.0, 1e-12);
  // A line 1 cm on the other side of the origin: (0.01, a + pi) is (-0.01, a), 2 cm from (0.01, a).
  m = compareLines(line(0.01, linemap::normalizeAngle(0.5 + kPi)), line(0.01, 0.5), MatchingOptions());
  EXPECT_NEAR(m.radius_error, -0.02, 1e-12);
  EXPECT_NEAR(m.angle_error, 0.0, 1e-12);
  EXPECT_NEAR(m.distance2, 4.0 / 9.0, 1e-9);
  // Far from the origin the flip is no match at all.
  EXPECT_EQ(matchLines({line(1.0, linemap::normalizeAngle(0.5 + kPi))}, {line(1.0, 0.5)}).size(), 0u);
}

TEST(SegmentMatching, OneToOneGreedyByDistance)
{
  // Two extracted lines near one true line: only the closer matches.
  std::vector<LineMatch> m = matchLines({line(1.02, 0.0), line(1.01, 0.0)}, {line(1.0, 0.0)});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].extracted, 1);
  EXPECT_EQ(m[0].truth, 0);

  // E1 = 1.03 could take T1 = 1.00 (d2 = 1) but E2 = 1.00 takes it first (d2 = 0);
  // E1 then takes T2 = 1.05 (d2 = 0.44); E2-T2 (d2 = 2.78) is out of the gate anyway.
  m = matchLines({line(1.03, 0.0), line(1.00, 0.0)}, {line(1.00, 0.0), line(1.05, 0.0)});
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].extracted, 1);
  EXPECT_EQ(m[0].truth, 0);
  EXPECT_EQ(m[1].extracted, 0);
  EXPECT_EQ(m[1].truth, 1);
  EXPECT_NEAR(m[1].radius_error, -0.02, 1e-12);
}

TEST(SegmentMatching, StatisticsCountRatesAndSpread)
{
  MatchStatistics stats;
  // Scan 1: truths at r = 1, 2, 3 (3 not counted); extracted 1.01, 2.99 and a stray 5.
  std::vector<HessianLine> truth{line(1.0, 0.0), line(2.0, 1.0), line(3.0, 2.0)};
  std::vector<HessianLine> extracted{line(1.01, 0.0), line(2.99, 2.0), line(5.0, -1.0)};
  stats.add(extracted.size(), truth.size(), matchLines(extracted, truth), {true, true, false});
  // Scan 2: one truth, found with r error -0.01.
  truth = {line(4.0, 0.2)};
  extracted = {line(3.99, 0.2)};
  stats.add(extracted.size(), truth.size(), matchLines(extracted, truth));

  EXPECT_EQ(stats.extracted(), 4u);
  EXPECT_EQ(stats.counted(), 3u);
  EXPECT_EQ(stats.truePositives(), 2u);  // r = 1 and r = 4; r = 3 matched but not counted
  EXPECT_EQ(stats.matched(), 3u);
  EXPECT_NEAR(stats.truePositiveRate(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(stats.falsePositiveRate(), 1.0 / 4.0, 1e-12);  // only the stray line
  // Radius errors +0.01, -0.01, -0.01: mean -1/300, sample std sqrt(0.0003 - 3 mean^2) / sqrt(2).
  const double mean = -0.01 / 3.0;
  EXPECT_NEAR(stats.radiusErrorStd(), std::sqrt((3e-4 - 3.0 * mean * mean) / 2.0), 1e-12);
  EXPECT_NEAR(stats.angleErrorStd(), 0.0, 1e-12);

  const MatchStatistics empty;
  EXPECT_EQ(empty.truePositiveRate(), 0.0);
  EXPECT_EQ(empty.falsePositiveRate(), 0.0);
}

TEST(SegmentMatching, TrueLineInTheLaserFrame)
{
  // Wall y = 3 (x from 0 to 4); laser at (1, 1) facing +y: the wall is 2 m straight ahead,
  // i.e. the line x = 2 of the laser frame (normal angle 0).
  const HessianLine l =
      lineInLaserFrame(linemap::Pose2(1.0, 1.0, kPi / 2.0), linemap::Segment2({0.0, 3.0}, {4.0, 3.0}));
  EXPECT_NEAR(l.radius, 2.0, 1e-12);
  EXPECT_NEAR(l.angle, 0.0, 1e-12);
  // Facing -x instead: the wall is on the laser's right (-y axis), normal angle -pi/2.
  const HessianLine r =
      lineInLaserFrame(linemap::Pose2(1.0, 1.0, kPi), linemap::Segment2({0.0, 3.0}, {4.0, 3.0}));
  EXPECT_NEAR(r.radius, 2.0, 1e-12);
  EXPECT_NEAR(r.angle, -kPi / 2.0, 1e-12);

  const TruthRule rule;
  EXPECT_TRUE(rule.counts(10, 0.6));
  EXPECT_FALSE(rule.counts(9, 5.0));
  EXPECT_FALSE(rule.counts(50, 0.59));
}

TEST(SegmentMatching, OverlapIsMeasuredAlongTheSecondSegment)
{
  using linemap::Segment2;
  const Segment2 wall({0.0, 1.0}, {4.0, 1.0});
  EXPECT_NEAR(overlapAlong(Segment2({1.0, 1.02}, {2.5, 0.98}), wall), 1.5, 1e-12);
  EXPECT_NEAR(overlapAlong(Segment2({5.0, 1.0}, {3.0, 1.0}), wall), 1.0, 1e-12);   // reversed, sticking out
  EXPECT_NEAR(overlapAlong(Segment2({-1.0, 1.0}, {6.0, 1.0}), wall), 4.0, 1e-12);  // covering it
  EXPECT_EQ(overlapAlong(Segment2({4.5, 1.0}, {6.0, 1.0}), wall), 0.0);            // beyond its end
  EXPECT_EQ(overlapAlong(wall, Segment2({1.0, 1.0}, {1.0, 1.0})), 0.0);            // no length
}

TEST(SegmentMatching, CollinearTruePiecesGoToTheSegmentOnThem)
{
  using linemap::Segment2;
  // One wall y = 1 with a door between x = 2 and 3: two true pieces with the same
  // line. matchLines (lines only) gives the single extracted segment to the first
  // piece by index, although it lies on the second.
  const HessianLine wall_line = line(1.0, kPi / 2.0);
  const std::vector<LinePiece> truth{{wall_line, Segment2({0.0, 1.0}, {2.0, 1.0})},
                                     {wall_line, Segment2({3.0, 1.0}, {6.0, 1.0})}};
  const std::vector<LinePiece> extracted{{line(1.01, kPi / 2.0), Segment2({3.1, 1.01}, {5.8, 1.01})}};
  std::vector<LineMatch> m = matchLines({extracted[0].line}, {truth[0].line, truth[1].line});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].truth, 0);
  m = matchSegments(extracted, truth);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].truth, 1);
  EXPECT_NEAR(m[0].radius_error, 0.01, 1e-12);

  // Overlap only ranks the pairs: a segment on no piece still matches within the gate,
  // and one outside the gate does not match whatever it overlaps.
  m = matchSegments({{line(1.0, kPi / 2.0), Segment2({7.0, 1.0}, {8.0, 1.0})}}, truth);
  ASSERT_EQ(m.size(), 1u);
  m = matchSegments({{line(1.2, kPi / 2.0), Segment2({3.0, 1.2}, {6.0, 1.2})}}, truth);
  EXPECT_TRUE(m.empty());
}
