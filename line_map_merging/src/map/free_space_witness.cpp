#include "line_map_merging/map/free_space_witness.hpp"

#include <algorithm>

namespace line_map_merging
{
using linemap::Segment2;
using linemap::Vec2;

using linemap::cross;

std::pair<double, double> clipToHalfPlanes(const Segment2& s, const HalfPlane* planes, std::size_t count)
{
  const Vec2 d = s.end - s.start;
  double lo = 0.0, hi = 1.0;
  for (std::size_t i = 0; i < count && lo < hi; ++i)
  {
    const double at_start = planes[i].n.dot(s.start) - planes[i].c;
    const double slope = planes[i].n.dot(d);
    if (slope == 0.0)
    {
      if (at_start < 0.0) return {1.0, 0.0};
      continue;
    }
    const double t = -at_start / slope;
    if (slope > 0.0)
      lo = std::max(lo, t);
    else
      hi = std::min(hi, t);
  }
  return {lo, hi};
}

std::uint32_t insideBins(const Segment2& s, const HalfPlane* planes, std::size_t count, std::size_t bins)
{
  const auto [lo, hi] = clipToHalfPlanes(s, planes, count);
  std::uint32_t mask = 0;
  for (std::size_t b = 0; b < bins; ++b)
  {
    const double centre = (static_cast<double>(b) + 0.5) / static_cast<double>(bins);
    if (centre >= lo && centre <= hi) mask |= 1u << b;
  }
  return mask;
}

bool makeWitness(const Vec2& laser, Segment2 segment, double margin, FreeSpaceWitness& w)
{
  Vec2 a = segment.start - laser, b = segment.end - laser;
  if (cross(a, b) < 0.0) std::swap(a, b);  // counter-clockwise: the inside is left of o->a, right of o->b
  const double na = a.norm(), nb = b.norm(), ab = (b - a).norm();
  if (na == 0.0 || nb == 0.0 || ab <= 2.0 * margin) return false;
  const Vec2 ua = a / na, ub = b / nb;
  // Outward normal of the segment's side (away from the laser) and the laser's distance from its line.
  const Vec2 outward = Vec2((b - a).y(), -(b - a).x()) / ab;
  const double distance = outward.dot(a);
  if (distance <= margin) return false;
  // In laser-relative coordinates x' = x - laser: n.x' - c >= 0  <=>  n.x - (c + n.laser) >= 0.
  const HalfPlane left{Vec2(-ua.y(), ua.x()), 0.0};   // cross(ua, x') >= 0
  const HalfPlane right{Vec2(ub.y(), -ub.x()), 0.0};  // cross(x', ub) >= 0
  const HalfPlane before{-outward, -distance};        // outward.x' <= distance
  const HalfPlane behind{outward, distance};          // outward.x' >= distance
  const auto shifted = [&](const HalfPlane& h, double by) {
    return HalfPlane{h.n, h.c + by + h.n.dot(laser)};
  };
  w.free[0] = shifted(left, margin);
  w.free[1] = shifted(right, margin);
  w.free[2] = shifted(before, margin);
  w.band[0] = shifted(left, 0.0);
  w.band[1] = shifted(right, 0.0);
  w.band[2] = shifted(before, -margin);
  w.band[3] = shifted(behind, -margin);
  w.box = {std::min({laser.x(), segment.start.x(), segment.end.x()}),
           std::min({laser.y(), segment.start.y(), segment.end.y()}),
           std::max({laser.x(), segment.start.x(), segment.end.x()}),
           std::max({laser.y(), segment.start.y(), segment.end.y()})};
  return true;
}

}  // namespace line_map_merging
