// Crossing resolution in CAE-RLSM: a wall bent by 3 degrees, seen piece by piece (and, near the bend,
// as single unsplit chords), must come out as a chain meeting at the bend, incrementally and after
// MP-GMA re-fuses it under a changed trajectory; the provenance stays whole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "cae_test.hpp"
#include "line_map_merging/mergers/crossing_pairs.hpp"
#include "synthetic_world.hpp"

namespace
{
const double kBend = 3.0 * linemap::kPi / 180.0;
// The wall runs east with its free side (north) on the left: (0, 0) -> bend (6, 0) -> (12, 6 tan 3deg).
const Vec2 kStart(0.0, 0.0), kVertex(6.0, 0.0), kEnd(12.0, 6.0 * std::tan(kBend));

struct Walk
{
  std::vector<Pose2> truth;
  std::vector<Keyframe> keyframes;
  std::size_t leaves = 0;
};

/// Keyframes every 0.5 m along y = 2 m, seeing the wall within 3.5 m. A view across the bend is split
/// there unless one side is shorter than 1 m: then it is one straight chord between its visible ends
/// (less than 5 cm off the wall, within an extractor's tolerance). Posed at `believed` (truth when empty).
Walk walk(const std::vector<Pose2>& believed = {})
{
  Walk w;
  const Segment2 arm1(kStart, kVertex), arm2(kVertex, kEnd);
  for (int i = 0; i <= 24; ++i)
  {
    const Pose2 truth(0.5 * i, 2.0, 0.0);
    w.truth.push_back(truth);
    const auto p1 = synthetic::visiblePart(arm1, truth.translation(), 3.5, 0.3);
    const auto p2 = synthetic::visiblePart(arm2, truth.translation(), 3.5, 0.3);
    std::vector<Segment2> world;
    if (p1 && p2 && std::min(p1->length(), p2->length()) < 1.0)
      world.emplace_back(p1->start, p2->end);
    else
    {
      if (p1) world.push_back(*p1);
      if (p2) world.push_back(*p2);
    }
    Keyframe k;
    k.index = static_cast<std::uint64_t>(i);
    k.stamp = i;
    k.pose = believed.empty() ? truth : believed[static_cast<std::size_t>(i)];
    const Pose2 inv = truth.inverse();
    for (const Segment2& s : world) k.segments.push_back(s.transformed(inv));
    w.leaves += k.segments.size();
    w.keyframes.push_back(k);
  }
  return w;
}

std::vector<Segment2> segmentsOf(const std::vector<MapSegment>& map)
{
  std::vector<Segment2> out;
  for (const MapSegment& m : map) out.push_back(m.segment);
  return out;
}

/// The map must be a chain of two pieces, one per arm, meeting within 1 cm of each other and within
/// 5 cm of the true bend (6, 0); every leaf must be under a map segment.
void expectChain(const CaeRlsm& cae, std::size_t leaves)
{
  const std::vector<MapSegment> map = cae.map();
  EXPECT_TRUE(line_map_merging::findCrossingPairs(segmentsOf(map), 0.0).empty());
  ASSERT_EQ(map.size(), 2u);
  const bool first_west = map[0].segment.start.x() < map[1].segment.start.x();
  const Segment2& west = map[first_west ? 0 : 1].segment;
  const Segment2& east = map[first_west ? 1 : 0].segment;
  // Each piece follows its arm: headings 0 and 3 deg (a chord of both would be about 1.5 deg).
  EXPECT_NEAR(west.heading(), 0.0, 0.3 * linemap::kPi / 180.0);
  EXPECT_NEAR(east.heading(), kBend, 0.3 * linemap::kPi / 180.0);
  EXPECT_NEAR(west.start.x(), kStart.x(), 0.05);
  EXPECT_NEAR(east.end.x(), kEnd.x(), 0.05);
  EXPECT_LT((west.end - east.start).norm(), 0.01) << "the pieces do not meet";
  EXPECT_LT((west.end - kVertex).norm(), 0.05) << "vertex (" << west.end.x() << ", " << west.end.y() << ")";
  // Provenance: every original under exactly one map segment.
  std::size_t total = 0;
  for (const MapSegment& m : map)
  {
    EXPECT_EQ(cae.leaves(m.id).size(), m.merged_count);
    total += m.merged_count;
  }
  EXPECT_EQ(total, leaves);
  EXPECT_EQ(cae.leafCount(), leaves);
}

/// `m` runs from `start` to `end`, to rounding.
void expectEnds(const MapSegment& m, const Vec2& start, const Vec2& end)
{
  EXPECT_NEAR((m.segment.start - start).norm(), 0.0, 1e-9);
  EXPECT_NEAR((m.segment.end - end).norm(), 0.0, 1e-9);
}

/// A believed trajectory off the truth: heading drifting by 0.1 deg per keyframe, y by 1 cm.
std::vector<Pose2> drifted()
{
  std::vector<Pose2> out;
  for (int i = 0; i <= 24; ++i) out.emplace_back(0.5 * i, 2.0 + 0.01 * i, 0.1 * i * linemap::kPi / 180.0);
  return out;
}
}  // namespace

