// Synthetic walls, keyframes and odometry drift for the merging tests (no dependency on line_map_eval).
#pragma once

#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"
#include "linemap/geometry.hpp"

namespace synthetic
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

/// The part of `wall` within `range` of `p`, in the wall's direction; nothing when shorter than min_length.
inline std::optional<Segment2> visiblePart(const Segment2& wall, const Vec2& p, double range,
                                           double min_length)
{
  const Vec2 d = wall.end - wall.start;
  const Vec2 f = wall.start - p;
  const double a = d.squaredNorm(), b = 2.0 * f.dot(d), c = f.squaredNorm() - range * range;
  const double disc = b * b - 4.0 * a * c;
  if (disc <= 0.0) return std::nullopt;
  const double t0 = std::max(0.0, (-b - std::sqrt(disc)) / (2.0 * a));
  const double t1 = std::min(1.0, (-b + std::sqrt(disc)) / (2.0 * a));
  if (t1 <= t0) return std::nullopt;
  Segment2 s(wall.start + t0 * d, wall.start + t1 * d);
  if (s.length() < min_length) return std::nullopt;
  return s;
}

/// Noisy copy of a local segment: a common perpendicular offset, a small rotation, endpoint jitter.
inline Segment2 addNoise(const Segment2& s, std::mt19937& rng, double offset_sigma, double angle_sigma,
                         double end_sigma)
{
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec2 u = (s.end - s.start).normalized();
  const Vec2 normal(-u.y(), u.x());
  const Vec2 mid = s.midpoint() + offset_sigma * n(rng) * normal;
  const double half = 0.5 * s.length();
  const double rot = angle_sigma * n(rng);
  const Vec2 ur(std::cos(rot) * u.x() - std::sin(rot) * u.y(), std::sin(rot) * u.x() + std::cos(rot) * u.y());
  return {mid - (half + end_sigma * n(rng)) * ur, mid + (half + end_sigma * n(rng)) * ur};
}

/// A rectangular corridor loop around a block: outer box [0,W]x[0,H], inner block [g,W-g]x[g,H-g].
/// Both boxes run counter-clockwise: the corridor is left of the outer walls and right of the inner ones.
struct Corridor
{
  double width = 20.0, height = 12.0, gap = 2.0;

  std::vector<Segment2> walls() const
  {
    const double W = width, H = height, g = gap;
    auto box = [](double x0, double y0, double x1, double y1)
    {
      return std::vector<Segment2>{{Vec2(x0, y0), Vec2(x1, y0)},
                                   {Vec2(x1, y0), Vec2(x1, y1)},
                                   {Vec2(x1, y1), Vec2(x0, y1)},
                                   {Vec2(x0, y1), Vec2(x0, y0)}};
    };
    std::vector<Segment2> w = box(0, 0, W, H);
    for (const Segment2& s : box(g, g, W - g, H - g)) w.push_back(s);
    return w;
  }

  /// True poses every `step` metres along the centre line, counter-clockwise, one full loop plus `extra`
  /// metres.
  std::vector<Pose2> loop(double step, double extra) const
  {
    const double c = 0.5 * gap;
    const std::vector<Vec2> corners{{c, c}, {width - c, c}, {width - c, height - c}, {c, height - c}};
    std::vector<Pose2> poses;
    double travelled = 0.0;
    const double total = 2.0 * (width + height - 2.0 * gap) + extra;
    for (int leg = 0; travelled < total; leg = (leg + 1) % 4)
    {
      const Vec2 a = corners[leg], b = corners[(leg + 1) % 4];
      const double len = (b - a).norm();
      const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
      for (double s = 0.0; s < len && travelled < total; s += step, travelled += step)
      {
        const Vec2 p = a + (s / len) * (b - a);
        poses.emplace_back(p.x(), p.y(), heading);
      }
    }
    return poses;
  }
};

/// Odometry-like drift: relative motions of `truth` with a heading bias per step and noise.
inline std::vector<Pose2> drift(const std::vector<Pose2>& truth, double heading_bias, double heading_sigma,
                                double scale, std::mt19937& rng)
{
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Pose2> out{truth.front()};
  for (std::size_t i = 1; i < truth.size(); ++i)
  {
    Pose2 rel = truth[i - 1].inverse() * truth[i];
    rel.x *= scale;
    rel.y *= scale;
    rel.theta = linemap::normalizeAngle(rel.theta + heading_bias + heading_sigma * n(rng));
    out.push_back(out.back() * rel);
  }
  return out;
}

/// Keyframes seeing `walls` from the true poses (segments in the laser frame), posed at `believed`.
/// A wall is seen only from its open side: the left for the first `outer` walls, the right for the others.
inline std::vector<line_map_merging::Keyframe> observe(const std::vector<Segment2>& walls,
                                                       const std::vector<Pose2>& truth,
                                                       const std::vector<Pose2>& believed, double range,
                                                       std::mt19937& rng, std::size_t outer = 4,
                                                       double offset_sigma = 0.003,
                                                       double angle_sigma = 0.002, double end_sigma = 0.01)
{
  std::vector<line_map_merging::Keyframe> kfs;
  for (std::size_t i = 0; i < truth.size(); ++i)
  {
    line_map_merging::Keyframe k;
    k.index = i;
    k.stamp = 100.0 + static_cast<double>(i);
    k.pose = believed[i];
    const Pose2 inv = truth[i].inverse();
    for (std::size_t j = 0; j < walls.size(); ++j)
    {
      const Segment2& w = walls[j];
      const Vec2 e = w.end - w.start, q = truth[i].translation() - w.start;
      const bool left = e.x() * q.y() - e.y() * q.x() > 0.0;
      if (left != (j < outer)) continue;
      if (auto v = visiblePart(w, truth[i].translation(), range, 0.3))
        k.segments.push_back(addNoise(v->transformed(inv), rng, offset_sigma, angle_sigma, end_sigma));
    }
    kfs.push_back(std::move(k));
  }
  return kfs;
}

/// Keyframe `index` (stamped `index` s) at `pose`, seeing the `world` segments exactly, in its frame.
inline line_map_merging::Keyframe keyframeOf(std::uint64_t index, const Pose2& pose,
                                             const std::vector<Segment2>& world)
{
  line_map_merging::Keyframe k;
  k.index = index;
  k.stamp = static_cast<double>(index);
  k.pose = pose;
  for (const Segment2& s : world) k.segments.push_back(s.transformed(pose.inverse()));
  return k;
}

}  // namespace synthetic
