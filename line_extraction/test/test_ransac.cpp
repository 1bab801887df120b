// RANSAC on closed-form square-room scans.
#include <gtest/gtest.h>

#include "line_extraction/line_extractor.hpp"
#include "room_walls.hpp"

using namespace line_extraction;
using namespace line_extraction_test;

TEST(Ransac, FindsTheFourWallsOfANoiselessRoom)
{
  const RoomScan room = roomScan();
  for (bool clustering : {false, true})
  {
    LineExtractor extractor(pipelineParams("ransac", clustering));
    EXPECT_TRUE(wallsFound(extractor.extract(room.input), room.walls, kMillimetre, kTenthDegree, true))
        << "clustering " << clustering;
  }
}

TEST(Ransac, SameSeedSameOutput)
{
  const RoomScan room = roomScan(0.02, 0.1, 7);
  linemap::ParamSet p = pipelineParams("ransac", false);
  p.set("ransac/seed", "42");
  LineExtractor a(p), b(p);
  const ExtractionResult first = a.extract(room.input);
  EXPECT_TRUE(identical(first, a.extract(room.input)));  // reseeded at every call
  EXPECT_TRUE(identical(first, b.extract(room.input)));
  EXPECT_GE(first.segments.size(), 4u);
}

TEST(Ransac, WallsSurviveTwentyPercentSpuriousReadings)
{
  // A fifth of the beams return short; the walls must still come out whole
  // (the spurious points neither capture them nor split them). Without
  // clustering: breakpoint clusters would cut the walls at every spurious point.
  const RoomScan room = roomScan(0.0, 0.2, 3);
  LineExtractor extractor(pipelineParams("ransac", false));
  EXPECT_TRUE(
      wallsFound(extractor.extract(room.input), room.walls, 0.005, 0.5 * linemap::kPi / 180.0, false, 3.0));
}

TEST(Ransac, RejectsBadParameters)
{
  linemap::ParamSet p = pipelineParams("ransac", false);
  p.set("ransac/iterations", "0");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
  p = pipelineParams("ransac", false);
  p.set("ransac/inlier_distance", "-1");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
}