TEST(CrossingResolution, BentWallCrossesWithoutIt)
{
  // The configuration is one that needs the resolution: without it, two chords cross in an X.
  CaeParams params;
  params.resolve_crossings = false;
  CaeRlsm cae(params);
  for (const Keyframe& k : walk().keyframes) cae.addKeyframe(k);
  EXPECT_EQ(line_map_merging::findCrossingPairs(segmentsOf(cae.map()), 0.1).size(), 1u);
}

TEST(CrossingResolution, BentWallBecomesAChain)
{
  CaeRlsm cae;
  const Walk w = walk();
  for (const Keyframe& k : w.keyframes) cae.addKeyframe(k);
  expectChain(cae, w.leaves);
}

TEST(CrossingResolution, ChainAfterMpGmaWithAChangedTrajectory)
{
  // Merged on a drifted trajectory, then adjusted to the true one: every adjustment path re-fuses
  // from the provenance and must end in the same chain.
  for (int mode = 0; mode < 3; ++mode)
  {
    SCOPED_TRACE(mode == 0 ? "regroup" : mode == 1 ? "re-fuse + consistency pass" : "re-fuse only (paper)");
    CaeParams params;
    params.regroup_on_adjust = mode == 0;
    params.consistent_adjustment = mode < 2;
    CaeRlsm cae(params);
    const Walk w = walk(drifted());
    for (const Keyframe& k : w.keyframes) cae.addKeyframe(k);
    const auto result = cae.adjust(indexedPoses(w.truth));
    EXPECT_EQ(result.moved, w.truth.size());
    if (mode < 2) expectChain(cae, w.leaves);
    // The paper's MP-GMA keeps the groups formed on the drifted poses: no chain to expect, but no
    // crossing either, and no leaf lost.
    EXPECT_TRUE(line_map_merging::findCrossingPairs(segmentsOf(cae.map()), 0.0).empty());
    EXPECT_EQ(cae.leafCount(), w.leaves);
  }
}

TEST(CrossingResolution, MapFileKeepsTheCutSegments)
{
  CaeRlsm cae;
  const Walk w = walk();
  for (const Keyframe& k : w.keyframes) cae.addKeyframe(k);
  const std::string path = ::testing::TempDir() + "crossing_resolution_map.yaml";
  cae.save(path);
  CaeRlsm loaded;
  loaded.load(path);
  const auto a = cae.map(), b = loaded.map();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].segment.start, b[i].segment.start);
    EXPECT_EQ(a[i].segment.end, b[i].segment.end);
    EXPECT_EQ(a[i].merged_count, b[i].merged_count);
  }
  expectChain(loaded, w.leaves);
  // Re-fused from the loaded provenance at unchanged poses, the chain forms again.
  loaded.adjust(indexedPoses(w.truth));
  expectChain(loaded, w.leaves);
  std::remove(path.c_str());
}

TEST(CrossingResolution, WallThroughAnotherLosesItsOvershoot)
{
  // A wall along y = 0 from x = 0 to 4 (free side north), and a wall along x = 2 running north whose
  // segment starts 0.3 m south of it: 90 deg apart, so two walls; the least supported arm, the
  // overshoot (4 x 0.3 m against 4 x 2 m, 4 x 2 m and 4 x 3 m), is cut at (2, 0): a T.
  CaeRlsm cae;
  for (int i = 0; i < 4; ++i)
    cae.addKeyframe(synthetic::keyframeOf(
        i, Pose2(), {Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(2, -0.3), Vec2(2, 3))}));
  const auto map = cae.map();
  ASSERT_EQ(map.size(), 2u);
  expectEnds(map[0], Vec2(0, 0), Vec2(4, 0));
  expectEnds(map[1], Vec2(2, 0), Vec2(2, 3));
  EXPECT_EQ(map[0].merged_count + map[1].merged_count, 8u);
}

