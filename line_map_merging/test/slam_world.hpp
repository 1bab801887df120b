// A ray-cast 2D world for the SLAM tests: walls as segments, scans as the nearest hit of each beam.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "linemap/geometry.hpp"

namespace slam_world
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

/// Range of the ray from `o` in direction `d` to the nearest wall, or infinity.
inline double castRay(const std::vector<Segment2>& walls, const Vec2& o, const Vec2& d)
{
  double best = std::numeric_limits<double>::infinity();
  for (const auto& w : walls)
  {
    const Vec2 e = w.end - w.start;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::fabs(den) < 1e-12) continue;
    const Vec2 f = w.start - o;
    const double t = (f.x() * e.y() - f.y() * e.x()) / den;  // along the ray
    const double u = (f.x() * d.y() - f.y() * d.x()) / den;  // along the wall
    if (t > 1e-9 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return best;
}

/// Points (in the sensor frame) of a 180-degree scan of `beams` beams from `pose`, ranges up to
/// `max_range`, with Gaussian range noise.
inline std::vector<Vec2> scan(const std::vector<Segment2>& walls, const Pose2& pose, int beams,
                              double max_range, double noise = 0.0, unsigned seed = 1)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise > 0.0 ? noise : 1.0);
  std::vector<Vec2> points;
  for (int i = 0; i < beams; ++i)
  {
    const double a = -linemap::kPi / 2 + linemap::kPi * (i + 0.5) / beams;
    const double world_a = pose.theta + a;
    double r = castRay(walls, pose.translation(), {std::cos(world_a), std::sin(world_a)});
    if (!(r <= max_range)) continue;
    if (noise > 0.0) r += n(rng);
    points.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return points;
}

/// The poses of a robot driving from `start` through `goals` (start not included): 5 cm per scan,
/// turning on the spot at 0.1 rad per scan towards each goal first.
inline std::vector<Pose2> drive(Pose2 p, const std::vector<Vec2>& goals)
{
  std::vector<Pose2> path;
  for (const Vec2& goal : goals)
  {
    const double heading = std::atan2(goal.y() - p.y, goal.x() - p.x);
    while (std::fabs(linemap::normalizeAngle(heading - p.theta)) > 1e-9)
    {
      const double d = linemap::normalizeAngle(heading - p.theta);
      p.theta = linemap::normalizeAngle(p.theta + std::clamp(d, -0.1, 0.1));
      path.push_back(p);
    }
    while ((goal - p.translation()).norm() > 1e-9)
    {
      const Vec2 step = goal - p.translation();
      const double len = std::min(0.05, step.norm());
      p.x += step.x() / step.norm() * len;
      p.y += step.y() / step.norm() * len;
      path.push_back(p);
    }
  }
  return path;
}

/// A 12 x 8 m room with a few boxes and a niche: no symmetry a matcher could confuse.
inline std::vector<Segment2> room()
{
  std::vector<Segment2> w = {{{0, 0}, {12, 0}}, {{12, 0}, {12, 8}}, {{12, 8}, {5, 8}}, {{5, 8}, {5, 9}},
                             {{5, 9}, {3, 9}},  {{3, 9}, {3, 8}},   {{3, 8}, {0, 8}},  {{0, 8}, {0, 0}}};
  auto box = [&](double x, double y, double sx, double sy)
  {
    w.push_back({{x, y}, {x + sx, y}});
    w.push_back({{x + sx, y}, {x + sx, y + sy}});
    w.push_back({{x + sx, y + sy}, {x, y + sy}});
    w.push_back({{x, y + sy}, {x, y}});
  };
  box(2, 2, 1, 0.6);
  box(8, 5, 0.5, 1.5);
  box(9.5, 1.5, 1.2, 0.4);
  return w;
}

}  // namespace slam_world
