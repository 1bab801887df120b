// Hostile scans for every registered extractor: a result or a ScanError naming the
// field, never a crash.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "synthetic_scans.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
ScanInput scanOf(const std::vector<float>& r, double inc)
{
  ScanInput s;
  s.ranges = r.data();
  s.count = r.size();
  s.angle_min = -kPi / 2;
  s.angle_increment = inc;
  s.range_min = 0.05;
  s.range_max = 30.0;
  return s;
}

// Runs the scan through every algorithm with and without clustering; returns the
// error message ("" when a result came back) of the last run and checks that all
// runs agree on accepting or rejecting the scan.
std::string runAll(const ScanInput& scan, std::size_t max_segments)
{
  std::string message;
  bool first = true;
  for (const std::string& name : extractorNames())
  {
    for (const char* clustering : {"false", "true"})
    {
      SCOPED_TRACE(name + " clustering " + clustering);
      linemap::ParamSet params;
      params.set("algorithm", name);
      params.set("clustering", clustering);
      LineExtractor extractor(params);
      std::string m;
      try
      {
        const ExtractionResult& r = extractor.extract(scan);
        EXPECT_LE(r.segments.size(), max_segments);
        for (const Segment& s : r.segments)
        {
          EXPECT_TRUE(std::isfinite(s.radius) && std::isfinite(s.angle));
          EXPECT_EQ(s.index_end - s.index_begin, s.num_points);
        }
      }
      catch (const ScanError& e)
      {
        m = e.what();
      }
      if (!first)
      {
        EXPECT_EQ(m.empty(), message.empty());
      }
      message = m;
      first = false;
    }
  }
  return message;
}
}  // namespace

TEST(BadScans, AllNanAllInfEmptyAndOnePointGiveNoSegments)
{
  const double inc = kPi / 180;
  const std::vector<float> nan(181, std::numeric_limits<float>::quiet_NaN());
  const std::vector<float> inf(181, std::numeric_limits<float>::infinity());
  const std::vector<float> empty;
  const std::vector<float> one{2.0f};
  EXPECT_EQ(runAll(scanOf(nan, inc), 0), "");
  EXPECT_EQ(runAll(scanOf(inf, inc), 0), "");
  EXPECT_EQ(runAll(scanOf(empty, inc), 0), "");
  EXPECT_EQ(runAll(scanOf(one, inc), 0), "");
}

TEST(BadScans, BadGeometryIsRejectedNamingTheField)
{
  const std::vector<float> r(181, 2.0f);
  EXPECT_NE(runAll(scanOf(r, 0.0), 0).find("angle_increment"), std::string::npos);
  EXPECT_NE(runAll(scanOf(r, -kPi / 180), 0).find("angle_increment"), std::string::npos);
  ScanInput s = scanOf(r, kPi / 180);
  const std::vector<float> intensities(180, 1.0f);
  s.intensities = intensities.data();
  s.intensity_count = intensities.size();
  EXPECT_NE(runAll(s, 0).find("intensities"), std::string::npos);
}

TEST(BadScans, HundredThousandBeamsComeBack)
{
  // A square room with 100,000 beams over a full turn, a third of them invalid.
  const int beams = 100000;
  const double inc = 2 * kPi / beams;
  std::vector<float> r = line_extraction_test::squareRoomRanges(3.0, 0.2, 0.1, 0.0, beams, -kPi, inc, 0.005);
  for (int i = 0; i < beams; i += 3) r[i] = std::numeric_limits<float>::quiet_NaN();
  ScanInput s = scanOf(r, inc);
  s.angle_min = -kPi;
  EXPECT_EQ(runAll(s, 20000), "");
}

TEST(BadScans, AlternatingJunkGivesAResult)
{
  // Every other beam invalid, the rest random ranges: no structure, no crash.
  std::vector<float> r(361);
  std::uint32_t x = 12345;
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    x = x * 1664525u + 1013904223u;
    r[i] = (i % 2) ? std::numeric_limits<float>::quiet_NaN() : 0.1f + 20.0f * (x >> 8) / 16777216.0f;
  }
  EXPECT_EQ(runAll(scanOf(r, kPi / 360), 361), "");
}
