// WSAC-GE on closed-form square-room scans.
#include <gtest/gtest.h>

#include "line_extraction/line_extractor.hpp"
#include "room_walls.hpp"

using namespace line_extraction;
using namespace line_extraction_test;

TEST(WsacGe, FindsTheFourWallsOfANoiselessRoom)
{
  const RoomScan room = roomScan();
  for (bool clustering : {false, true})
  {
    LineExtractor extractor(pipelineParams("wsac_ge", clustering));
    EXPECT_TRUE(wallsFound(extractor.extract(room.input), room.walls, kMillimetre, kTenthDegree, true))
        << "clustering " << clustering;
  }
}

TEST(WsacGe, SameSeedSameOutput)
{
  const RoomScan room = roomScan(0.02, 0.1, 7);
  linemap::ParamSet p = pipelineParams("wsac_ge", false);
  p.set("wsac_ge/seed", "42");
  LineExtractor a(p), b(p);
  const ExtractionResult first = a.extract(room.input);
  EXPECT_TRUE(identical(first, a.extract(room.input)));  // reseeded at every call
  EXPECT_TRUE(identical(first, b.extract(room.input)));
  EXPECT_GE(first.segments.size(), 4u);
}

TEST(WsacGe, WallsSurviveTwentyPercentSpuriousReadings)
{
  // A fifth of the beams return short; the global score must still pick the
  // four whole walls. Without clustering: breakpoint clusters would cut the
  // walls at every spurious point.
  for (std::uint32_t seed : {3u, 4u, 5u})
  {
    const RoomScan room = roomScan(0.0, 0.2, seed);
    LineExtractor extractor(pipelineParams("wsac_ge", false));
    EXPECT_TRUE(
        wallsFound(extractor.extract(room.input), room.walls, 0.005, 0.5 * linemap::kPi / 180.0, false, 3.0))
        << "seed " << seed;
  }
}

TEST(WsacGe, LineCostDecidesWhetherALineIsWorthKeeping)
{
  // Each wall has ~180 points of support 1 each: a line cost above that keeps no line at all.
  const RoomScan room = roomScan();
  linemap::ParamSet p = pipelineParams("wsac_ge", false);
  p.set("wsac_ge/line_cost", "1000");
  LineExtractor extractor(p);
  EXPECT_TRUE(extractor.extract(room.input).segments.empty());
}

TEST(WsacGe, RejectsBadParameters)
{
  linemap::ParamSet p = pipelineParams("wsac_ge", false);
  p.set("wsac_ge/tukey_c", "0");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
  p = pipelineParams("wsac_ge", false);
  p.set("wsac_ge/delete_probability", "1.5");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
}
