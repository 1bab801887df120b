// Closed-form scans for unit tests: a laser inside an axis-aligned square room.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace line_extraction_test
{
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
