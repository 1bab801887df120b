// gtest checks of segments shared by the merger tests.
#pragma once

#include <gtest/gtest.h>

#include "linemap/geometry.hpp"

/// s runs from a to b, each coordinate within tol.
inline void expectSegment(const linemap::Segment2& s, const linemap::Vec2& a, const linemap::Vec2& b,
                          double tol = 1e-9)
{
  EXPECT_NEAR(s.start.x(), a.x(), tol);
  EXPECT_NEAR(s.start.y(), a.y(), tol);
  EXPECT_NEAR(s.end.x(), b.x(), tol);
  EXPECT_NEAR(s.end.y(), b.y(), tol);
}
