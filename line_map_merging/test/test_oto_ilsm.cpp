// OTO-ILSM: one-to-one incremental merging against CAE-RLSM's one-to-many merging.
#include <gtest/gtest.h>

#include <limits>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/mergers/oto_ilsm.hpp"
#include "segment_checks.hpp"
#include "synthetic_world.hpp"

using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using line_map_merging::OtoIlsm;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;
using synthetic::keyframeOf;

namespace
{
/// The loop case: a wall seen at the start (A) and the end (B) of a loop with a 1 m gap, then one
/// segment C bridging both; C is nearer to B's line (0.01 m) than to A's (0.02 m).
std::vector<Keyframe> loopCase()
{
  return {keyframeOf(0, Pose2(0, -1, 0.3), {Segment2(Vec2(0, 0), Vec2(4, 0))}),
          keyframeOf(1, Pose2(8, -1, -0.2), {Segment2(Vec2(5, 0.01), Vec2(9, 0.01))}),
          keyframeOf(2, Pose2(4.5, 1, 0.1), {Segment2(Vec2(3, 0.02), Vec2(6, 0.02))})};
}

/// The paper's count weighting, which the hand-computed fusions below assume (these tests are about
/// which map segment a scan segment joins, not how the fusion weighs its members).
line_map_merging::FusionParams countWeighting()
{
  line_map_merging::FusionParams p;
  p.weighting = line_map_merging::FusionWeighting::count;
  return p;
}
}  // namespace

TEST(OtoIlsm, BridgingSegmentMergesWithOneMapSegmentOnlyWhereCaeMergesAllThree)
{
  CaeRlsm cae;
  OtoIlsm oto(countWeighting());
  for (const Keyframe& k : loopCase())
  {
    cae.addKeyframe(k);
    oto.addKeyframe(k);
  }
  ASSERT_EQ(cae.segmentCount(), 1u);
  const auto map = oto.map();
  ASSERT_EQ(map.size(), 2u);  // the redundant pair over x in [3, 4] stays
  // A untouched.
  EXPECT_EQ(map[0].id, 0u);
  EXPECT_EQ(map[0].merged_count, 1u);
  expectSegment(map[0].segment, Vec2(0, 0), Vec2(4, 0));
  // B + C: barycentre ((7 + 4.5) / 2, (0.01 + 0.02) / 2), heading 0, x over [3, 9].
  EXPECT_EQ(map[1].id, 1u);
  EXPECT_EQ(map[1].merged_count, 2u);
  expectSegment(map[1].segment, Vec2(3, 0.015), Vec2(9, 0.015));
  EXPECT_EQ(oto.leafCount(), 3u);
  EXPECT_EQ(oto.keyframeCount(), 3u);
}

TEST(OtoIlsm, ClosestCandidateWinsAndTiesGoToTheSmallerId)
{
  // A at y = 0 and B at y = 0.125 are too far apart (d_max 0.1) to merge.
  const std::vector<Segment2> walls{Segment2(Vec2(0, 0), Vec2(4, 0)),
                                    Segment2(Vec2(0, 0.125), Vec2(4, 0.125))};
  {
    OtoIlsm oto(countWeighting());
    oto.addKeyframe(keyframeOf(0, Pose2(), walls));
    ASSERT_EQ(oto.segmentCount(), 2u);
    // 0.09 m from A, 0.035 m from B: joins B.
    oto.addKeyframe(keyframeOf(1, Pose2(2, 1, 0), {Segment2(Vec2(1, 0.09), Vec2(3, 0.09))}));
    const auto map = oto.map();
    ASSERT_EQ(map.size(), 2u);
    expectSegment(map[0].segment, Vec2(0, 0), Vec2(4, 0));
    expectSegment(map[1].segment, Vec2(0, 0.1075), Vec2(4, 0.1075));
  }
  {
    OtoIlsm oto(countWeighting());
    oto.addKeyframe(keyframeOf(0, Pose2(), walls));
    // 0.0625 m from both, same heading: the smaller id (A) wins.
    oto.addKeyframe(keyframeOf(1, Pose2(), {Segment2(Vec2(1, 0.0625), Vec2(3, 0.0625))}));
    const auto map = oto.map();
    ASSERT_EQ(map.size(), 2u);
    EXPECT_EQ(map[0].merged_count, 2u);
    expectSegment(map[0].segment, Vec2(0, 0.03125), Vec2(4, 0.03125));
    expectSegment(map[1].segment, Vec2(0, 0.125), Vec2(4, 0.125));
  }
}

TEST(OtoIlsm, NoAdjustmentWithoutProvenance)
{
  OtoIlsm oto(countWeighting());
  for (const Keyframe& k : loopCase()) oto.addKeyframe(k);
  const auto before = oto.map();
  EXPECT_FALSE(oto.supportsAdjustment());
  EXPECT_FALSE(oto.hasProvenance());
  const auto r = oto.adjust({{0, Pose2(1, 1, 1)}, {9, Pose2()}});
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.unknown, 1u);
  const auto after = oto.map();
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i)
  {
    EXPECT_EQ(after[i].id, before[i].id);
    EXPECT_EQ(after[i].segment.start, before[i].segment.start);
    EXPECT_EQ(after[i].segment.end, before[i].segment.end);
  }
  EXPECT_DOUBLE_EQ(oto.keyframes()[0].pose.theta, 0.3);
}

TEST(OtoIlsm, IdsStayStableAndResetRestartsThem)
{
  OtoIlsm oto(countWeighting());
  for (const Keyframe& k : loopCase()) oto.addKeyframe(k);
  oto.addKeyframe(keyframeOf(3, Pose2(), {Segment2(Vec2(0, 5), Vec2(1, 5))}));
  EXPECT_EQ(oto.map().back().id, 2u);
  oto.reset();
  EXPECT_EQ(oto.segmentCount(), 0u);
  EXPECT_EQ(oto.keyframeCount(), 0u);
  oto.addKeyframe(keyframeOf(3, Pose2(), {Segment2(Vec2(0, 5), Vec2(1, 5))}));
  EXPECT_EQ(oto.map().front().id, 0u);
}

TEST(OtoIlsm, BadInputIsCountedOrRejectedWithoutChangingTheMap)
{
  OtoIlsm oto(countWeighting());
  expectBadInputRejected(oto);
}

TEST(OtoIlsm, FactoryBuildsEveryNamedMergerAndRejectsUnknownNames)
{
  linemap::ParamSet params;
  for (const std::string& name : line_map_merging::mergerNames())
    EXPECT_EQ(line_map_merging::makeMerger(name, params)->name(), name);
  EXPECT_THROW(line_map_merging::makeMerger("nope", params), linemap::ParameterError);
  params.set("fusion/max_distance", "-1");
  try
  {
    line_map_merging::makeMerger("oto", params);
    FAIL() << "a negative distance was accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("fusion/max_distance"), std::string::npos);
  }
}
