// Three-criteria fusion (Li et al. 2023): closed-form lens areas, the criteria, trivial clusters,
// TLS fusion and corner snapping.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_merging/mergers/li2023.hpp"
#include "segment_checks.hpp"

using line_map_merging::Keyframe;
using line_map_merging::Li2023;
using line_map_merging::Li2023Params;
using linemap::kPi;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// Keyframe k sees world segments frames[k], from a pose of its own.
std::vector<line_map_merging::MapSegment> merge(const std::vector<std::vector<Segment2>>& frames,
                                                Li2023Params params = Li2023Params())
{
  Li2023 li(params);
  for (std::size_t i = 0; i < frames.size(); ++i)
  {
    Keyframe k;
    k.index = i;
    k.pose = Pose2(0.5 * i, 0.2, -0.1 * i);
    for (const Segment2& s : frames[i]) k.segments.push_back(s.transformed(k.pose.inverse()));
    li.addKeyframe(k);
  }
  return li.map();
}
}  // namespace

TEST(Li2023, LensAreaMatchesClosedForms)
{
  using line_map_merging::lensArea;
  EXPECT_EQ(lensArea(1.0, 1.0, 3.0), 0.0);           // disjoint
  EXPECT_NEAR(lensArea(1.0, 2.0, 3.0), 0.0, 1e-12);  // externally tangent
  EXPECT_NEAR(lensArea(1.0, 3.0, 1.5), kPi, 1e-12);  // contained: the small disc
  EXPECT_NEAR(lensArea(1.0, 3.0, 2.0), kPi, 1e-12);  // internally tangent
  EXPECT_NEAR(lensArea(1.0, 1.0, 1.0), 2.0 * kPi / 3.0 - std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_NEAR(lensArea(1.0, 1.0, 0.0), kPi, 1e-12);  // coincident
  // Equal radii r at distance r*sqrt(2): two quarter-disc segments, r^2 (pi/2 - 1).
  EXPECT_NEAR(lensArea(2.0, 2.0, 2.0 * std::sqrt(2.0)), 4.0 * (kPi / 2.0 - 1.0), 1e-12);
  // Symmetric in the radii.
  EXPECT_NEAR(lensArea(1.0, 1.5, 1.2), lensArea(1.5, 1.0, 1.2), 1e-12);
}

TEST(Li2023, CriteriaOnHandComputedPairs)
{
  using line_map_merging::circleOverlapRatio;
  using line_map_merging::includedAngle;
  using line_map_merging::midpointDistance;
  const Segment2 a(Vec2(0, 0), Vec2(2, 0));
  const Segment2 rot30(Vec2(0, 0), Vec2(std::cos(kPi / 6), std::sin(kPi / 6)));
  EXPECT_NEAR(includedAngle(a, rot30), kPi / 6, 1e-12);
  EXPECT_NEAR(includedAngle(a, Segment2(rot30.end, rot30.start)), kPi / 6, 1e-12);  // direction-free
  EXPECT_NEAR(includedAngle(a, Segment2(Vec2(5, 1), Vec2(3, 1))), 0.0, 1e-12);      // reversed parallel
  EXPECT_NEAR(includedAngle(a, Segment2(Vec2(0, 0), Vec2(0, 1))), kPi / 2, 1e-12);
  // Unit circles 1 apart: lens / pi.
  EXPECT_NEAR(circleOverlapRatio(a, Segment2(Vec2(1, 0), Vec2(3, 0))),
              (2.0 * kPi / 3.0 - std::sqrt(3.0) / 2.0) / kPi, 1e-12);
  // A short segment inside the long one's circle: fully overlapped.
  EXPECT_NEAR(circleOverlapRatio(a, Segment2(Vec2(0.8, 0.1), Vec2(1.2, 0.1))), 1.0, 1e-12);
  // Midpoint (1, 0.1) is 0.1 from a; a's midpoint (1, 0) is 0.1 from the short one.
  EXPECT_NEAR(midpointDistance(a, Segment2(Vec2(0.8, 0.1), Vec2(1.2, 0.1))), 0.1, 1e-12);
  // Beyond the other segment's end the distance is to that endpoint: (1, 0) is 1.5 from (2.5, 0),
  // (3, 0) is 1.0 from (2, 0).
  EXPECT_NEAR(midpointDistance(a, Segment2(Vec2(2.5, 0), Vec2(3.5, 0))), 1.5, 1e-12);
}

TEST(Li2023, CircleOverlapThresholdDecidesCollinearNeighbours)
{
  // Circles of radius 1, centres 1 apart: epsilon = 0.391; merged at gamma 0.3, not at 0.4.
  const std::vector<std::vector<Segment2>> frames{{Segment2(Vec2(0, 0), Vec2(2, 0))},
                                                  {Segment2(Vec2(1, 0), Vec2(3, 0))}};
  auto map = merge(frames);
  ASSERT_EQ(map.size(), 1u);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(3, 0));
  Li2023Params strict;
  strict.gamma = 0.4;
  strict.min_count = 1;
  EXPECT_EQ(merge(frames, strict).size(), 2u);
}

