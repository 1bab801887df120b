// O2TO-ILSM: OTO-ILSM replayed over the final poses, whatever poses the keyframes arrived with.
#include <gtest/gtest.h>

#include <random>

#include "line_map_merging/mergers/o2to_ilsm.hpp"
#include "line_map_merging/mergers/oto_ilsm.hpp"
#include "synthetic_world.hpp"

using line_map_merging::Keyframe;
using line_map_merging::MapSegment;
using line_map_merging::O2toIlsm;
using line_map_merging::OtoIlsm;
using linemap::Pose2;

namespace
{
struct LoopRun
{
  std::vector<Keyframe> drifted;  // as they arrive, with odometry poses
  std::vector<Keyframe> final;    // the same keyframes at the true (optimised) poses
};

LoopRun loopRun()
{
  synthetic::Corridor corridor;
  std::mt19937 rng(5);
  const auto truth = corridor.loop(0.5, 4.0);
  const auto believed = synthetic::drift(truth, 0.004, 0.002, 1.01, rng);
  LoopRun run;
  run.drifted = synthetic::observe(corridor.walls(), truth, believed, 5.0, rng);
  run.final = run.drifted;
  for (std::size_t i = 0; i < truth.size(); ++i) run.final[i].pose = truth[i];
  return run;
}

void expectIdentical(const std::vector<MapSegment>& a, const std::vector<MapSegment>& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].merged_count, b[i].merged_count);
    EXPECT_EQ(a[i].segment.start, b[i].segment.start) << "segment " << i;
    EXPECT_EQ(a[i].segment.end, b[i].segment.end) << "segment " << i;
  }
}
}  // namespace

TEST(O2toIlsm, AdjustedToTheFinalPosesEqualsOtoFedTheFinalPoses)
{
  const LoopRun run = loopRun();
  OtoIlsm oto_final, oto_drifted;
  O2toIlsm o2to;
  for (std::size_t i = 0; i < run.final.size(); ++i)
  {
    oto_final.addKeyframe(run.final[i]);
    oto_drifted.addKeyframe(run.drifted[i]);
    o2to.addKeyframe(run.drifted[i]);
  }
  // Before the adjustment it is OTO over the poses it was given (and fills the cache).
  expectIdentical(o2to.map(), oto_drifted.map());

  std::vector<std::pair<std::uint64_t, Pose2>> poses;
  for (const Keyframe& k : run.final) poses.emplace_back(k.index, k.pose);
  poses.emplace_back(99999, Pose2());
  const auto r = o2to.adjust(poses);
  EXPECT_EQ(r.moved, run.final.size());
  EXPECT_EQ(r.unknown, 1u);
  const auto map = o2to.map();
  expectIdentical(map, oto_final.map());
  // The drift must have made a difference, or the comparison above proves nothing.
  EXPECT_NE(map.size(), oto_drifted.segmentCount());
  EXPECT_LT(map.size(), oto_final.leafCount() / 4);
  EXPECT_EQ(o2to.leafCount(), oto_final.leafCount());
  EXPECT_EQ(o2to.keyframes()[3].pose.x, run.final[3].pose.x);
  EXPECT_TRUE(o2to.supportsAdjustment());
}

TEST(O2toIlsm, StoresKeyframesAndRejectsDuplicates)
{
  const LoopRun run = loopRun();
  O2toIlsm o2to;
  o2to.addKeyframe(run.final[0]);
  EXPECT_THROW(o2to.addKeyframe(run.final[0]), std::invalid_argument);
  EXPECT_EQ(o2to.keyframeCount(), 1u);
  o2to.reset();
  EXPECT_EQ(o2to.keyframeCount(), 0u);
  EXPECT_EQ(o2to.segmentCount(), 0u);
}
