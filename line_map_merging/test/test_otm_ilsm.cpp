// OTM-ILSM: incremental one-to-many merging, and the spatial index against the linear reference.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "cae_test.hpp"
#include "segment_checks.hpp"
#include "synthetic_world.hpp"

using synthetic::keyframeOf;

namespace
{
/// Keyframes driving along x under walls `walls`, heading wobbling, noisy segments.
std::vector<Keyframe> drive(const std::vector<Segment2>& walls, int scans, std::uint32_t seed)
{
  std::mt19937 rng(seed);
  std::vector<Keyframe> out;
  for (int k = 0; k < scans; ++k)
  {
    const Pose2 pose(0.2 * k, 0.0, 0.3 * std::sin(0.7 * k));
    Keyframe kf;
    kf.index = static_cast<std::uint64_t>(k);
    kf.stamp = k;
    kf.pose = pose;
    for (const Segment2& w : walls)
      if (auto v = synthetic::visiblePart(w, pose.translation(), 4.0, 0.3))
        kf.segments.push_back(synthetic::addNoise(v->transformed(pose.inverse()), rng, 0.005, 0.005, 0.01));
    out.push_back(std::move(kf));
  }
  return out;
}
}  // namespace

TEST(OtmIlsm, WallSeenInFiftyNoisyScansIsOneSegment)
{
  CaeRlsm merger;
  std::size_t segments = 0;
  for (const Keyframe& k : drive({Segment2(Vec2(0, 2), Vec2(10, 2))}, 50, 1))
  {
    ASSERT_EQ(k.segments.size(), 1u);
    segments += merger.addKeyframe(k).merged;
  }
  ASSERT_EQ(segments, 50u);
  const auto map = merger.map();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0].id, 0u);
  EXPECT_EQ(map[0].merged_count, 50u);
  EXPECT_NEAR(map[0].segment.start.y(), 2.0, 0.01);
  EXPECT_NEAR(map[0].segment.end.y(), 2.0, 0.01);
  EXPECT_NEAR(map[0].segment.start.x(), 0.0, 0.05);
  EXPECT_NEAR(map[0].segment.end.x(), 10.0, 0.05);
  EXPECT_EQ(merger.leafCount(), 50u);
  EXPECT_EQ(merger.leaves(0).size(), 50u);
}

TEST(OtmIlsm, ParallelWallsThirtyCentimetresApartStayTwo)
{
  CaeRlsm merger;
  for (const Keyframe& k :
       drive({Segment2(Vec2(0, 2), Vec2(10, 2)), Segment2(Vec2(0, 2.3), Vec2(10, 2.3))}, 50, 2))
    merger.addKeyframe(k);
  const auto map = merger.map();
  ASSERT_EQ(map.size(), 2u);
  const double y0 = map[0].segment.midpoint().y(), y1 = map[1].segment.midpoint().y();
  EXPECT_NEAR(std::min(y0, y1), 2.0, 0.01);
  EXPECT_NEAR(std::max(y0, y1), 2.3, 0.01);
  EXPECT_EQ(map[0].merged_count + map[1].merged_count, 100u);
}

