// Hough transform extraction on closed-form square-room scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "line_extraction/hough.hpp"
#include "line_extraction/line_extractor.hpp"
#include "line_extraction/preprocess.hpp"
#include "room_walls.hpp"

using namespace line_extraction;
using namespace line_extraction_test;

TEST(Hough, FindsTheFourWallsOfANoiselessRoom)
{
  const RoomScan room = roomScan();
  for (bool clustering : {false, true})
  {
    LineExtractor extractor(pipelineParams("hough", clustering));
    EXPECT_TRUE(wallsFound(extractor.extract(room.input), room.walls, kMillimetre, kTenthDegree, true))
        << "clustering " << clustering;
  }
}

TEST(Hough, SameOutputOnEveryCall)
{
  const RoomScan room = roomScan(0.02, 0.1, 7);
  LineExtractor a(pipelineParams("hough", false)), b(pipelineParams("hough", false));
  const ExtractionResult first = a.extract(room.input);
  EXPECT_TRUE(identical(first, a.extract(room.input)));  // the accumulator is left clean
  EXPECT_TRUE(identical(first, b.extract(room.input)));
  EXPECT_GE(first.segments.size(), 4u);
}

TEST(Hough, PeakCellLiesWithinOneCellOfTheWallBeforeRefit)
{
  // Noiseless walls: all votes of a wall meet in the cell containing its true
  // (radius, angle), so the strongest cell is that one or, where the line sits
  // on a cell border, its neighbour: within one cell (1 cm, 0.4 deg) either way.
  const RoomScan room = roomScan();
  PreparedScan scan;
  Preprocessor(30.0).prepare(room.input, scan);
  HoughExtractor hough(linemap::ParamSet{});
  ExtractionResult out;
  hough.extractRange(scan, PointRange{0, static_cast<int>(scan.size())}, out);
  EXPECT_NEAR(hough.radiusResolution(), 0.01, 1e-12);
  EXPECT_NEAR(hough.angleResolution(), 0.4 * linemap::kPi / 180.0, 1e-12);
  ASSERT_GE(hough.peaks().size(), 4u);
  for (int k = 0; k < 4; ++k)  // the four strongest peaks are the four walls
  {
    const HoughExtractor::Peak& peak = hough.peaks()[k];
    int close = 0;
    for (const linemap::HessianLine& wall : room.walls)
      close += std::abs(peak.radius - wall.radius) <= hough.radiusResolution() &&
               std::abs(linemap::normalizeAngle(peak.angle - wall.angle)) <= hough.angleResolution();
    EXPECT_EQ(close, 1) << "peak " << k << " (r " << peak.radius << ", a " << peak.angle << ")";
  }
  // Strongest first.
  for (std::size_t k = 1; k < hough.peaks().size(); ++k)
    EXPECT_LE(hough.peaks()[k].votes, hough.peaks()[k - 1].votes);
}

TEST(Hough, RejectsBadParameters)
{
  linemap::ParamSet p = pipelineParams("hough", false);
  p.set("hough/radius_resolution", "0");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
  p = pipelineParams("hough", false);
  p.set("hough/min_votes", "1");
  EXPECT_THROW(LineExtractor{p}, linemap::ParameterError);
}