TEST(CrossingResolution, FacesFittedAcrossEachOtherLoseTheWeakerArm)
{
  // The two faces of a thin wall, fitted 2.9 deg apart so that they cross: the north face (0, 0) ->
  // (4, 0) running east, seen 4 times, and the south face (3, 0.05) -> (0, -0.1) running west, seen
  // twice, crossing y = 0 at x = 2. Opposite facing sides: two walls, not a bend. Arm supports: north
  // 4 x 2 m on each side; south 2 x 1.0012 m before the crossing, 2 x 2.0025 m after. The south face's
  // first arm goes: (2, 0) -> (0, -0.1).
  CaeRlsm cae;
  for (int i = 0; i < 4; ++i)
  {
    std::vector<Segment2> seen = {Segment2(Vec2(0, 0), Vec2(4, 0))};
    if (i < 2) seen.push_back(Segment2(Vec2(3, 0.05), Vec2(0, -0.1)));
    cae.addKeyframe(synthetic::keyframeOf(i, Pose2(), seen));
  }
  const auto map = cae.map();
  ASSERT_EQ(map.size(), 2u);
  expectEnds(map[0], Vec2(0, 0), Vec2(4, 0));
  expectEnds(map[1], Vec2(2, 0), Vec2(0, -0.1));
  EXPECT_EQ(map[1].merged_count, 2u);
}

TEST(CrossingResolution, BadParametersThrow)
{
  CaeParams params;
  params.crossing_overhang = 0.0;  // an exact T would cross again after rounding
  EXPECT_THROW(CaeRlsm{params}, linemap::ParameterError);
  params.crossing_overhang = 0.01;
  params.crossing_chain_angle = 0.5 * linemap::kPi;
  EXPECT_THROW(CaeRlsm{params}, linemap::ParameterError);
}

// After MP-GMA the crossings of the whole map are resolved; the indexed path first finds in parallel which
// segments cross anything and skips the others unless a pair resolved near them. The linear path (no
// index, no skipping) is the reference: both must leave the same map, in a clutter of bent walls and
// walls across them whose full extents, restored by the re-fusion, cross again. A pre-check that lets a
// crossing segment pass as clean leaves crossings and another map.
TEST(CrossingResolution, WholeMapAfterMpGmaIndexedAndLinearAlike)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> at(0.0, 12.0), heading(-linemap::kPi, linemap::kPi),
      length(0.5, 3.0), jitter(-0.05, 0.05);
  std::vector<Keyframe> keyframes;
  for (std::uint64_t k = 0; k < 40; ++k)
  {
    Keyframe kf;
    kf.index = k;
    kf.pose = Pose2(at(rng), 0.3 * at(rng), jitter(rng));
    // Walls bent by a few degrees (chains, split at their bends, which can make new crossings) and
    // walls across them (cut back to a T).
    for (int i = 0; i < 6; ++i)
    {
      const bool across = i == 5;
      const Vec2 a(jitter(rng) * 40.0, jitter(rng) * 8.0);
      const double h = across ? 0.5 * linemap::kPi + jitter(rng) * 4.0 : jitter(rng) * 2.0, l = length(rng);
      kf.segments.emplace_back(a, a + l * Vec2(std::cos(h), std::sin(h)));
    }
    keyframes.push_back(kf);
  }
  std::vector<std::pair<std::uint64_t, Pose2>> moved;
  for (const Keyframe& k : keyframes)
    moved.emplace_back(k.index,
                       Pose2(k.pose.x + jitter(rng), k.pose.y + jitter(rng), k.pose.theta + jitter(rng)));
  std::vector<MapSegment> maps[2];
  for (int linear = 0; linear < 2; ++linear)
  {
    CaeParams p;
    p.consistent_adjustment = false;  // MP-GMA as in the paper, then crossing resolution over the whole map
    p.spatial_index = linear == 0;
    CaeRlsm merger(p);
    for (const Keyframe& k : keyframes) merger.addKeyframe(k);
    merger.adjust(moved);
    maps[linear] = merger.map();
    EXPECT_TRUE(line_map_merging::findCrossingPairs(segmentsOf(maps[linear]), p.crossing_overhang).empty());
  }
  ASSERT_EQ(maps[0].size(), maps[1].size());
  for (std::size_t i = 0; i < maps[0].size(); ++i)
  {
    EXPECT_EQ(maps[0][i].id, maps[1][i].id);
    EXPECT_EQ(maps[0][i].segment.start, maps[1][i].segment.start);
    EXPECT_EQ(maps[0][i].segment.end, maps[1][i].segment.end);
  }
}