TEST(OtmIlsm, OneSegmentBridgingTheTwoEndsOfALoopMergesAllThree)
{
  CaeRlsm merger;
  merger.addKeyframe(
      keyframeOf(0, Pose2(0, -1, 0.3), {Segment2(Vec2(0, 0), Vec2(4, 0))}));  // start of the loop
  merger.addKeyframe(keyframeOf(1, Pose2(8, -1, -0.2), {Segment2(Vec2(5, 0), Vec2(9, 0))}));  // end: 1 m gap
  ASSERT_EQ(merger.segmentCount(), 2u);
  merger.addKeyframe(
      keyframeOf(2, Pose2(4.5, 1, 0.1), {Segment2(Vec2(3, 0.02), Vec2(6, 0.02))}));  // bridges both
  const auto map = merger.map();
  ASSERT_EQ(map.size(), 1u);  // a one-to-one merge would leave two
  EXPECT_EQ(map[0].id, 0u);   // the smallest id survives
  EXPECT_EQ(map[0].merged_count, 3u);
  // Length weighting (4, 4 and 3 m): centre of mass y = 3 * 0.02 / 11 at x = (8 + 28 + 13.5) / 11 = 4.5,
  // the middle of the bridging segment, so the principal axis is x: the line y = 0.06/11 over [0, 9].
  EXPECT_NEAR(map[0].segment.start.x(), 0.0, 1e-9);
  EXPECT_NEAR(map[0].segment.end.x(), 9.0, 1e-9);
  EXPECT_NEAR(map[0].segment.start.y(), 0.06 / 11.0, 1e-9);
  EXPECT_NEAR(map[0].segment.end.y(), 0.06 / 11.0, 1e-9);
  EXPECT_EQ(merger.leaves(0).size(), 3u);
  // The merged id 1 is gone for good: the next new segment gets a fresh id.
  merger.addKeyframe(keyframeOf(3, Pose2(), {Segment2(Vec2(0, 5), Vec2(1, 5))}));
  EXPECT_EQ(merger.map().back().id, 2u);
}

TEST(OtmIlsm, BadInputIsCountedOrRejectedWithoutChangingTheMap)
{
  CaeRlsm merger;
  expectBadInputRejected(merger);
}

TEST(OtmIlsm, SpatialIndexAndLinearSearchGiveIdenticalMaps)
{
  // 10,000 noisy views of 300 random walls, 10 per keyframe, from random poses.
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> pos(0.0, 60.0), ang(-linemap::kPi, linemap::kPi), len(1.0, 6.0),
      frac(0.0, 1.0);
  std::vector<Segment2> walls;
  for (int i = 0; i < 300; ++i)
  {
    const Vec2 a(pos(rng), pos(rng));
    const double h = ang(rng);
    walls.emplace_back(a, a + len(rng) * Vec2(std::cos(h), std::sin(h)));
  }
  std::vector<Keyframe> keyframes;
  for (int k = 0; k < 1000; ++k)
  {
    std::vector<Segment2> world;
    for (int j = 0; j < 10; ++j)
    {
      const Segment2& w = walls[rng() % walls.size()];
      double t0 = frac(rng), t1 = frac(rng);
      if (t1 < t0) std::swap(t0, t1);
      t1 = std::max(t1, t0 + 0.1);
      const Segment2 part(w.start + t0 * (w.end - w.start), w.start + t1 * (w.end - w.start));
      world.push_back(synthetic::addNoise(part, rng, 0.02, 0.015, 0.02));
    }
    keyframes.push_back(
        keyframeOf(static_cast<std::uint64_t>(k), Pose2(pos(rng), pos(rng), ang(rng)), world));
  }
  CaeParams indexed, linear;
  linear.spatial_index = false;
  CaeRlsm a(indexed), b(linear);
  for (const Keyframe& k : keyframes)
  {
    a.addKeyframe(k);
    b.addKeyframe(k);
  }
  const auto ma = a.map(), mb = b.map();
  ASSERT_EQ(a.leafCount(), 10000u);
  ASSERT_EQ(ma.size(), mb.size());
  EXPECT_LT(ma.size(), 3000u) << "too few merges for the comparison to mean anything";
  std::size_t multi = 0;
  for (std::size_t i = 0; i < ma.size(); ++i)
  {
    ASSERT_EQ(ma[i].id, mb[i].id);
    ASSERT_EQ(ma[i].merged_count, mb[i].merged_count);
    EXPECT_EQ(ma[i].segment.start, mb[i].segment.start) << "id " << ma[i].id;
    EXPECT_EQ(ma[i].segment.end, mb[i].segment.end) << "id " << ma[i].id;
    multi += ma[i].merged_count > 1;
  }
  EXPECT_GT(multi, 100u);
}