TEST(Li2023, ParallelWallsMergeOnlyWithinEta)
{
  // 0.05 m apart: one cluster; the TLS line through the four endpoints is y = 0.025.
  auto map = merge({{Segment2(Vec2(0, 0), Vec2(4, 0))}, {Segment2(Vec2(0, 0.05), Vec2(4, 0.05))}});
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0].merged_count, 2u);
  expectSegment(map[0].segment, Vec2(0, 0.025), Vec2(4, 0.025));
  Li2023Params keep_all;
  keep_all.min_count = 1;
  map = merge({{Segment2(Vec2(0, 0), Vec2(4, 0))}, {Segment2(Vec2(0, 0.15), Vec2(4, 0.15))}}, keep_all);
  EXPECT_EQ(map.size(), 2u);
}

TEST(Li2023, TrivialClustersAreDroppedAndSameKeyframeSegmentsNeverLinkDirectly)
{
  const std::vector<std::vector<Segment2>> frames{
      {Segment2(Vec2(0, 0), Vec2(4, 0))},
      {Segment2(Vec2(0.1, 0.01), Vec2(3.9, 0.01)), Segment2(Vec2(10, 10), Vec2(10.5, 10.3))},
      {Segment2(Vec2(0.2, -0.01), Vec2(4.1, -0.01))}};
  auto map = merge(frames);
  ASSERT_EQ(map.size(), 1u);  // the clutter segment seen once is gone
  EXPECT_EQ(map[0].merged_count, 3u);
  Li2023Params keep_all;
  keep_all.min_count = 1;
  EXPECT_EQ(merge(frames, keep_all).size(), 2u);
  // Two overlapping collinear segments of one keyframe stay two.
  EXPECT_EQ(merge({{Segment2(Vec2(0, 0), Vec2(2, 0)), Segment2(Vec2(1, 0), Vec2(3, 0))}}, keep_all).size(),
            2u);
}

TEST(Li2023, SegmentsMeetingAtACornerShareOneEndpointAfterSnapping)
{
  // Wall 1 along y = 0, x in [0, 1.98]; wall 2 along x = 2, y in [0.04, 2]; their ends are
  // 0.045 m apart (< 0.1 m) and move to their mean (1.99, 0.02).
  const std::vector<std::vector<Segment2>> frames{
      {Segment2(Vec2(0, 0), Vec2(1.96, 0)), Segment2(Vec2(2, 0.04), Vec2(2, 2))},
      {Segment2(Vec2(0.02, 0), Vec2(1.98, 0)), Segment2(Vec2(2, 0.06), Vec2(2, 1.9))}};
  auto map = merge(frames);
  ASSERT_EQ(map.size(), 2u);
  EXPECT_EQ(map[0].segment.end, map[1].segment.start);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(1.99, 0.02));
  expectSegment(map[1].segment, Vec2(1.99, 0.02), Vec2(2, 2));
  // Without snapping the ends stay where the fits put them.
  Li2023Params no_snap;
  no_snap.snap_distance = 0.0;
  map = merge(frames, no_snap);
  ASSERT_EQ(map.size(), 2u);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(1.98, 0));
  expectSegment(map[1].segment, Vec2(2, 0.04), Vec2(2, 2));
}

TEST(Li2023, BadParametersNameTheKey)
{
  linemap::ParamSet params;
  params.set("li2023/gamma", "0");
  try
  {
    Li2023Params::fromParams(params);
    FAIL() << "gamma 0 accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("li2023/gamma"), std::string::npos);
  }
  params = linemap::ParamSet();
  params.set("li2023/min_count", "0");
  EXPECT_THROW(Li2023Params::fromParams(params), linemap::ParameterError);
  EXPECT_THROW(line_map_merging::lensArea(-1.0, 1.0, 1.0), std::invalid_argument);
}

TEST(Li2023, FusedSegmentTakesTheMajorityDirection)
{
  // The criteria are undirected: a 1 m segment running -x fuses with a 4 m one running +x. The
  // length-weighted majority runs +x, whichever member comes first.
  for (bool short_first : {true, false})
  {
    const Segment2 long_one(Vec2(0, 0), Vec2(4, 0)), short_one(Vec2(2.5, 0.02), Vec2(1.5, 0.02));
    auto map = short_first ? merge({{short_one}, {long_one}}) : merge({{long_one}, {short_one}});
    ASSERT_EQ(map.size(), 1u);
    EXPECT_GT(map[0].segment.end.x() - map[0].segment.start.x(), 3.9) << "short first: " << short_first;
  }
}
