// gtest checks of segments shared by the merger tests.
#pragma once

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include "line_map_merging/mergers/merger.hpp"
#include "linemap/geometry.hpp"
#include "synthetic_world.hpp"

/// s runs from a to b, each coordinate within tol.
inline void expectSegment(const linemap::Segment2& s, const linemap::Vec2& a, const linemap::Vec2& b,
                          double tol = 1e-9)
{
  EXPECT_NEAR(s.start.x(), a.x(), tol);
  EXPECT_NEAR(s.start.y(), a.y(), tol);
  EXPECT_NEAR(s.end.x(), b.x(), tol);
  EXPECT_NEAR(s.end.y(), b.y(), tol);
}

/// Every merger on bad input (the bad-input tests of each merger): a zero-length and a non-finite
/// segment are counted as rejected, the keyframe's index given twice and a pose with an infinite
/// field throw, and the map keeps the one good segment.
inline void expectBadInputRejected(line_map_merging::Merger& merger)
{
  using linemap::Segment2;
  using linemap::Vec2;
  line_map_merging::Keyframe k =
      synthetic::keyframeOf(7, linemap::Pose2(), {Segment2(Vec2(0, 0), Vec2(1, 0))});
  k.segments.push_back(Segment2(Vec2(1, 1), Vec2(1, 1)));  // zero length
  k.segments.push_back(Segment2(Vec2(std::numeric_limits<double>::quiet_NaN(), 0), Vec2(1, 0)));
  const auto r = merger.addKeyframe(k);
  EXPECT_EQ(r.merged, 1u);
  EXPECT_EQ(r.rejected, 2u);
  EXPECT_THROW(merger.addKeyframe(k), std::invalid_argument);  // duplicate index
  for (double linemap::Pose2::*field : {&linemap::Pose2::x, &linemap::Pose2::theta})
  {
    line_map_merging::Keyframe bad =
        synthetic::keyframeOf(8, linemap::Pose2(), {Segment2(Vec2(0, 3), Vec2(1, 3))});
    bad.pose.*field = std::numeric_limits<double>::infinity();
    EXPECT_THROW(merger.addKeyframe(bad), std::invalid_argument);
  }
  EXPECT_EQ(merger.segmentCount(), 1u);
  EXPECT_EQ(merger.keyframeCount(), 1u);
  EXPECT_EQ(merger.leafCount(), 1u);
}
