// CAE-RLSM's single-view rule: a short map segment whose originals all come from one keyframe is
// withheld from the map until an original of another keyframe fuses into it; long segments and the
// provenance are never affected, and the rule holds after MP-GMA re-fuses the map.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "cae_test.hpp"

namespace
{
// In the map frame, both with the free side (towards the sensors near the origin) on the left:
// a 2 m wall x = 3 and a 0.3 m piece of the wall y = 2, x in [0.7, 1.0].
const Segment2 kLongWall(Vec2(3.0, -1.0), Vec2(3.0, 1.0));
const Segment2 kShortPiece(Vec2(1.0, 2.0), Vec2(0.7, 2.0));

Keyframe keyframeAt(std::uint64_t index, const Pose2& pose, const std::vector<Segment2>& map_segments)
{
  Keyframe k;
  k.index = index;
  k.stamp = static_cast<double>(index);
  k.pose = pose;
  const Pose2 inverse = pose.inverse();
  for (const Segment2& s : map_segments) k.segments.push_back(s.transformed(inverse));
  return k;
}

bool showsNear(const std::vector<MapSegment>& map, const Segment2& s)
{
  for (const MapSegment& m : map)
    if ((m.segment.start - s.start).norm() < 1e-6 && (m.segment.end - s.end).norm() < 1e-6) return true;
  return false;
}

TEST(SingleViewSupport, ShortPieceSeenOnceIsWithheldUntilSeenAgain)
{
  CaeRlsm cae;  // single_view_min_length 0.6 m by default
  cae.addKeyframe(keyframeAt(0, Pose2(0.0, 0.0, 0.0), {kLongWall, kShortPiece}));
  std::vector<MapSegment> map = cae.map();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_TRUE(showsNear(map, kLongWall));
  EXPECT_EQ(cae.segmentCount(), 1u);
  EXPECT_EQ(cae.leafCount(), 2u);  // the provenance keeps the withheld original

  // A second keyframe, 0.5 m on and turned, sees the same piece: it is admitted.
  cae.addKeyframe(keyframeAt(1, Pose2(0.5, 0.0, 0.3), {kShortPiece}));
  map = cae.map();
  ASSERT_EQ(map.size(), 2u);
  EXPECT_TRUE(showsNear(map, kShortPiece));
  EXPECT_EQ(cae.leafCount(), 3u);
}

TEST(SingleViewSupport, TwoOriginalsOfOneKeyframeAreStillOneView)
{
  CaeRlsm cae;
  // Two collinear halves of the piece in one scan fuse into one map segment of one view.
  const Segment2 a(Vec2(1.0, 2.0), Vec2(0.85, 2.0)), b(Vec2(0.85, 2.0), Vec2(0.7, 2.0));
  cae.addKeyframe(keyframeAt(0, Pose2(0.0, 0.0, 0.0), {a, b}));
  EXPECT_TRUE(cae.map().empty());
  EXPECT_EQ(cae.leafCount(), 2u);
}

TEST(SingleViewSupport, ZeroShowsEverySegment)
{
  CaeParams params;
  params.single_view_min_length = 0.0;
  CaeRlsm cae(params);
  cae.addKeyframe(keyframeAt(0, Pose2(0.0, 0.0, 0.0), {kLongWall, kShortPiece}));
  EXPECT_EQ(cae.map().size(), 2u);
  params.single_view_min_length = -1.0;
  EXPECT_THROW(CaeRlsm{params}, linemap::ParameterError);
}

TEST(SingleViewSupport, HoldsAfterMapAdjustment)
{
  CaeRlsm cae;
  cae.addKeyframe(keyframeAt(0, Pose2(0.0, 0.0, 0.0), {kLongWall, kShortPiece}));
  cae.addKeyframe(keyframeAt(1, Pose2(0.5, 0.0, 0.3), {kLongWall}));
  ASSERT_EQ(cae.map().size(), 1u);
  // Both keyframes move 0.2 m in y: the long wall moves with them, the piece stays withheld.
  const auto result = cae.adjust({{0, Pose2(0.0, 0.2, 0.0)}, {1, Pose2(0.5, 0.2, 0.3)}});
  EXPECT_EQ(result.moved, 2u);
  const std::vector<MapSegment> map = cae.map();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_NEAR(map[0].segment.start.y(), kLongWall.start.y() + 0.2, 1e-6);
  EXPECT_EQ(cae.leafCount(), 3u);
}

TEST(SingleViewSupport, MapFileKeepsTheWithheldSegments)
{
  CaeRlsm cae;
  cae.addKeyframe(keyframeAt(0, Pose2(0.0, 0.0, 0.0), {kLongWall, kShortPiece}));
  const std::string path = testing::TempDir() + "single_view_map.yaml";
  cae.save(path);
  {
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // The withheld segment is in the file, marked for its readers; the shown one is not marked.
    std::size_t marks = 0;
    for (std::size_t at = text.find("withheld: true"); at != std::string::npos;
         at = text.find("withheld: true", at + 1))
      ++marks;
    EXPECT_EQ(marks, 1u);
  }
  CaeRlsm loaded;
  loaded.load(path);
  std::remove(path.c_str());
  EXPECT_EQ(loaded.map().size(), 1u);
  EXPECT_EQ(loaded.leafCount(), 2u);
  // The withheld piece came back with the file: a second view admits it.
  loaded.addKeyframe(keyframeAt(1, Pose2(0.5, 0.0, 0.3), {kShortPiece}));
  EXPECT_EQ(loaded.map().size(), 2u);
}

}  // namespace
