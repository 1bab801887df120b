// Shared by the tests of the consensus extractors (hough, ransac, em, wsac_ge):
// a 360 degree scan of the square room of synthetic_scans.hpp seen from an
// off-centre, rotated laser, the room's walls in the laser frame, and a check
// that extracted segments are exactly those walls.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "linemap/geometry.hpp"
#include "synthetic_scans.hpp"

namespace line_extraction_test
{
constexpr double kHalfSize = 2.0;
constexpr double kLaserX = 0.3, kLaserY = -0.4, kLaserYaw = 0.35;
constexpr int kBeams = 720;

struct RoomScan
{
  std::vector<float> ranges;
  line_extraction::ScanInput input;
  std::vector<linemap::HessianLine> walls;  ///< laser frame
};

/// `spurious` of the beams (chosen at random) return a uniform range short of the wall.
inline RoomScan roomScan(double sigma = 0.0, double spurious = 0.0, std::uint32_t seed = 1)
{
  RoomScan r;
  const double inc = 2.0 * linemap::kPi / kBeams;
  r.ranges =
      squareRoomRanges(kHalfSize, kLaserX, kLaserY, kLaserYaw, kBeams, -linemap::kPi, inc, sigma, seed);
  std::mt19937 rng(seed + 1000);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (float& range : r.ranges)
    if (u(rng) < spurious) range = static_cast<float>(0.2 + (range - 0.3) * u(rng));
  r.input.ranges = r.ranges.data();
  r.input.count = r.ranges.size();
  r.input.angle_min = -linemap::kPi;
  r.input.angle_increment = inc;
  r.input.range_min = 0.05;
  r.input.range_max = 30.0;
  // Wall x = +-h (normal angle 0 / pi in the room) and y = +-h (pi/2 / -pi/2), seen from the laser.
  const double normals[4] = {0.0, linemap::kPi, linemap::kPi / 2.0, -linemap::kPi / 2.0};
  const double radii[4] = {kHalfSize - kLaserX, kHalfSize + kLaserX, kHalfSize - kLaserY,
                           kHalfSize + kLaserY};
  for (int k = 0; k < 4; ++k) r.walls.push_back({linemap::normalizeAngle(normals[k] - kLaserYaw), radii[k]});
  return r;
}

inline linemap::ParamSet pipelineParams(const std::string& algorithm, bool clustering)
{
  linemap::ParamSet p;
  p.set("algorithm", algorithm);
  p.set("clustering", clustering ? "true" : "false");
  return p;
}

/// Every wall is found by exactly one segment within the tolerances, at least
/// `min_length` long; with `only_walls` no other segment exists.
inline ::testing::AssertionResult wallsFound(const line_extraction::ExtractionResult& result,
                                             const std::vector<linemap::HessianLine>& walls,
                                             double radius_tol, double angle_tol, bool only_walls,
                                             double min_length = 0.0)
{
  std::vector<int> hits(walls.size(), 0);
  std::string log;
  for (const line_extraction::Segment& s : result.segments)
  {
    bool matched = false;
    for (std::size_t k = 0; k < walls.size(); ++k)
    {
      if (std::abs(s.radius - walls[k].radius) <= radius_tol &&
          std::abs(linemap::normalizeAngle(s.angle - walls[k].angle)) <= angle_tol &&
          s.length() >= min_length)
      {
        ++hits[k];
        matched = true;
      }
    }
    log += " (r " + std::to_string(s.radius) + ", a " + std::to_string(s.angle) + ", len " +
           std::to_string(s.length()) + ")";
    if (!matched && only_walls) return ::testing::AssertionFailure() << "segment off every wall:" << log;
  }
  for (std::size_t k = 0; k < walls.size(); ++k)
    if (hits[k] != 1)
      return ::testing::AssertionFailure() << "wall " << k << " (r " << walls[k].radius << ", a "
                                           << walls[k].angle << ") matched " << hits[k] << " times;" << log;
  return ::testing::AssertionSuccess();
}

/// Bitwise equality of two extraction results.
inline bool identical(const line_extraction::ExtractionResult& a, const line_extraction::ExtractionResult& b)
{
  if (a.segments.size() != b.segments.size() || a.point_indices != b.point_indices) return false;
  for (std::size_t i = 0; i < a.segments.size(); ++i)
  {
    const line_extraction::Segment &x = a.segments[i], &y = b.segments[i];
    if (x.start != y.start || x.end != y.end || x.angle != y.angle || x.radius != y.radius ||
        x.num_points != y.num_points)
      return false;
  }
  return true;
}

constexpr double kMillimetre = 1e-3;
constexpr double kTenthDegree = 0.1 * linemap::kPi / 180.0;

}  // namespace line_extraction_test
