// Sensor profiles and range noise growing with range: the noise model's statistics, the shipped
// profiles, their errors, and the large hall world they are meant for.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/simulator.hpp"

namespace
{
using linemap::kPi;
using linemap::Segment2;
using linemap::Vec2;
using namespace line_map_eval;

const std::string kConfig = std::string(LINEMAP_SOURCE_DIR) + "/config/";

std::string profileError(const std::string& text)
{
  try
  {
    parseSensorProfile(text, "sensor.yaml");
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

/// The walls' bounding box: x0, y0, x1, y1.
std::array<double, 4> wallBox(const World& world)
{
  std::array<double, 4> box{1e9, 1e9, -1e9, -1e9};
  for (const Wall& w : world.walls)
    for (const Vec2& p : {w.segment.start, w.segment.end})
      box = {std::min(box[0], p.x()), std::min(box[1], p.y()), std::max(box[2], p.x()),
             std::max(box[3], p.y())};
  return box;
}

/// Sample std of measured minus true range over `n` beams at true range `r`.
double noiseStd(const LaserModel& laser, double r, std::size_t n, Random& rng)
{
  const std::vector<RayHit> hits(n, RayHit{r, 0});
  const std::vector<double> ranges = measureScan(hits, laser, rng);
  double sum = 0.0, sum2 = 0.0;
  for (const double m : ranges)
  {
    sum += m - r;
    sum2 += (m - r) * (m - r);
  }
  const double mean = sum / double(n);
  return std::sqrt(sum2 / double(n) - mean * mean);
}
}  // namespace

TEST(RangeNoise, StdGrowsLinearlyWithRange)
{
  LaserModel laser;
  laser.range_max = 100.0;
  laser.sigma = 0.01;
  laser.sigma_slope = 0.002;
  EXPECT_DOUBLE_EQ(laser.sigmaAt(2.0), 0.014);
  EXPECT_DOUBLE_EQ(laser.sigmaAt(20.0), 0.05);
  // 40000 samples: the sample std is within 0.35 % of the truth (one std), so 2 % is 5.7 stds; a
  // constant std (0.01) or sqrt(sigma^2 + (k r)^2) (0.0108 and 0.041) fall far outside.
  Random rng(11, 1);
  const std::size_t n = 40000;
  EXPECT_NEAR(noiseStd(laser, 2.0, n, rng), 0.014, 0.02 * 0.014);
  EXPECT_NEAR(noiseStd(laser, 20.0, n, rng), 0.05, 0.02 * 0.05);
  // No slope: the constant std of before, with the very same draws.
  LaserModel flat = laser;
  flat.sigma_slope = 0.0;
  Random a(5, 1), b(5, 1);
  const std::vector<RayHit> hits{{3.0, 0}, {12.0, 0}, {std::numeric_limits<double>::infinity(), -1}};
  const auto ranges = measureScan(hits, flat, a);
  EXPECT_DOUBLE_EQ(ranges[0], 3.0 + 0.01 * b.normal());
  EXPECT_DOUBLE_EQ(ranges[1], 12.0 + 0.01 * b.normal());
  EXPECT_TRUE(std::isinf(ranges[2]));
}

TEST(SensorProfiles, ShippedProfilesGiveTheirGeometry)
{
  const World office = loadWorld(kConfig + "worlds/office.yaml");
  EXPECT_EQ(office.laser.sigma_slope, 0.0);  // absent key: no growth

  const SensorProfile coarse = loadSensorProfile(kConfig + "sensors/laser_1deg_30m.yaml", office.laser);
  EXPECT_EQ(coarse.name, "1deg_30m");
  EXPECT_EQ(coarse.laser.beams, 181u);
  EXPECT_NEAR(coarse.laser.angleIncrement(), kPi / 180.0, 1e-15);
  EXPECT_NEAR(coarse.laser.angleMin(), -kPi / 2.0, 1e-15);
  EXPECT_EQ(coarse.laser.range_max, 30.0);
  EXPECT_EQ(coarse.laser.sigma_slope, 0.001);
  EXPECT_EQ(coarse.laser.mounting.x, office.laser.mounting.x);  // not in the profile: the world's

  const SensorProfile fine = loadSensorProfile(kConfig + "sensors/laser_025deg_80m.yaml");
  EXPECT_EQ(fine.laser.beams, 1081u);
  EXPECT_NEAR(fine.laser.angleIncrement(), 0.25 * kPi / 180.0, 1e-15);
  EXPECT_NEAR(fine.laser.angleMin(), -0.75 * kPi, 1e-15);
  EXPECT_EQ(fine.laser.range_max, 80.0);

  const World seen = withSensorProfile(office, kConfig + "sensors/laser_025deg_80m.yaml");
  EXPECT_EQ(seen.name, "office / 025deg_80m");
  EXPECT_EQ(seen.laser.beams, 1081u);
  EXPECT_EQ(seen.walls.size(), office.walls.size());
  SimulationOptions opt;
  opt.scans = 3;
  const SimulationResult sim = simulate(seen, opt);
  EXPECT_EQ(sim.recording.geometry.beam_count, 1081u);
  EXPECT_EQ(sim.recording.scans.front().ranges.size(), 1081u);
  EXPECT_EQ(sim.truth.laser.sigma_slope, 0.0005);
}

TEST(SensorProfiles, BadProfilesAreNamed)
{
  const std::string missing = profileError("name: x\n");
  EXPECT_NE(missing.find("sensor.yaml: laser: missing key"), std::string::npos) << missing;
  const std::string typo = profileError("laser: {beams: 181, sigma_slop: 0.001}\n");
  EXPECT_NE(typo.find("laser/sigma_slop: unknown key"), std::string::npos) << typo;
  const std::string slope = profileError("laser:\n  sigma_slope: -0.001\n");
  EXPECT_NE(slope.find("sensor.yaml: laser/sigma_slope: must be >= 0"), std::string::npos) << slope;
  EXPECT_NE(slope.find("line 2"), std::string::npos) << slope;
  const std::string beams = profileError("laser: {beams: 1.5}\n");
  EXPECT_NE(beams.find("laser/beams"), std::string::npos) << beams;
  const std::string range = profileError("laser: {range_min: 5, range_max: 4}\n");
  EXPECT_NE(range.find("laser/range_max"), std::string::npos) << range;
  EXPECT_NE(profileError("").find("empty"), std::string::npos);
  try
  {
    loadSensorProfile("/nonexistent/profile.yaml");
    ADD_FAILURE() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profile.yaml: cannot open the sensor profile"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(profileError("laser: {beams: 181}\n"), "");
}

TEST(HallWorld, LoadsWithItsApseAndKeepsClearance)
{
  const World hall = loadWorld(kConfig + "worlds/hall.yaml");
  EXPECT_EQ(hall.name, "hall");
  // At least 40 x 30 m.
  const auto [x0, y0, x1, y1] = wallBox(hall);
  std::size_t apse = 0, column = 0;
  for (const Wall& w : hall.walls)
  {
    apse += w.arc == 0;
    column += w.arc == 1;
  }
  EXPECT_GE(x1 - x0, 40.0);
  EXPECT_GE(y1 - y0, 30.0);
  // Radius 16 m, 5 mm sagitta: steps of at most 2 acos(1 - 0.005 / 16) = 2.865 deg, 63 over 180 deg;
  // the column (radius 0.5 m): 2 acos(0.99) = 16.22 deg, 23 over 360 deg.
  EXPECT_EQ(apse, 63u);
  EXPECT_EQ(column, 23u);

  // The loop keeps its clearance from every surface, and the long walls are 10-25 m away.
  const auto& wp = hall.path.waypoints;
  ASSERT_GE(wp.size(), 3u);
  double nearest = 1e9;
  for (std::size_t i = 0; i < wp.size(); ++i)
  {
    const Vec2 a = wp[i], b = wp[(i + 1) % wp.size()];
    for (const Wall& w : hall.walls)
      for (double t = 0.0; t <= 1.0; t += 0.01)
        nearest =
            std::min(nearest, linemap::distanceToSegment(a + t * (b - a), w.segment.start, w.segment.end) -
                                  0.5 * w.thickness);
    for (const Vec2& p : {a, b})
    {
      EXPECT_GE(p.y(), 10.0);  // the bottom wall y = 0 and the top wall y = 32
      EXPECT_LE(p.y(), 22.0);
      EXPECT_GE(p.x(), 10.0);  // the left wall x = 0
    }
  }
  EXPECT_GE(nearest, hall.path.clearance);
  EXPECT_GE(hall.path.clearance, 1.0);
  EXPECT_GT(pathLength(hall.path), 60.0);
}

TEST(HallWorld, TheApseIsSeenAndScoredAsACurve)
{
  SimulationOptions opt;
  opt.scans = 60;
  const SimulationResult sim = simulate(loadWorld(kConfig + "worlds/hall.yaml"), opt);
  // The apse's two sides and the column's two sides.
  ASSERT_EQ(sim.truth.curves.size(), 4u);
  const GroundTruthParams params;
  const SeenParts seen = seenParts(sim.truth, params.min_seen_length, params.min_seen_beams);
  // The apse's 0.80 m chords are hit by 2-4 beams of 1 deg at 14-20 m: no chord is a sight alone,
  // but most of the inner side is seen as a curve.
  std::size_t seen_chords = 0;
  for (const std::size_t f : sim.truth.curves[0]) seen_chords += !seen[f].empty();
  EXPECT_GT(seen_chords, sim.truth.curves[0].size() / 2);
  // A map of the true faces scores perfectly, joints and all.
  const GroundTruthResult perfect = evaluateAgainstGroundTruth(sim.truth, sim.truth.walls, params);
  EXPECT_DOUBLE_EQ(perfect.coverage, 1.0);
  EXPECT_EQ(perfect.max_endpoint_error, 0.0);
  EXPECT_EQ(perfect.unmapped_ends, 0u);
}

TEST(ExpoHallWorld, ALargeHallDrivenFarFromItsFacades)
{
  const World expo = loadWorld(kConfig + "worlds/expo_hall.yaml");
  EXPECT_EQ(expo.name, "expo_hall");
  const auto [x0, y0, x1, y1] = wallBox(expo);
  EXPECT_GE(x1 - x0, 60.0);
  EXPECT_GE(y1 - y0, 40.0);

  // The glass stretch of the top wall (x 22-40 at y = 40): nothing longer than a mullion stands in it.
  for (const Wall& w : expo.walls)
  {
    const Vec2 mid = w.segment.midpoint();
    if (std::abs(mid.y() - 40.0) < 0.5 && mid.x() > 22.5 && mid.x() < 39.5)
    {
      EXPECT_LE(w.segment.length(), 0.2) << "a solid wall in the glass stretch at x = " << mid.x();
    }
  }

  // Driven once around the middle: every point of the loop at least 12 m from the outer walls' box, and
  // the clearance from every solid kept.
  const auto& wp = expo.path.waypoints;
  ASSERT_GE(wp.size(), 3u);
  double nearest = 1e9, nearest_facade = 1e9;
  for (std::size_t i = 0; i < wp.size(); ++i)
  {
    const Vec2 a = wp[i], b = wp[(i + 1) % wp.size()];
    for (double t = 0.0; t <= 1.0; t += 0.01)
    {
      const Vec2 p = a + t * (b - a);
      nearest_facade = std::min({nearest_facade, p.x() - x0, x1 - p.x(), p.y() - y0, y1 - p.y()});
      for (const Wall& w : expo.walls)
        nearest = std::min(nearest,
                           linemap::distanceToSegment(p, w.segment.start, w.segment.end) - 0.5 * w.thickness);
    }
  }
  EXPECT_GE(nearest_facade, 12.0);
  EXPECT_GE(nearest, expo.path.clearance);
  EXPECT_GT(pathLength(expo.path), 70.0);
}
