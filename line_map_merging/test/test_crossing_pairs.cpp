// findCrossingPairs on hand-computed configurations: what crosses (an X, also at a small angle) and
// what does not (corners, T junctions, a chain at a bend, parallel segments, short overhangs).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "line_map_merging/mergers/crossing_pairs.hpp"

using line_map_merging::CrossingPair;
using line_map_merging::findCrossingPairs;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
Segment2 seg(double x0, double y0, double x1, double y1)
{
  return {Vec2(x0, y0), Vec2(x1, y1)};
}
}  // namespace

TEST(CrossingPairs, XCrossesAtItsCentre)
{
  // Diagonals of the square [0, 2]^2 meet at (1, 1), sqrt(2) m from every end.
  const auto pairs = findCrossingPairs({seg(0, 0, 2, 2), seg(0, 2, 2, 0)}, 0.1);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].a, 0);
  EXPECT_EQ(pairs[0].b, 1);
  EXPECT_NEAR(pairs[0].point.x(), 1.0, 1e-12);
  EXPECT_NEAR(pairs[0].point.y(), 1.0, 1e-12);
  // Overhangs are sqrt(2) = 1.414 m: 1.41 still crosses, 1.42 no longer does.
  EXPECT_EQ(findCrossingPairs({seg(0, 0, 2, 2), seg(0, 2, 2, 0)}, 1.41).size(), 1u);
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 2), seg(0, 2, 2, 0)}, 1.42).empty());
}

TEST(CrossingPairs, SmallAngleXOfTwoChords)
{
  // y = 0.05 x and y = 0.1 - 0.025 x meet at x = 0.1 / 0.075 = 4/3, y = 1/15 (4.3 deg apart).
  const auto pairs = findCrossingPairs({seg(0, 0, 4, 0.2), seg(0, 0.1, 4, 0)}, 0.1);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_NEAR(pairs[0].point.x(), 4.0 / 3.0, 1e-9);
  EXPECT_NEAR(pairs[0].point.y(), 1.0 / 15.0, 1e-9);
  // Direction does not matter: reversed segments cross at the same point.
  const auto reversed = findCrossingPairs({seg(4, 0.2, 0, 0), seg(4, 0, 0, 0.1)}, 0.1);
  ASSERT_EQ(reversed.size(), 1u);
  EXPECT_NEAR(reversed[0].point.x(), 4.0 / 3.0, 1e-9);
}

TEST(CrossingPairs, CornersJunctionsAndBendsDoNotCross)
{
  // L corner: both end at (0, 0).
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(0, 0, 0, 2)}, 0.05).empty());
  // L corner with 3 cm overshoot on both: below a 5 cm limit.
  EXPECT_TRUE(findCrossingPairs({seg(-0.03, 0, 2, 0), seg(0, -0.03, 0, 2)}, 0.05).empty());
  // T junction: the stem ends on the bar.
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(1, 0, 1, 2)}, 0.05).empty());
  // T junction whose stem stops 1 cm short of the bar: no intersection at all.
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(1, 0.01, 1, 2)}, 0.0).empty());
  // Chain meeting at a 3 deg bend (the second piece rises 2 tan 3 deg = 0.1048 m over 2 m).
  EXPECT_TRUE(
      findCrossingPairs({seg(0, 0, 2, 0), seg(2, 0, 4, 2 * std::tan(3.0 * linemap::kPi / 180.0))}, 0.05)
          .empty());
}

TEST(CrossingPairs, ParallelAndCollinearSegmentsDoNotCross)
{
  // Near miss: parallel 1 cm apart, overlapping over their whole length.
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(0, 0.01, 2, 0.01)}, 0.0).empty());
  // Collinear and overlapping: no single intersection point.
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(1, 0, 3, 0)}, 0.0).empty());
  // Converging but meeting only beyond both ends (at x = 4).
  EXPECT_TRUE(findCrossingPairs({seg(0, 0, 2, 0), seg(0, 0.2, 2, 0.1)}, 0.0).empty());
}

TEST(CrossingPairs, OverhangJustBelowAndAboveTheLimit)
{
  const Segment2 bar = seg(0, 0, 2, 0);
  // The stem reaches 0.099 m below the bar: overhang below the 0.1 m limit.
  EXPECT_TRUE(findCrossingPairs({bar, seg(1, -0.099, 1, 1)}, 0.1).empty());
  // 0.101 m: above it, crossing at (1, 0).
  auto pairs = findCrossingPairs({bar, seg(1, -0.101, 1, 1)}, 0.1);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_NEAR(pairs[0].point.x(), 1.0, 1e-12);
  EXPECT_NEAR(pairs[0].point.y(), 0.0, 1e-12);
  // The same on the bar's side: the stem crosses 0.099 m / 0.101 m from the bar's start.
  EXPECT_TRUE(findCrossingPairs({bar, seg(0.099, -1, 0.099, 1)}, 0.1).empty());
  pairs = findCrossingPairs({bar, seg(0.101, -1, 0.101, 1)}, 0.1);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_NEAR(pairs[0].point.x(), 0.101, 1e-12);
  // And at the bar's end (1.901 from the start leaves 0.099).
  EXPECT_TRUE(findCrossingPairs({bar, seg(1.901, -1, 1.901, 1)}, 0.1).empty());
  EXPECT_EQ(findCrossingPairs({bar, seg(1.899, -1, 1.899, 1)}, 0.1).size(), 1u);
}

TEST(CrossingPairs, PairsAreOrderedAndIndexed)
{
  // A horizontal bar crossed by two verticals; an unrelated segment in between.
  const std::vector<Segment2> map = {seg(3, -1, 3, 1), seg(10, 10, 11, 10), seg(0, 0, 4, 0),
                                     seg(1, -1, 1, 1)};
  const auto pairs = findCrossingPairs(map, 0.1);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].a, 0);
  EXPECT_EQ(pairs[0].b, 2);
  EXPECT_NEAR(pairs[0].point.x(), 3.0, 1e-12);
  EXPECT_EQ(pairs[1].a, 2);
  EXPECT_EQ(pairs[1].b, 3);
  EXPECT_NEAR(pairs[1].point.x(), 1.0, 1e-12);
  EXPECT_NEAR(pairs[1].point.y(), 0.0, 1e-12);
  EXPECT_TRUE(findCrossingPairs({}, 0.1).empty());
}

TEST(CrossingPairs, BadInputThrows)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  try
  {
    findCrossingPairs({seg(0, 0, 1, 0), seg(0, 0, nan, 1)}, 0.1);
    FAIL() << "no exception";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("segment 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(findCrossingPairs({seg(0, 0, 1, 0)}, -0.1), std::invalid_argument);
  EXPECT_THROW(findCrossingPairs({seg(0, 0, 1, 0)}, nan), std::invalid_argument);
}
