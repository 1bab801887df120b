#include "line_map_merging/fusion.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace line_map_merging
{
FusionParams FusionParams::fromParams(const linemap::ParamSet& params)
{
  FusionParams p;
  p.max_angle = params.getDouble("fusion/max_angle", p.max_angle);
  p.max_distance = params.getDouble("fusion/max_distance", p.max_distance);
  p.min_overlap = params.getDouble("fusion/min_overlap", p.min_overlap);
  p.validate();
  return p;
}

void FusionParams::validate() const
{
  if (!(max_angle >= 0.0 && max_angle <= linemap::kPi))
    throw linemap::ParameterError("parameter 'fusion/max_angle': " + std::to_string(max_angle) +
                                  " is not in [0, pi] rad");
  if (!(max_distance >= 0.0 && std::isfinite(max_distance)))
    throw linemap::ParameterError("parameter 'fusion/max_distance': " + std::to_string(max_distance) +
                                  " is not a finite distance >= 0 m");
  if (!std::isfinite(min_overlap))
    throw linemap::ParameterError("parameter 'fusion/min_overlap': " + std::to_string(min_overlap) +
                                  " is not finite");
}

double FusionParams::searchPadding() const
{
  return max_distance + std::max(0.0, -min_overlap);
}

double headingDeviation(const Segment2& map, const Segment2& scan)
{
  return std::abs(linemap::normalizeAngle(map.heading() - scan.heading()));
}

double verticalDistance(const Segment2& map, const Segment2& scan)
{
  return std::max(linemap::distanceToLine(scan.start, map.start, map.end),
                  linemap::distanceToLine(scan.end, map.start, map.end));
}

double horizontalOverlap(const Segment2& map, const Segment2& scan)
{
  const Vec2 d = map.end - map.start;
  const double length = d.norm();
  if (length <= 0.0) return -std::numeric_limits<double>::infinity();
  const Vec2 u = d / length;
  const double a = (scan.start - map.start).dot(u);
  const double b = (scan.end - map.start).dot(u);
  return std::min(std::max(a, b), length) - std::max(std::min(a, b), 0.0);
}

bool meetsFusionConditions(const Segment2& map, const Segment2& scan, const FusionParams& params)
{
  return headingDeviation(map, scan) <= params.max_angle &&
         verticalDistance(map, scan) <= params.max_distance &&
         horizontalOverlap(map, scan) >= params.min_overlap;
}

bool meetEachOther(const Segment2& a, const Segment2& b, const FusionParams& params)
{
  return meetsFusionConditions(a, b, params) || meetsFusionConditions(b, a, params);
}

void FusionMoments::add(const Segment2& s, double w)
{
  const Vec2 d = s.end - s.start;
  const double n = d.norm();
  weight += w;
  centroid_sum += w * s.midpoint();
  if (n > 0.0) direction_sum += (w / n) * d;
}

void FusionMoments::add(const FusionMoments& m)
{
  weight += m.weight;
  centroid_sum += m.centroid_sum;
  direction_sum += m.direction_sum;
}

Vec2 FusionMoments::direction() const
{
  const double n = direction_sum.norm();
  // Headings within max_angle of each other never cancel; a zero sum only comes from degenerate input.
  return n > 0.0 ? Vec2(direction_sum / n) : Vec2(1.0, 0.0);
}

FusedLine::FusedLine(const FusionMoments& moments)
    : origin_(moments.centroid()),
      direction_(moments.direction()),
      t_min_(std::numeric_limits<double>::infinity()),
      t_max_(-std::numeric_limits<double>::infinity())
{
}

void FusedLine::include(const Vec2& p)
{
  const double t = (p - origin_).dot(direction_);
  t_min_ = std::min(t_min_, t);
  t_max_ = std::max(t_max_, t);
}

Segment2 FusedLine::segment() const
{
  if (t_min_ > t_max_) return {origin_, origin_};
  return {origin_ + t_min_ * direction_, origin_ + t_max_ * direction_};
}

Segment2 fuse(const std::vector<WeightedSegment>& segments)
{
  if (segments.empty()) throw std::invalid_argument("fuse: no segments to fuse");
  FusionMoments moments;
  for (const auto& s : segments)
  {
    if (!(s.weight > 0.0)) throw std::invalid_argument("fuse: segment weight must be > 0");
    moments.add(s.segment, s.weight);
  }
  FusedLine line(moments);
  for (const auto& s : segments) line.include(s.segment);
  return line.segment();
}

bool isValidSegment(const Segment2& s)
{
  const auto inRange = [](const Vec2& p)
  { return std::abs(p.x()) <= kMaxCoordinate && std::abs(p.y()) <= kMaxCoordinate; };  // false for NaN
  return inRange(s.start) && inRange(s.end) && (s.end - s.start).squaredNorm() > 0.0;
}

}  // namespace line_map_merging
