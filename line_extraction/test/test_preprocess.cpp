// Preprocessing: invalid readings dropped, geometry checked, beam cache refreshed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "line_extraction/preprocess.hpp"
#include "synthetic_scans.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
ScanInput scanOf(const std::vector<float>& r, double angle_min, double inc)
{
  return line_extraction_test::scanOf(r, angle_min, inc, 0.1, 10.0);
}

std::string errorOf(const ScanInput& s)
{
  Preprocessor pre;
  PreparedScan out;
  try
  {
    pre.prepare(s, out);
  }
  catch (const ScanError& e)
  {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Preprocess, DropsInvalidReadingsAndConvertsToCartesian)
{
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<float> r{1.0f, nan, inf, -inf, 0.05f, 10.0f, 12.0f, 2.0f, 6.0f, 0.0f};
  Preprocessor pre(5.0);  // 6 m is beyond the usable range
  PreparedScan out;
  pre.prepare(scanOf(r, 0.0, kPi / 2), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out.beam_index[0], 0);
  EXPECT_EQ(out.beam_index[1], 7);
  // Beam 7 at 7 * 90 deg = 630 deg = -90 deg: point (0, -2).
  EXPECT_NEAR(out.points[0].x(), 1.0, 1e-12);
  EXPECT_NEAR(out.points[0].y(), 0.0, 1e-12);
  EXPECT_NEAR(out.points[1].x(), 0.0, 1e-6);
  EXPECT_NEAR(out.points[1].y(), -2.0, 1e-6);
  EXPECT_NEAR(out.ranges[1], 2.0, 1e-12);
  EXPECT_NEAR(out.angles[1], 7 * kPi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(out.angle_increment, kPi / 2);
}

TEST(Preprocess, BeamCacheFollowsTheGeometry)
{
  const std::vector<float> r{1.0f, 1.0f, 1.0f};
  Preprocessor pre;
  PreparedScan out;
  pre.prepare(scanOf(r, 0.0, 0.1), out);
  EXPECT_NEAR(out.points[2].y(), std::sin(0.2), 1e-12);
  pre.prepare(scanOf(r, 1.0, 0.1), out);  // same count, other angle_min
  EXPECT_NEAR(out.points[2].y(), std::sin(1.2), 1e-12);
  pre.prepare(scanOf(r, 1.0, 0.2), out);  // other increment
  EXPECT_NEAR(out.points[2].x(), std::cos(1.4), 1e-12);
}

TEST(Preprocess, FullCircleIsRecognised)
{
  std::vector<float> r(360, 1.0f);
  Preprocessor pre;
  PreparedScan out;
  pre.prepare(scanOf(r, -kPi, 2 * kPi / 360), out);
  EXPECT_TRUE(out.full_circle);
  r.resize(180);
  pre.prepare(scanOf(r, -kPi / 2, 2 * kPi / 360), out);
  EXPECT_FALSE(out.full_circle);
}

TEST(Preprocess, RejectsBadGeometryNamingTheField)
{
  const std::vector<float> r{1.0f, 2.0f};
  EXPECT_NE(errorOf(scanOf(r, 0.0, 0.0)).find("angle_increment"), std::string::npos);
  EXPECT_NE(errorOf(scanOf(r, 0.0, -0.1)).find("angle_increment"), std::string::npos);
  EXPECT_NE(errorOf(scanOf(r, 0.0, std::nan(""))).find("angle_increment"), std::string::npos);
  EXPECT_NE(errorOf(scanOf(r, std::numeric_limits<double>::infinity(), 0.1)).find("angle_min"),
            std::string::npos);
  ScanInput s = scanOf(r, 0.0, 0.1);
  s.range_min = 5.0;
  s.range_max = 1.0;
  EXPECT_NE(errorOf(s).find("range_min"), std::string::npos);
  s = scanOf(r, 0.0, 0.1);
  const std::vector<float> intensities{1.0f, 2.0f, 3.0f};
  s.intensities = intensities.data();
  s.intensity_count = intensities.size();
  EXPECT_NE(errorOf(s).find("intensities"), std::string::npos);
  s.intensity_count = 2;
  EXPECT_EQ(errorOf(s), "");
  s = scanOf(r, 0.0, 0.1);
  s.ranges = nullptr;
  EXPECT_NE(errorOf(s).find("ranges"), std::string::npos);
}

TEST(Preprocess, EmptyScanGivesNoPoints)
{
  const std::vector<float> r;
  Preprocessor pre;
  PreparedScan out;
  pre.prepare(scanOf(r, 0.0, 0.1), out);
  EXPECT_EQ(out.size(), 0u);
}

TEST(Preprocess, FullCircleStartsAtTheWidestGap)
{
  // A circle of radius 2 with beams 100..139 farther out; beam 100 at 3.5 m makes
  // the jump from beam 99 (1.5 m) wider than the jump back at beam 140 (1 m).
  std::vector<float> r(360, 2.0f);
  for (int i = 100; i < 140; ++i) r[i] = 3.0f;
  r[100] = 3.5f;
  Preprocessor pre;
  PreparedScan out;
  pre.prepare(scanOf(r, -kPi, 2 * kPi / 360), out);
  ASSERT_EQ(out.size(), 360u);
  EXPECT_EQ(out.beam_index[0], 100);
  EXPECT_EQ(out.beam_index[359], 99);
  for (std::size_t i = 1; i < out.size(); ++i) EXPECT_GT(out.angles[i], out.angles[i - 1]);
  EXPECT_NEAR(out.angles[359], -kPi + 99 * 2 * kPi / 360 + 2 * kPi, 1e-12);
  EXPECT_NEAR(out.points[0].x(), 3.5 * std::cos(-kPi + 100 * 2 * kPi / 360), 1e-6);
}
