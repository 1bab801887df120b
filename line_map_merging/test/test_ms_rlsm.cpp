// MS-RLSM: angular mean shift on the circle of period pi, then lateral/longitudinal clustering and
// length-weighted fusion.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/mergers/ms_rlsm.hpp"
#include "segment_checks.hpp"

using line_map_merging::Keyframe;
using line_map_merging::MsParams;
using line_map_merging::MsRlsm;
using linemap::kPi;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// One keyframe per segment, each seen from its own pose.
std::vector<line_map_merging::MapSegment> merge(const std::vector<Segment2>& world,
                                                MsParams params = MsParams())
{
  MsRlsm ms(params);
  std::uint64_t index = 0;
  for (const Segment2& s : world)
  {
    Keyframe k;
    k.index = index;
    k.pose = Pose2(0.3 * index, -1.0, 0.2 * index);
    k.segments.push_back(s.transformed(k.pose.inverse()));
    ms.addKeyframe(k);
    ++index;
  }
  return ms.map();
}
}  // namespace

TEST(MsRlsm, AngularMeanShiftIsCircularWithPeriodPi)
{
  // 0.01 and pi - 0.01 are 0.02 apart on the circle of undirected directions.
  const std::vector<double> angles{0.01, kPi - 0.01, 0.02, 0.5 * kPi, 0.5 * kPi + 0.03};
  std::vector<double> modes;
  const auto labels = line_map_merging::angularClusters(angles, std::vector<double>(5, 1.0), 0.1, &modes);
  ASSERT_EQ(labels.size(), 5u);
  EXPECT_EQ(labels[0], 0);
  EXPECT_EQ(labels[1], 0);
  EXPECT_EQ(labels[2], 0);
  EXPECT_EQ(labels[3], 1);
  EXPECT_EQ(labels[4], 1);
  ASSERT_EQ(modes.size(), 2u);
  // Mean of 0.01, -0.01, 0.02 and of pi/2, pi/2 + 0.03 (doubled-angle means differ by < 1e-5).
  EXPECT_NEAR(modes[0], 0.02 / 3.0, 1e-5);
  EXPECT_NEAR(modes[1], 0.5 * kPi + 0.015, 1e-5);
  // A narrow kernel separates directions 0.15 rad apart.
  const auto narrow = line_map_merging::angularClusters({0.0, 0.15}, {1.0, 1.0}, 0.05);
  EXPECT_NE(narrow[0], narrow[1]);
}

TEST(MsRlsm, ParallelWallsMergeOnlyWithinTheLateralSeparation)
{
  // 0.08 m apart (< 0.1 m): one segment, barycentre weighted by length (4 and 2).
  auto map = merge({Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(1, 0.08), Vec2(3, 0.08))});
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0].merged_count, 2u);
  expectSegment(map[0].segment, Vec2(0, 0.16 / 6.0), Vec2(4, 0.16 / 6.0));
  // 0.15 m apart: two.
  map = merge({Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(0, 0.15), Vec2(4, 0.15))});
  ASSERT_EQ(map.size(), 2u);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(4, 0));
  expectSegment(map[1].segment, Vec2(0, 0.15), Vec2(4, 0.15));
  // A larger lateral separation merges them.
  MsParams wide;
  wide.lateral_separation = 0.2;
  EXPECT_EQ(merge({Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(0, 0.15), Vec2(4, 0.15))}, wide).size(),
            1u);
}

TEST(MsRlsm, OppositeDirectionsOfOneWallShareTheAngularCluster)
{
  // Undirected angles 0.005 and pi - 0.005: one cluster across the wrap; one wall.
  const auto map = merge({Segment2(Vec2(0, 0), Vec2(4, 0.04)), Segment2(Vec2(4, 0), Vec2(0, 0.04))});
  ASSERT_EQ(map.size(), 1u);
  // Symmetric pair: barycentre (2, 0.02), heading 0, x over [0, 4].
  expectSegment(map[0].segment, Vec2(0, 0.02), Vec2(4, 0.02));
}

TEST(MsRlsm, LongitudinalGapAndPerpendicularWalls)
{
  // A 0.05 m gap is within |longitudinal_overlap| = 0.1 m, a 0.2 m gap is not.
  auto map = merge({Segment2(Vec2(0, 0), Vec2(2, 0)), Segment2(Vec2(2.05, 0), Vec2(4, 0))});
  ASSERT_EQ(map.size(), 1u);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(4, 0));
  EXPECT_EQ(merge({Segment2(Vec2(0, 0), Vec2(2, 0)), Segment2(Vec2(2.2, 0), Vec2(4, 0))}).size(), 2u);
  // A corner: two angular clusters.
  map = merge({Segment2(Vec2(0, 0), Vec2(2, 0)), Segment2(Vec2(2, 0), Vec2(2, 2))});
  ASSERT_EQ(map.size(), 2u);
  expectSegment(map[1].segment, Vec2(2, 0), Vec2(2, 2));
}

TEST(MsRlsm, BadParametersNameTheKey)
{
  linemap::ParamSet params;
  params.set("ms/angular_bandwidth", "2.0");
  try
  {
    MsParams::fromParams(params);
    FAIL() << "bandwidth 2 rad accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("ms/angular_bandwidth"), std::string::npos);
  }
  params = linemap::ParamSet();
  params.set("ms/lateral_separation", "-0.1");
  EXPECT_THROW(MsParams::fromParams(params), linemap::ParameterError);
}

TEST(MsRlsm, FusedSegmentTakesTheMajorityDirection)
{
  // Angular clusters are undirected: a 1 m segment running -x fuses with a 4 m one running +x.
  // The output runs like the length-weighted majority of its members, in either input order.
  const Segment2 long_one(Vec2(0, 0), Vec2(4, 0)), short_one(Vec2(2.5, 0.02), Vec2(1.5, 0.02));
  for (const auto& input :
       {std::vector<Segment2>{short_one, long_one}, std::vector<Segment2>{long_one, short_one}})
  {
    const auto map = merge(input);
    ASSERT_EQ(map.size(), 1u);
    EXPECT_GT(map[0].segment.end.x() - map[0].segment.start.x(), 3.9);
  }
  const Segment2 reversed_long(Vec2(4, 0), Vec2(0, 0)), forward_short(Vec2(1.5, 0.02), Vec2(2.5, 0.02));
  const auto map = merge({forward_short, reversed_long});
  ASSERT_EQ(map.size(), 1u);
  EXPECT_LT(map[0].segment.end.x() - map[0].segment.start.x(), -3.9);
}
