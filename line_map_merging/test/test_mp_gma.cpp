// MP-GMA: re-fusing from the provenance under new keyframe poses, with and without the
// consistency pass, on a synthetic corridor loop with odometry drift.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "cae_test.hpp"
#include "synthetic_world.hpp"

namespace
{
struct LoopData
{
  std::vector<Pose2> truth;
  std::vector<Pose2> drifted;
  std::vector<Keyframe> keyframes;  // posed at the drifted poses
};

LoopData makeLoop(std::uint32_t seed)
{
  synthetic::Corridor corridor;
  LoopData d;
  std::mt19937 rng(seed);
  d.truth = corridor.loop(0.5, 6.0);
  d.drifted = synthetic::drift(d.truth, 0.003, 0.002, 1.01, rng);
  d.keyframes = synthetic::observe(corridor.walls(), d.truth, d.drifted, 4.0, rng);
  return d;
}

/// Merges the keyframes of `d` into `merger` on their true poses.
void mergeOnTruePoses(const LoopData& d, CaeRlsm& merger)
{
  for (Keyframe k : d.keyframes)
  {
    k.pose = d.truth[k.index];
    merger.addKeyframe(k);
  }
}

/// Largest endpoint distance between each segment of `a` and its best match in `b` (same heading).
double maxEndpointDifference(const std::vector<MapSegment>& a, const std::vector<MapSegment>& b)
{
  double worst = 0.0;
  for (const MapSegment& s : a)
  {
    double best = std::numeric_limits<double>::infinity();
    for (const MapSegment& t : b)
    {
      if (std::abs(linemap::normalizeAngle(s.segment.heading() - t.segment.heading())) > 0.5) continue;
      best = std::min(
          best, std::max((s.segment.start - t.segment.start).norm(), (s.segment.end - t.segment.end).norm()));
    }
    worst = std::max(worst, best);
  }
  return worst;
}
}  // namespace

TEST(MpGma, EverySegmentIsTheFusionOfItsLeavesUnderTheNewPoses)
{
  const LoopData d = makeLoop(3);
  CaeParams paper;
  paper.consistent_adjustment = false;
  paper.resolve_crossings = false;  // cutting would make segments shorter than their leaves' fusion
  CaeRlsm merger(paper);
  for (const Keyframe& k : d.keyframes) merger.addKeyframe(k);
  const auto before = merger.map();
  const auto result = merger.adjust(indexedPoses(d.truth));
  EXPECT_EQ(result.moved, d.truth.size());
  EXPECT_EQ(result.unknown, 0u);
  const auto after = merger.map();
  ASSERT_EQ(after.size(), before.size());  // the paper's adjustment never changes the grouping
  double moved = 0.0;
  for (std::size_t i = 0; i < after.size(); ++i)
  {
    ASSERT_EQ(after[i].id, before[i].id);
    std::vector<line_map_merging::WeightedSegment> leaves;
    for (const auto& leaf : merger.leaves(after[i].id))
      leaves.push_back({leaf.segment.transformed(d.truth[leaf.keyframe]), 1.0});
    const Segment2 expected = line_map_merging::fuse(leaves, paper.fusion.weighting);
    EXPECT_NEAR((after[i].segment.start - expected.start).norm(), 0.0, 1e-9) << "id " << after[i].id;
    EXPECT_NEAR((after[i].segment.end - expected.end).norm(), 0.0, 1e-9) << "id " << after[i].id;
    moved = std::max(moved, (after[i].segment.start - before[i].segment.start).norm());
  }
  EXPECT_GT(moved, 0.1) << "the drift should have displaced the map";
}

