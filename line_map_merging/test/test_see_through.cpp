// CAE-RLSM's map that follows the building: a keyframe of a later session sees through an original of
// an earlier one when that original lies in the free triangle between its laser and a segment it
// extracted; seen through by see_through_views keyframes, the original is retired and its map segment
// re-fused from the rest or retired. All expectations are worked out by hand from the geometry below.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cae_test.hpp"

namespace
{
// Every keyframe's laser sits at the origin facing +x, so laser frame = map frame. Segments run with the
// free side (the origin) on their left.
// The earlier session's wall y = 2, x in [-2, 2] (4 m), as two 2 m originals of one keyframe.
const Segment2 kOldWallRight(Vec2(2.0, 2.0), Vec2(0.0, 2.0));
const Segment2 kOldWallLeft(Vec2(0.0, 2.0), Vec2(-2.0, 2.0));
// The wall behind it, y = 5, x in [-6, 6]: from the origin its free triangle, eroded by 0.25 m, covers the
// line y = 2 for |x| < 2.4 - 0.25 / cos(atan(6 / 5)) = 2.01, so the whole old wall lies in it.
const Segment2 kBackWall(Vec2(6.0, 5.0), Vec2(-6.0, 5.0));

/// The margin the triangles below are worked out for.
CaeParams withMargin025()
{
  CaeParams p;
  p.see_through_margin = 0.25;
  return p;
}

Keyframe keyframe(std::uint64_t index, const std::vector<Segment2>& segments)
{
  Keyframe k;
  k.index = index;
  k.stamp = static_cast<double>(index);
  k.segments = segments;
  return k;
}

/// A map of session 0 with the old wall, continued: what a session file gives the next session.
CaeRlsm continuedMap(const CaeParams& params = withMargin025())
{
  CaeRlsm first(params);
  first.addKeyframe(keyframe(0, {kOldWallRight, kOldWallLeft}));
  first.addKeyframe(keyframe(1, {kOldWallRight, kOldWallLeft}));
  CaeRlsm continued(params);
  continued.loadText(first.mapText(), "session 0");
  return continued;
}

bool mapsWallAt(const std::vector<MapSegment>& map, double y)
{
  for (const MapSegment& m : map)
    if (std::abs(m.segment.start.y() - y) < 0.05 && std::abs(m.segment.end.y() - y) < 0.05) return true;
  return false;
}

TEST(SeeThrough, ALaterSessionRetiresAWallItSeesThroughTwice)
{
  CaeRlsm cae = continuedMap();
  ASSERT_EQ(cae.session(), 1u);
  ASSERT_EQ(cae.leafCount(), 4u);
  ASSERT_TRUE(mapsWallAt(cae.map(), 2.0));

  // One view is not enough (see_through_views = 2): a single mislocalised scan must not erase a wall.
  EXPECT_EQ(cae.addKeyframe(keyframe(10, {kBackWall})).retired, 0u);
  EXPECT_TRUE(mapsWallAt(cae.map(), 2.0));
  EXPECT_EQ(cae.addKeyframe(keyframe(11, {kBackWall})).retired, 4u);
  const std::vector<MapSegment> map = cae.map();
  EXPECT_FALSE(mapsWallAt(map, 2.0));
  EXPECT_TRUE(mapsWallAt(map, 5.0));
  EXPECT_EQ(cae.leafCount(), 2u);  // the back wall's two originals
  EXPECT_EQ(cae.retiredLeaves(), 4u);
  EXPECT_EQ(cae.retiredSegments(), 1u);
  ASSERT_EQ(cae.keyframes().back().session, 1u);
}

TEST(SeeThrough, NothingIsRetiredWithinOneSession)
{
  // Drift before a loop closes makes a scan see through walls of its own session: they stay.
  CaeRlsm cae(withMargin025());
  cae.addKeyframe(keyframe(0, {kOldWallRight, kOldWallLeft}));
  for (std::uint64_t i = 1; i < 5; ++i) EXPECT_EQ(cae.addKeyframe(keyframe(i, {kBackWall})).retired, 0u);
  EXPECT_TRUE(mapsWallAt(cae.map(), 2.0));
  EXPECT_EQ(cae.session(), 0u);
}

TEST(SeeThrough, AWallSeenInPlaceInBetweenKeepsIt)
{
  // Through, in place, through: the view in place clears the first vote, so two views through do not
  // follow each other and the wall stays (a door that was open once).
  CaeRlsm cae = continuedMap();
  const Segment2 wall_again(Vec2(2.0, 2.03), Vec2(-2.0, 2.03));  // 3 cm off: within the margin
  EXPECT_EQ(cae.addKeyframe(keyframe(10, {kBackWall})).retired, 0u);
  EXPECT_EQ(cae.addKeyframe(keyframe(11, {wall_again})).retired, 0u);
  EXPECT_EQ(cae.addKeyframe(keyframe(12, {kBackWall})).retired, 0u);
  EXPECT_TRUE(mapsWallAt(cae.map(), 2.0));
  EXPECT_EQ(cae.retiredLeaves(), 0u);
}

TEST(SeeThrough, AWallBehindTheSegmentStays)
{
  CaeParams params = withMargin025();
  params.see_through_views = 1;
  // The back wall is the old one now: a new wall in front of it (y = 2) hides it, never sees through it.
  CaeRlsm first(params);
  first.addKeyframe(keyframe(0, {kBackWall}));
  CaeRlsm cae(params);
  cae.loadText(first.mapText(), "session 0");
  EXPECT_EQ(cae.addKeyframe(keyframe(10, {kOldWallRight, kOldWallLeft})).retired, 0u);
  EXPECT_EQ(cae.addKeyframe(keyframe(11, {kOldWallRight, kOldWallLeft})).retired, 0u);
  EXPECT_TRUE(mapsWallAt(cae.map(), 5.0));
}

TEST(SeeThrough, AWallAlongTheTrianglesSideStays)
{
  // A corridor's side wall seen at a grazing angle: it runs along the ray from the laser to the end
  // wall's corner (1, 6), 5 cm inside the triangle (pose error). Unit ray u = (1, 6) / sqrt(37); the wall
  // is s u + 0.05 (-u.y, u.x) for s in [1.5, 5.5].
  const Vec2 u = Vec2(1.0, 6.0).normalized(), inward(-u.y(), u.x());
  const Segment2 side(5.5 * u + 0.05 * inward, 1.5 * u + 0.05 * inward);
  const Segment2 end_wall(Vec2(1.0, 6.0), Vec2(-1.0, 6.0));
  const auto retiredWith = [&](double margin)
  {
    CaeParams params;
    params.see_through_views = 1;
    params.see_through_margin = margin;
    CaeRlsm first(params);
    first.addKeyframe(keyframe(0, {side}));
    CaeRlsm cae(params);
    cae.loadText(first.mapText(), "session 0");
    return cae.addKeyframe(keyframe(10, {end_wall})).retired;
  };
  EXPECT_EQ(retiredWith(0.25), 0u);  // 5 cm from the side: within the margin
  // Without the erosion the whole wall lies in the triangle and would go.
  EXPECT_EQ(retiredWith(0.001), 1u);
}

TEST(SeeThrough, AMapSegmentIsReFusedFromTheOriginalsLeft)
{
  // The right half of the old wall is gone: the back wall shows through there, while the left half is
  // seen in place. Right original: the triangle before (8, 5)-(0.5, 5), eroded, covers y = 2 over
  // x in [0.2 + 0.25 sqrt(0.5^2 + 5^2) / 5, 3.2 - 0.25 sqrt(8^2 + 5^2) / 5] = [0.45, 2.73]; of [0, 2] that
  // is 1.55 m, over half. Left original: in place over 1.5 m of 2.
  CaeRlsm cae = continuedMap();
  const Segment2 back_right(Vec2(8.0, 5.0), Vec2(0.5, 5.0));
  const Segment2 left_half(Vec2(-0.5, 2.0), Vec2(-2.0, 2.0));
  cae.addKeyframe(keyframe(10, {back_right, left_half}));
  EXPECT_EQ(cae.addKeyframe(keyframe(11, {back_right, left_half})).retired, 2u);  // both keyframes' rights
  bool found = false;
  for (const MapSegment& m : cae.map())
  {
    if (std::abs(m.segment.start.y() - 2.0) > 0.05) continue;
    found = true;
    // Re-fused from the left originals (old and new): it ends where they end, x = 0, not at x = 2.
    EXPECT_NEAR(std::max(m.segment.start.x(), m.segment.end.x()), 0.0, 1e-6);
    EXPECT_NEAR(std::min(m.segment.start.x(), m.segment.end.x()), -2.0, 1e-6);
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(cae.retiredSegments(), 0u);
}

TEST(SeeThrough, SessionsSurviveTheFileAndAdjustmentKeepsRetiredOriginalsOut)
{
  // A map of one session is written without sessions, as before they existed.
  CaeRlsm first;
  first.addKeyframe(keyframe(0, {kOldWallRight, kOldWallLeft}));
  EXPECT_NE(first.mapText().find("- [0, 0, 0, 0, 0, 0, 0, 0]"), std::string::npos) << first.mapText();

  CaeRlsm cae = continuedMap();
  cae.addKeyframe(keyframe(10, {kBackWall}));
  cae.addKeyframe(keyframe(11, {kBackWall}));
  const std::string text = cae.mapText();
  EXPECT_NE(text.find("- [11, 11, 0, 0, 0, 0, 0, 0, 1]"), std::string::npos) << text;
  CaeRlsm again;
  again.loadText(text, "session 1");
  EXPECT_EQ(again.session(), 2u);
  EXPECT_EQ(again.mapText(), text);

  // MP-GMA rebuilds from the provenance: the retired originals are not in it any more.
  const std::size_t leaves = cae.leafCount();
  cae.adjust({{0, Pose2(0.0, 0.0, 0.0)}, {11, Pose2(0.0, 0.0, 0.0)}});
  EXPECT_EQ(cae.leafCount(), leaves);
  EXPECT_FALSE(mapsWallAt(cae.map(), 2.0));
}

TEST(SeeThrough, ParametersAreChecked)
{
  CaeParams p;
  p.see_through_margin = 0.0;
  EXPECT_THROW(p.validate(), linemap::ParameterError);
  p = CaeParams();
  p.see_through_views = 0;
  EXPECT_THROW(p.validate(), linemap::ParameterError);
}

}  // namespace