// Cutting at a crossing moves an end along its segment, which can leave it wholly within another's fusion
// band (liesWithin): two pieces of one wall cut back to one point along one line, one on the other, where
// the map merge would have absorbed it (absorb_contained). After every keyframe and after an adjustment, no
// map segment may lie within another, in clutters of short, slightly bent walls seen from jittered poses.
// (Pieces that merely meet the fusion conditions, such as overlapping chords of a curved wall, are left to
// the next keyframes' crossing resolution: a merge would fuse the curve into one chord.)
TEST(CrossingResolution, CutsLeaveNoSegmentWithinAnother)
{
  const line_map_merging::FusionParams fusion = CaeParams().fusion;
  const auto expectNoneWithin = [&](const std::vector<Segment2>& map, const std::string& when)
  {
    for (std::size_t i = 0; i < map.size(); ++i)
      for (std::size_t j = 0; j < map.size(); ++j)
        EXPECT_FALSE(i != j && line_map_merging::liesWithin(map[i], map[j], fusion))
            << when << ": segment " << j << " lies within " << i;
  };
  std::size_t checked_maps = 0;
  for (unsigned seed = 1; seed <= 60; ++seed)
  {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jitter(-1.0, 1.0), length(0.1, 0.6);
    // A few walls with bends of up to 4 degrees, each seen in pieces by every keyframe.
    std::vector<std::vector<Vec2>> walls;
    for (int w = 0; w < 3; ++w)
    {
      std::vector<Vec2> corners{Vec2(0.3 * jitter(rng), w * 0.7 + 0.02 * jitter(rng))};
      double h = 0.05 * jitter(rng) + (w == 2 ? 0.5 * linemap::kPi : 0.0);
      for (int c = 0; c < 3; ++c)
      {
        h += 0.07 * jitter(rng);
        corners.push_back(corners.back() + 0.4 * Vec2(std::cos(h), std::sin(h)));
      }
      walls.push_back(corners);
    }
    CaeRlsm cae;
    std::vector<std::pair<std::uint64_t, Pose2>> moved;
    for (std::uint64_t k = 0; k < 30; ++k)
    {
      Keyframe kf;
      kf.index = k;
      kf.stamp = static_cast<double>(k);
      kf.pose = Pose2(0.05 * jitter(rng), 0.05 * jitter(rng), 0.02 * jitter(rng));
      const Pose2 inv = kf.pose.inverse();
      for (const auto& corners : walls)
        for (std::size_t c = 0; c + 1 < corners.size(); ++c)
        {
          // A piece of this arm, its ends a little off the wall (a few cm: extractor noise).
          const double from = 0.25 * (jitter(rng) + 1.0), to = std::min(from + length(rng), 1.3);
          const Vec2 d = corners[c + 1] - corners[c], n = Vec2(-d.y(), d.x()).normalized();
          const Vec2 a = corners[c] + from * d + 0.02 * jitter(rng) * n;
          const Vec2 b = corners[c] + to * d + 0.02 * jitter(rng) * n;
          kf.segments.push_back(Segment2(a, b).transformed(inv));
        }
      cae.addKeyframe(kf);
      moved.emplace_back(
          k, Pose2(kf.pose.x + 0.01 * jitter(rng), kf.pose.y + 0.01 * jitter(rng), kf.pose.theta));
      expectNoneWithin(segmentsOf(cae.map()),
                       "seed " + std::to_string(seed) + ", keyframe " + std::to_string(k));
      ++checked_maps;
    }
    cae.adjust(moved);
    expectNoneWithin(segmentsOf(cae.map()), "seed " + std::to_string(seed) + ", after the adjustment");
  }
  EXPECT_EQ(checked_maps, 60u * 30u);
}
