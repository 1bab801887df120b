// Every extractor of this package, with and without breakpoint clustering, on a
// noiseless square room seen whole: the four walls are found within 1 mm and 0.1 deg,
// nothing else is found, and the walls are covered.
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
struct Wall
{
  double angle, radius;
};

struct Pose
{
  double x, y, yaw;
};

// The walls x = +-h, y = +-h seen from the laser pose, in the laser frame.
std::vector<Wall> wallsInLaserFrame(double h, const Pose& p)
{
  return {{linemap::normalizeAngle(0.0 - p.yaw), h - p.x},
          {linemap::normalizeAngle(kPi - p.yaw), h + p.x},
          {linemap::normalizeAngle(kPi / 2 - p.yaw), h - p.y},
          {linemap::normalizeAngle(-kPi / 2 - p.yaw), h + p.y}};
}

struct Case
{
  std::string algorithm;
  bool clustering;
};

std::string caseName(const testing::TestParamInfo<Case>& info)
{
  return info.param.algorithm + (info.param.clustering ? "_clustering" : "");
}

class SquareRoom : public testing::TestWithParam<Case>
{
};

TEST_P(SquareRoom, FindsTheFourWalls)
{
  const double h = 3.0;
  const int beams = 360;
  const double inc = 2.0 * kPi / beams;
  linemap::ParamSet params;
  params.set("algorithm", GetParam().algorithm);
  params.set("clustering", GetParam().clustering ? "true" : "false");
  LineExtractor extractor(params);
  for (const Pose& pose : {Pose{0.4, -0.3, 0.2}, Pose{-1.1, 0.7, -2.5}, Pose{0.0, 0.0, 0.0}})
  {
    SCOPED_TRACE("pose " + std::to_string(pose.x) + " " + std::to_string(pose.y) + " " +
                 std::to_string(pose.yaw));
    const std::vector<float> ranges =
        line_extraction_test::squareRoomRanges(h, pose.x, pose.y, pose.yaw, beams, -kPi, inc);
    ScanInput scan;
    scan.ranges = ranges.data();
    scan.count = ranges.size();
    scan.angle_min = -kPi;
    scan.angle_increment = inc;
    scan.range_min = 0.05;
    scan.range_max = 20.0;
    const ExtractionResult& result = extractor.extract(scan);
    const std::vector<Wall> walls = wallsInLaserFrame(h, pose);
    std::vector<double> covered(walls.size(), 0.0);
    for (const Segment& s : result.segments)
    {
      int match = -1;
      for (std::size_t w = 0; w < walls.size(); ++w)
        if (std::abs(s.radius - walls[w].radius) < 1e-3 &&
            std::abs(linemap::normalizeAngle(s.angle - walls[w].angle)) < 0.1 * kPi / 180.0)
          match = static_cast<int>(w);
      EXPECT_GE(match, 0) << "segment radius " << s.radius << " angle " << s.angle << " with " << s.num_points
                          << " points matches no wall";
      if (match >= 0) covered[match] += s.length();
    }
    // Each wall is 6 m long; the beam spacing near the corners leaves a few cm out.
    for (std::size_t w = 0; w < walls.size(); ++w)
      EXPECT_GT(covered[w], 5.5) << "wall " << w << " (radius " << walls[w].radius << ") covered "
                                 << covered[w];
  }
}

std::vector<Case> cases()
{
  std::vector<Case> c;
  for (const char* name : {"srg", "split_merge", "iepf", "smsm", "incremental", "line_regression"})
    for (bool clustering : {false, true}) c.push_back({name, clustering});
  return c;
}

INSTANTIATE_TEST_SUITE_P(Algorithms, SquareRoom, testing::ValuesIn(cases()), caseName);

TEST(Registry, NamesInTableOrderAndUnknownNameRejected)
{
  const std::vector<std::string> expected{"srg",         "split_merge",     "iepf",  "smsm",
                                          "incremental", "line_regression", "hough", "ransac",
                                          "em",          "wsac_ge"};
  EXPECT_EQ(extractorNames(), expected);
  linemap::ParamSet params;
  try
  {
    makeExtractor("no_such_algorithm", params);
    FAIL() << "unknown name accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    const std::string what = e.what();
    EXPECT_NE(what.find("no_such_algorithm"), std::string::npos);
    EXPECT_NE(what.find("split_merge"), std::string::npos);
  }
}

TEST(Pipeline, BadParametersAreNamed)
{
  for (const auto& kv : std::vector<std::pair<std::string, std::string>>{{"srg/line_distance", "-1"},
                                                                         {"srg/seed_points", "1"},
                                                                         {"range_sigma", "0"},
                                                                         {"min_points", "abc"},
                                                                         {"iepf/distance_threshold", "0"},
                                                                         {"algorithm", "nope"}})
  {
    linemap::ParamSet params;
    params.set(kv.first, kv.second);
    if (kv.first.rfind("iepf", 0) == 0) params.set("algorithm", "iepf");
    try
    {
      LineExtractor extractor(params);
      ADD_FAILURE() << kv.first << "=" << kv.second << " accepted";
    }
    catch (const linemap::ParameterError& e)
    {
      const std::string expected = kv.first == "algorithm" ? "nope" : kv.first;
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

}  // namespace
