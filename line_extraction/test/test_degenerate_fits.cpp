// No extractor emits a segment shorter than the pipeline's minimum by default, and a cluster whose
// points all lie within the range noise of one spot yields no segment at all, whatever min_length
// says: such a fit has no direction (split_merge once emitted start = end for a small object).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "synthetic_scans.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
const std::vector<std::string> kAlgorithms = {"srg",         "split_merge",     "iepf",  "smsm",
                                              "incremental", "line_regression", "hough", "ransac",
                                              "em",          "wsac_ge"};

ScanInput input(const std::vector<float>& ranges, double angle_min, double increment)
{
  return line_extraction_test::scanOf(ranges, angle_min, increment);
}

/// Deterministic noise in [-amplitude, amplitude].
float noise(int i, double amplitude)
{
  return static_cast<float>(amplitude * std::sin(12.9898 * i + 78.233 * std::cos(4.1 * i)));
}

class DegenerateFits : public testing::TestWithParam<std::tuple<std::string, bool>>
{
 protected:
  linemap::ParamSet params() const
  {
    linemap::ParamSet p;
    p.set("algorithm", std::get<0>(GetParam()));
    p.set("clustering", std::get<1>(GetParam()) ? "true" : "false");
    return p;
  }
};

TEST_P(DegenerateFits, NoSegmentShorterThanTheDefaultMinimum)
{
  // A 4 x 4 m room seen from its centre (0.5 deg beams), with 26 beams on a small object 0.3 m
  // ahead (ranges 0.3 m +- 1 cm): 6.8 cm of arc, no wall.
  const int beams = 720;
  const double inc = 2.0 * kPi / beams;
  std::vector<float> ranges = line_extraction_test::squareRoomRanges(2.0, 0.0, 0.0, 0.0, beams, -kPi, inc);
  for (int i = 0; i < 26; ++i) ranges[beams / 2 - 13 + i] = 0.3f + noise(i, 0.01);
  LineExtractor extractor(params());
  // A sane minimum: at 1 cm range noise a 5 cm segment's direction is uncertain by ~0.3 rad.
  EXPECT_GE(extractor.params().min_length, 0.05);
  const ExtractionResult& result = extractor.extract(input(ranges, -kPi, inc));
  EXPECT_FALSE(result.segments.empty());
  for (const Segment& s : result.segments)
    EXPECT_GE(s.length(), extractor.params().min_length)
        << s.num_points << " points from (" << s.start.x() << ", " << s.start.y() << ")";
}

TEST_P(DegenerateFits, PointsWithinNoiseOfOneSpotAreNoLine)
{
  // 40 beams 0.01 deg apart (1 mm of arc at 0.3 m), ranges 0.3 m +- 1 cm: every point lies within
  // the range noise (range_sigma 1 cm) of one spot. Even with no length minimum and two-point
  // segments allowed, no segment may come out.
  const int beams = 40;
  const double inc = 0.01 * kPi / 180.0;
  std::vector<float> ranges(beams);
  for (int i = 0; i < beams; ++i) ranges[i] = 0.3f + noise(i, 0.01);
  linemap::ParamSet p = params();
  p.set("min_length", "0");
  p.set("min_points", "2");
  LineExtractor extractor(p);
  const ExtractionResult& result = extractor.extract(input(ranges, -0.5 * beams * inc, inc));
  for (const Segment& s : result.segments)
    ADD_FAILURE() << "a segment of " << s.length() << " m from " << s.num_points
                  << " points within 1 cm of one spot";
}

std::string name(const testing::TestParamInfo<std::tuple<std::string, bool>>& info)
{
  return std::get<0>(info.param) + (std::get<1>(info.param) ? "_clustering" : "");
}

INSTANTIATE_TEST_SUITE_P(EveryExtractor, DegenerateFits,
                         testing::Combine(testing::ValuesIn(kAlgorithms), testing::Bool()), name);

}  // namespace
