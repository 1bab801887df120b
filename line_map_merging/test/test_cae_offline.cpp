// Offline CAE-RLSM: OTM-ILSM replayed over the final poses equals a CaeRlsm fed those poses.
#include <gtest/gtest.h>

#include <random>

#include "line_map_merging/mergers/cae_offline.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "synthetic_world.hpp"

using line_map_merging::CaeOffline;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using linemap::Pose2;

TEST(CaeOffline, AdjustedToTheFinalPosesEqualsCaeRlsmFedTheFinalPoses)
{
  synthetic::Corridor corridor;
  std::mt19937 rng(11);
  const auto truth = corridor.loop(0.5, 4.0);
  const auto believed = synthetic::drift(truth, 0.004, 0.002, 1.01, rng);
  const auto drifted = synthetic::observe(corridor.walls(), truth, believed, 5.0, rng);

  CaeRlsm online_final;
  CaeOffline offline;
  std::vector<std::pair<std::uint64_t, Pose2>> poses;
  for (std::size_t i = 0; i < drifted.size(); ++i)
  {
    Keyframe k = drifted[i];
    k.pose = truth[i];
    online_final.addKeyframe(k);
    offline.addKeyframe(drifted[i]);
    poses.emplace_back(k.index, truth[i]);
  }
  const std::size_t drifted_count = offline.segmentCount();  // fills the cache before the adjustment
  EXPECT_EQ(offline.adjust(poses).moved, drifted.size());

  const auto a = offline.map(), b = online_final.map();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_NE(a.size(), drifted_count) << "the drift changed nothing: the test proves nothing";
  EXPECT_LT(a.size(), online_final.leafCount() / 4);
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].merged_count, b[i].merged_count);
    EXPECT_EQ(a[i].segment.start, b[i].segment.start) << "id " << a[i].id;
    EXPECT_EQ(a[i].segment.end, b[i].segment.end) << "id " << a[i].id;
    // Provenance of the replay: the same leaves, in the laser frames.
    const auto la = offline.leaves(a[i].id), lb = online_final.leaves(b[i].id);
    ASSERT_EQ(la.size(), lb.size());
    for (std::size_t j = 0; j < la.size(); ++j) EXPECT_EQ(la[j].keyframe, lb[j].keyframe);
  }
  EXPECT_TRUE(offline.hasProvenance());
  EXPECT_EQ(offline.leafCount(), online_final.leafCount());
}

TEST(CaeOffline, BadSegmentsAreCountedAndSkipped)
{
  CaeOffline offline;
  Keyframe k;
  k.index = 3;
  k.segments = {linemap::Segment2(linemap::Vec2(0, 0), linemap::Vec2(1, 0)),
                linemap::Segment2(linemap::Vec2(2, 2), linemap::Vec2(2, 2))};
  const auto r = offline.addKeyframe(k);
  EXPECT_EQ(r.merged, 1u);
  EXPECT_EQ(r.rejected, 1u);
  EXPECT_EQ(offline.segmentCount(), 1u);
  k.index = 4;
  k.stamp = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(offline.addKeyframe(k), std::invalid_argument);
  EXPECT_EQ(offline.keyframeCount(), 1u);
}
