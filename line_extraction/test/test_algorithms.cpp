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
    const ScanInput scan = line_extraction_test::scanOf(ranges, -kPi, inc);
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

// The orientation convention: the sensor (the laser frame's origin) lies left of start -> end.
// A wall with Hessian normal n = (cos angle, sin angle) points away from the origin (radius >= 0),
// so its left normal must be -n: the direction is n turned by +90 deg, heading = angle + pi/2.
class Orientation : public testing::TestWithParam<std::string>
{
};

TEST_P(Orientation, FreeSideOnTheLeft)
{
  const double h = 3.0;
  const int beams = 360;
  const double inc = 2.0 * kPi / beams;
  linemap::ParamSet params;
  params.set("algorithm", GetParam());
  LineExtractor extractor(params);
  std::size_t checked = 0;
  for (const Pose& pose : {Pose{0.4, -0.3, 0.2}, Pose{-1.1, 0.7, -2.5}, Pose{2.0, 1.5, 1.0}})
  {
    // A full turn of beams starting at several angles: the wall cut by the scan start wraps.
    for (double angle_min : {-kPi, -kPi / 2, 0.3})
    {
      const std::vector<float> ranges =
          line_extraction_test::squareRoomRanges(h, pose.x, pose.y, pose.yaw, beams, angle_min, inc);
      const ScanInput scan = line_extraction_test::scanOf(ranges, angle_min, inc);
      for (const Segment& s : extractor.extract(scan).segments)
      {
        const double heading = std::atan2(s.end.y() - s.start.y(), s.end.x() - s.start.x());
        EXPECT_NEAR(linemap::normalizeAngle(heading - (s.angle + kPi / 2)), 0.0, 1e-3)
            << GetParam() << ": segment radius " << s.radius << " angle " << s.angle << " runs with heading "
            << heading;
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 12u) << GetParam() << " found too few segments to check";
}

INSTANTIATE_TEST_SUITE_P(Algorithms, Orientation,
                         testing::Values("srg", "split_merge", "iepf", "smsm", "incremental",
                                         "line_regression", "hough", "ransac", "em", "wsac_ge"));

TEST(Orientation, ReversedSegmentIsSwapped)
{
  // The wall x = 1 seen from the origin: running towards +y keeps the origin on the left.
  Segment s;
  s.start = Vec2(1.0, 1.0);
  s.end = Vec2(1.0, -1.0);
  orientFreeSideLeft(s);
  EXPECT_EQ(s.start, Vec2(1.0, -1.0));
  EXPECT_EQ(s.end, Vec2(1.0, 1.0));
  orientFreeSideLeft(s);  // already oriented: unchanged
  EXPECT_EQ(s.start, Vec2(1.0, -1.0));
  // Behind the sensor (x = -2) the same direction would put the origin on the right.
  s.start = Vec2(-2.0, -1.0);
  s.end = Vec2(-2.0, 1.0);
  orientFreeSideLeft(s);
  EXPECT_EQ(s.start, Vec2(-2.0, 1.0));
}