TEST(MapMerge, SegmentsThatMeetOnlyWithTheOtherAsMapSegmentAreMerged)
{
  // M: 0.6 m along y = 0. S: 6 m through M's middle, 3 deg off (within theta_max = 4 deg). As a scan
  // segment S fails the vertical distance to M's line (3 sin 3 deg = 0.157 m > d_max = 0.1 m), so
  // OTM-ILSM starts a new map segment; the other way round M's endpoints lie 0.3 sin 3 deg = 0.016 m
  // from S's line and overlap it fully: the two are redundant, and the map-level merge joins them.
  const double a = 3.0 * linemap::kPi / 180.0;
  const Vec2 u(std::cos(a), std::sin(a)), mid(0.3, 0.0);
  const Segment2 m(Vec2(0, 0), Vec2(0.6, 0)), s(mid - 3.0 * u, mid + 3.0 * u);
  ASSERT_FALSE(line_map_merging::meetsFusionConditions(m, s, line_map_merging::FusionParams()));
  ASSERT_TRUE(line_map_merging::meetEachOther(m, s, line_map_merging::FusionParams()));
  for (bool map_merge : {false, true})
  {
    CaeParams params;
    params.map_merge = map_merge;
    params.single_view_min_length = 0.0;  // M is 0.6 m, seen once: shown, as the paper shows it
    CaeRlsm merger(params);
    merger.addKeyframe(keyframeOf(0, Pose2(0.2, -1, 0.4), {m}));
    merger.addKeyframe(keyframeOf(1, Pose2(1, 1, -0.3), {s}));
    const auto map = merger.map();
    if (!map_merge)
    {
      EXPECT_EQ(map.size(), 2u) << "the paper's OTM-ILSM keeps them apart";
      continue;
    }
    ASSERT_EQ(map.size(), 1u);
    EXPECT_EQ(map[0].id, 0u);  // the smallest id survives and takes the other's leaves
    EXPECT_EQ(merger.leaves(0).size(), 2u);
    EXPECT_EQ(merger.leafCount(), 2u);
    // Length weighting: the 6 m segment dominates; the fused line stays within 4 deg of S.
    EXPECT_LT(std::abs(linemap::normalizeAngle(map[0].segment.heading() - a)), 0.5 * a);
  }
}

TEST(MapMerge, ASegmentInsideAnothersBandIsAbsorbedBeyondThetaMax)
{
  // A 5 m wall, then a 0.7 m glimpse of it fitted 6 deg off (beyond theta_max = 4 deg) whose ends lie
  // 0.037 m from the wall's line and project onto the wall: the fusion conditions fail both ways
  // round (heading), the segment lies inside the wall's d_max band. The other face of a 0.05 m wall
  // beside them, equally inside the band but facing the other way, must stay.
  const double a = 6.0 * linemap::kPi / 180.0;
  const Vec2 u(std::cos(a), std::sin(a)), mid(2.5, 0.0);
  const Segment2 wall(Vec2(0, 0), Vec2(5, 0)), glimpse(mid - 0.35 * u, mid + 0.35 * u);
  const Segment2 other_face(Vec2(3.5, -0.05), Vec2(1.5, -0.05));
  ASSERT_FALSE(line_map_merging::meetEachOther(wall, glimpse, line_map_merging::FusionParams()));
  for (bool absorb : {false, true})
  {
    CaeParams params;
    params.absorb_contained = absorb;
    params.single_view_min_length = 0.0;  // every segment is seen once here: count them all
    CaeRlsm merger(params);
    merger.addKeyframe(keyframeOf(0, Pose2(1, 1, 0.2), {wall}));
    merger.addKeyframe(keyframeOf(1, Pose2(2, 1.5, -0.4), {glimpse}));
    merger.addKeyframe(keyframeOf(2, Pose2(2, -1.5, 0.4), {other_face}));
    const auto map = merger.map();
    ASSERT_EQ(map.size(), absorb ? 2u : 3u);
    if (!absorb) continue;
    EXPECT_EQ(merger.leaves(0).size(), 2u);  // the wall kept its id and took the glimpse's leaf
    // Length weighting: 0.7 m at 6 deg tilts the 5 m wall by about 0.7 / 5.7 * 6 = 0.7 deg, and its
    // extent stays the wall's (the glimpse projects inside it).
    EXPECT_LT(std::abs(map[0].segment.heading()), 1.0 * linemap::kPi / 180.0);
    EXPECT_NEAR(map[0].segment.length(), 5.0, 0.01);
  }
}