TEST(MpGma, ConsistentAdjustmentEqualsTheMapBuiltOnTheTruePoses)
{
  const LoopData d = makeLoop(4);
  CaeRlsm reference;
  mergeOnTruePoses(d, reference);
  const auto ref = reference.map();
  EXPECT_EQ(ref.size(), 8u) << "one segment per corridor wall";

  CaeRlsm merger;  // consistent adjustment is the default
  for (const Keyframe& k : d.keyframes) merger.addKeyframe(k);
  const std::size_t drifted_count = merger.segmentCount();
  EXPECT_GT(drifted_count, ref.size()) << "the drift should have broken the loop";
  const auto result = merger.adjust(indexedPoses(d.truth));
  const auto adjusted = merger.map();
  ASSERT_EQ(adjusted.size(), ref.size()) << "split " << result.split << ", merged " << result.merged;
  std::size_t leaves = 0;
  for (const MapSegment& s : adjusted) leaves += s.merged_count;
  EXPECT_EQ(leaves, merger.leafCount());
  const double diff = std::max(maxEndpointDifference(adjusted, ref), maxEndpointDifference(ref, adjusted));
  std::printf("drifted map %zu segments, adjusted %zu, true-pose map %zu; max endpoint difference %.3g m\n",
              drifted_count, adjusted.size(), ref.size(), diff);
  EXPECT_LT(diff, 0.001);

  // The paper's behaviour keeps the broken grouping: more segments than walls.
  CaeParams paper;
  paper.consistent_adjustment = false;
  CaeRlsm plain(paper);
  for (const Keyframe& k : d.keyframes) plain.addKeyframe(k);
  plain.adjust(indexedPoses(d.truth));
  std::printf("paper (no consistency pass): %zu segments\n", plain.segmentCount());
  EXPECT_GT(plain.segmentCount(), ref.size());
}

TEST(MpGma, UnknownKeyframesAreCountedAndThreadCountDoesNotMatter)
{
  const LoopData d = makeLoop(5);
  CaeParams one, two;
  one.threads = 1;
  two.threads = 2;
  CaeRlsm a(one), b(two);
  for (const Keyframe& k : d.keyframes)
  {
    a.addKeyframe(k);
    b.addKeyframe(k);
  }
  auto poses = indexedPoses(d.truth);
  poses.emplace_back(999999, Pose2(1, 2, 3));
  const auto ra = a.adjust(poses);
  b.adjust(poses);
  EXPECT_EQ(ra.unknown, 1u);
  EXPECT_EQ(ra.moved, d.truth.size());
  const auto ma = a.map(), mb = b.map();
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i)
  {
    EXPECT_EQ(ma[i].id, mb[i].id);
    EXPECT_EQ(ma[i].segment.start, mb[i].segment.start);
    EXPECT_EQ(ma[i].segment.end, mb[i].segment.end);
  }
  std::vector<std::pair<std::uint64_t, Pose2>> bad{{0, Pose2(std::nan(""), 0, 0)}};
  EXPECT_THROW(a.adjust(bad), std::invalid_argument);
  EXPECT_EQ(a.map().size(), ma.size());
  // Finite but absurd (the fuzzer's 1.35e308): the fused sums of squares would overflow to NaN.
  const std::uint64_t first = d.keyframes.front().index;
  bad = {{first, Pose2(1.35e308, 0, 0)}, {first, Pose2(0, 2e7, 0)}};
  for (const auto& pose : bad)
    EXPECT_THROW(a.adjust({pose}), std::invalid_argument) << pose.second.x << " " << pose.second.y;
  const auto after = a.map();
  ASSERT_EQ(after.size(), ma.size());
  for (std::size_t i = 0; i < after.size(); ++i) EXPECT_EQ(after[i].segment.start, ma[i].segment.start);
}

TEST(MpGma, SegmentsAndPosesBeyondTheMapExtentAreRefused)
{
  CaeRlsm merger;
  Keyframe k;
  k.index = 1;
  k.segments = {
      {Vec2(0, 0), Vec2(1, 0)}, {Vec2(4.65, 5.18e286), Vec2(-0.5, -8.7)}, {Vec2(2e7, 0), Vec2(2e7, 1)}};
  const line_map_merging::AddResult r = merger.addKeyframe(k);
  EXPECT_EQ(r.merged, 1u);
  EXPECT_EQ(r.rejected, 2u);
  k.index = 2;
  k.pose = Pose2(-1.1e7, 0, 0);
  EXPECT_THROW(merger.addKeyframe(k), std::invalid_argument);
  EXPECT_EQ(merger.keyframeCount(), 1u);
  EXPECT_EQ(merger.leafCount(), 1u);
}

