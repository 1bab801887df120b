// Scoring a map of a building that changed between two sessions: the true faces before and after cut into
// removed, added and unchanged pieces (hand-made worlds, every face seen whole by one scan), and a map's
// share of each, worked out by hand.
#include <gtest/gtest.h>

#include <vector>

#include "line_map_eval/metrics/change_coverage.hpp"

namespace
{
using line_map_eval::ChangePieces;
using line_map_eval::ChangeScores;
using line_map_eval::GroundTruth;
using line_map_eval::GroundTruthParams;
using linemap::Segment2;
using linemap::Vec2;

/// A truth whose faces one scan sees whole, each by 200 beams.
GroundTruth seenWhole(const std::vector<Segment2>& faces)
{
  GroundTruth t;
  t.walls = faces;
  t.scans.emplace_back();
  for (std::size_t f = 0; f < faces.size(); ++f) t.scans.back().visible.push_back({f, faces[f], 200, {}});
  return t;
}

double totalLength(const std::vector<Segment2>& pieces)
{
  double sum = 0.0;
  for (const Segment2& s : pieces) sum += s.length();
  return sum;
}

// Before: a wall y = 0 (x 0..4) and one y = 2 (x 0..4). After: the first runs on to x = 6, the second is
// gone, and a new one stands at y = 3 (x 0..2).
const Segment2 kBottom(Vec2(0, 0), Vec2(4, 0)), kMiddle(Vec2(0, 2), Vec2(4, 2));
const Segment2 kBottomLonger(Vec2(0, 0), Vec2(6, 0)), kTop(Vec2(0, 3), Vec2(2, 3));

TEST(ChangeCoverage, FacesAreCutIntoRemovedAddedAndUnchangedPieces)
{
  const ChangePieces p = line_map_eval::changePieces(seenWhole({kBottom, kMiddle}),
                                                     seenWhole({kBottomLonger, kTop}), GroundTruthParams());
  EXPECT_NEAR(totalLength(p.removed), 4.0, 1e-9);    // y = 2
  EXPECT_NEAR(totalLength(p.added), 4.0, 1e-9);      // y = 0 from x = 4 to 6, and y = 3
  EXPECT_NEAR(totalLength(p.unchanged), 4.0, 1e-9);  // y = 0 up to x = 4
  ASSERT_EQ(p.removed.size(), 1u);
  EXPECT_NEAR((p.removed[0].start - kMiddle.start).norm(), 0.0, 1e-9);
  // The other face of a wall runs the other way: it is no overlay.
  const Segment2 reversed(kBottom.end, kBottom.start);
  const ChangePieces q =
      line_map_eval::changePieces(seenWhole({kBottom}), seenWhole({reversed}), GroundTruthParams());
  EXPECT_NEAR(totalLength(q.removed), 4.0, 1e-9);
  EXPECT_NEAR(totalLength(q.added), 4.0, 1e-9);
  EXPECT_TRUE(q.unchanged.empty());
}

TEST(ChangeCoverage, AMapIsScoredOnEachKindOfPiece)
{
  const ChangePieces p = line_map_eval::changePieces(seenWhole({kBottom, kMiddle}),
                                                     seenWhole({kBottomLonger, kTop}), GroundTruthParams());
  // The old map: the removed wall still in it, the new ones not.
  ChangeScores old_map = line_map_eval::scoreChanges(p, {kBottom, kMiddle}, GroundTruthParams());
  EXPECT_NEAR(old_map.removed_retired, 0.0, 1e-9);
  EXPECT_NEAR(old_map.added_coverage, 0.0, 1e-9);
  EXPECT_NEAR(old_map.unchanged_coverage, 100.0, 1e-9);
  // The map of the building now.
  ChangeScores now = line_map_eval::scoreChanges(p, {kBottomLonger, kTop}, GroundTruthParams());
  EXPECT_NEAR(now.removed_retired, 100.0, 1e-9);
  EXPECT_NEAR(now.added_coverage, 100.0, 1e-9);
  EXPECT_NEAR(now.unchanged_coverage, 100.0, 1e-9);
  // Half the removed wall kept (x 2..4), the new wall y = 3 missing: the kept half covers the removed wall
  // from x = 2 - coverage_tolerance (0.05 m), 2.05 of its 4 m, so 48.75 % is retired; 2 of the 4 added
  // metres are covered.
  ChangeScores half =
      line_map_eval::scoreChanges(p, {kBottomLonger, Segment2(Vec2(2, 2), Vec2(4, 2))}, GroundTruthParams());
  EXPECT_NEAR(half.removed_retired, 100.0 - 100.0 * 2.05 / 4.0, 0.3);
  EXPECT_NEAR(half.added_coverage, 50.0, 1.0);
}

}  // namespace
