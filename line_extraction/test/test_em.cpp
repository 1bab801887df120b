// EM line extraction on closed-form square-room scans.
#include <gtest/gtest.h>

#include "line_extraction/line_extractor.hpp"
#include "room_walls.hpp"

using namespace line_extraction;
using namespace line_extraction_test;

TEST(Em, FindsTheFourWallsOfANoiselessRoom)
{
  const RoomScan room = roomScan();
  for (bool clustering : {false, true})
  {
    LineExtractor extractor(pipelineParams("em", clustering));
    EXPECT_TRUE(wallsFound(extractor.extract(room.input), room.walls, kMillimetre, kTenthDegree, true))
        << "clustering " << clustering;
  }
}

TEST(Em, SameSeedSameOutput)
{
  const RoomScan room = roomScan(0.02, 0.1, 7);
  linemap::ParamSet p = pipelineParams("em", false);
  p.set("em/seed", "42");
  LineExtractor a(p), b(p);
  const ExtractionResult first = a.extract(room.input);
  EXPECT_TRUE(identical(first, a.extract(room.input)));  // reseeded at every call
  EXPECT_TRUE(identical(first, b.extract(room.input)));
  EXPECT_GE(first.segments.size(), 4u);
}

TEST(Em, ModelSelectionNeitherSplitsNoisyWallsNorKeepsWorthlessLines)
{
  // Range noise of 2 cm: the mixture keeps exactly one line per wall (no extra
  // component explaining part of a wall), each within 1 cm and 0.5 deg
  // (a wall of ~180 points fits far better than that: sigma / sqrt(n) ~ 1.5 mm).
  for (std::uint32_t seed : {11u, 12u, 13u})
  {
    const RoomScan room = roomScan(0.02, 0.0, seed);
    LineExtractor extractor(pipelineParams("em", false));
    EXPECT_TRUE(wallsFound(extractor.extract(room.input), room.walls, 0.01, 0.5 * linemap::kPi / 180.0, true))
        << "seed " << seed;
  }
  // A line penalty above any wall's likelihood gain: no line at all.
  const RoomScan room = roomScan();
  linemap::ParamSet p = pipelineParams("em", false);
  p.set("em/line_penalty", "1e9");
  LineExtractor extractor(p);
  EXPECT_TRUE(extractor.extract(room.input).segments.empty());
}

TEST(Em, RejectsBadParameters)
{
  linemap::ParamSet p = pipelineParams("em", false);
  p.set("em/min_sigma", "0");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
  p = pipelineParams("em", false);
  p.set("em/restarts", "0");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
}
