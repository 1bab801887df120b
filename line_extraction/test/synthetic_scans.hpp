// Closed-form scans for unit tests: a laser inside an axis-aligned square room.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "line_extraction/preprocess.hpp"
#include "line_extraction/types.hpp"

namespace line_extraction_test
{
/// A scan over `ranges` (which must outlive it): beam i at angle_min + i * increment.
inline line_extraction::ScanInput scanOf(const std::vector<float>& ranges, double angle_min, double increment,
                                         double range_min = 0.05, double range_max = 20.0)
{
  line_extraction::ScanInput s;
  s.ranges = ranges.data();
  s.count = ranges.size();
  s.angle_min = angle_min;
  s.angle_increment = increment;
  s.range_min = range_min;
  s.range_max = range_max;
  return s;
}

/// The preprocessed points of `ranges` (range limits 0.01 to 100 m).
inline line_extraction::PreparedScan prepared(const std::vector<float>& ranges, double angle_min,
                                              double increment)
{
  line_extraction::Preprocessor pre;
  line_extraction::PreparedScan out;
  pre.prepare(scanOf(ranges, angle_min, increment, 0.01, 100.0), out);
  return out;
}

/// Ranges of a laser at (cx, cy) with heading `yaw` inside the square room
/// |x| <= half_size, |y| <= half_size, each beam hitting the nearest wall;
/// Gaussian range noise `sigma` (0 = exact) drawn from `seed`.
inline std::vector<float> squareRoomRanges(double half_size, double cx, double cy, double yaw, int beams,
                                           double angle_min, double angle_increment, double sigma = 0.0,
                                           std::uint32_t seed = 1)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma > 0.0 ? sigma : 1.0);
  std::vector<float> ranges(beams);
  for (int i = 0; i < beams; ++i)
  {
    const double a = yaw + angle_min + i * angle_increment;
    const double dx = std::cos(a), dy = std::sin(a);
    double t = std::numeric_limits<double>::infinity();
    if (dx > 1e-12) t = std::min(t, (half_size - cx) / dx);
    if (dx < -1e-12) t = std::min(t, (-half_size - cx) / dx);
    if (dy > 1e-12) t = std::min(t, (half_size - cy) / dy);
    if (dy < -1e-12) t = std::min(t, (-half_size - cy) / dy);
    ranges[i] = static_cast<float>(t + (sigma > 0.0 ? noise(rng) : 0.0));
  }
  return ranges;
}

}  // namespace line_extraction_test