TEST(MpGma, AdjustingBackToTheOldPosesRestoresTheGrouping)
{
  // Leaves are never lost: going to the true poses and back re-creates a map with every leaf.
  const LoopData d = makeLoop(6);
  CaeRlsm merger;
  for (const Keyframe& k : d.keyframes) merger.addKeyframe(k);
  const std::size_t leaves = merger.leafCount();
  merger.adjust(indexedPoses(d.truth));
  std::vector<std::pair<std::uint64_t, Pose2>> back;
  for (std::size_t i = 0; i < d.drifted.size(); ++i) back.emplace_back(i, d.drifted[i]);
  merger.adjust(back);
  std::size_t total = 0;
  for (const MapSegment& s : merger.map()) total += s.merged_count;
  EXPECT_EQ(total, leaves);
  EXPECT_EQ(merger.leafCount(), leaves);
}

TEST(MpGma, MergingContinuesAfterAnAdjustmentIndexAndLinearAlike)
{
  // OTM-ILSM after MP-GMA searches the rebuilt index: the same map as the linear search.
  const LoopData d = makeLoop(7);
  for (bool consistent : {false, true})
  {
    CaeParams indexed, linear;
    indexed.consistent_adjustment = linear.consistent_adjustment = consistent;
    linear.spatial_index = false;
    CaeRlsm a(indexed), b(linear);
    const std::size_t half = d.keyframes.size() / 2;
    for (std::size_t i = 0; i < half; ++i)
    {
      a.addKeyframe(d.keyframes[i]);
      b.addKeyframe(d.keyframes[i]);
    }
    std::vector<std::pair<std::uint64_t, Pose2>> poses;
    for (std::size_t i = 0; i < half; ++i) poses.emplace_back(i, d.truth[i]);
    a.adjust(poses);
    b.adjust(poses);
    for (std::size_t i = half; i < d.keyframes.size(); ++i)
    {
      Keyframe k = d.keyframes[i];
      k.pose = d.truth[i];
      a.addKeyframe(k);
      b.addKeyframe(k);
    }
    const auto ma = a.map(), mb = b.map();
    ASSERT_EQ(ma.size(), mb.size()) << "consistent " << consistent;
    for (std::size_t i = 0; i < ma.size(); ++i)
    {
      EXPECT_EQ(ma[i].id, mb[i].id);
      EXPECT_EQ(ma[i].merged_count, mb[i].merged_count);
      EXPECT_EQ(ma[i].segment.start, mb[i].segment.start);
      EXPECT_EQ(ma[i].segment.end, mb[i].segment.end);
    }
    if (consistent)
    {
      EXPECT_EQ(ma.size(), 8u) << "true poses from the adjustment on: one segment per wall";
    }
  }
}

TEST(MpGma, RegroupGivesExactlyTheTruePoseMapAndKeepsIds)
{
  // Regrouping replays OTM-ILSM over the leaves in arrival order: under the true poses it is the
  // same computation as merging on them, so the maps are identical (not only within 1 mm).
  const LoopData d = makeLoop(6);
  CaeRlsm reference;
  mergeOnTruePoses(d, reference);
  CaeRlsm merger;
  ASSERT_TRUE(merger.params().regroup_on_adjust);
  for (const Keyframe& k : d.keyframes) merger.addKeyframe(k);
  merger.adjust(indexedPoses(d.truth));
  const auto ref = reference.map(), adjusted = merger.map();
  ASSERT_EQ(adjusted.size(), ref.size());
  EXPECT_EQ(maxEndpointDifference(adjusted, ref), 0.0);
  std::size_t leaves = 0;
  for (const MapSegment& s : adjusted) leaves += s.merged_count;
  EXPECT_EQ(leaves, merger.leafCount()) << "every leaf belongs to exactly one map segment";

  // Adjusting to the poses it already has replays the same merges: same segments under the same ids.
  std::vector<std::pair<std::uint64_t, linemap::Pose2>> same;
  for (const auto& k : merger.keyframes()) same.emplace_back(k.index, k.pose);
  merger.adjust(same);
  const auto again = merger.map();
  ASSERT_EQ(again.size(), adjusted.size());
  for (std::size_t i = 0; i < again.size(); ++i)
  {
    EXPECT_EQ(again[i].id, adjusted[i].id);
    EXPECT_EQ(again[i].merged_count, adjusted[i].merged_count);
    EXPECT_EQ((again[i].segment.start - adjusted[i].segment.start).norm(), 0.0);
  }
}
