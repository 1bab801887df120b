#include "line_map_merging/mergers/fusion.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace line_map_merging
{
FusionParams FusionParams::fromParams(const linemap::ParamSet& params)
{
  FusionParams p;
  linemap::readFields(params,
                      {{"fusion/max_angle", &FusionParams::max_angle},
                       {"fusion/max_distance", &FusionParams::max_distance},
                       {"fusion/min_overlap", &FusionParams::min_overlap}},
                      p);
  const std::string weighting = params.getString("fusion/weighting", "length");
  if (weighting == "length")
    p.weighting = FusionWeighting::length;
  else if (weighting == "count")
    p.weighting = FusionWeighting::count;
  else
    throw linemap::ParameterError("parameter 'fusion/weighting': '" + weighting +
                                  "' is neither 'length' nor 'count'");
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
  // The cheapest test first (the heading costs two atan2); the outcome does not depend on the order.
  return horizontalOverlap(map, scan) >= params.min_overlap &&
         verticalDistance(map, scan) <= params.max_distance &&
         headingDeviation(map, scan) <= params.max_angle;
}

bool meetEachOther(const Segment2& a, const Segment2& b, const FusionParams& params)
{
  return meetsFusionConditions(a, b, params) || meetsFusionConditions(b, a, params);
}

bool liesWithin(const Segment2& outer, const Segment2& inner, const FusionParams& params)
{
  const Vec2 d = outer.end - outer.start;
  const double length = d.norm();
  if (!(length > 0.0)) return false;
  const Vec2 u = d / length;
  const double a = (inner.start - outer.start).dot(u);
  const double b = (inner.end - outer.start).dot(u);
  // The heading (two atan2) last: the outcome does not depend on the order.
  return std::min(a, b) >= 0.0 && std::max(a, b) <= length &&
         verticalDistance(outer, inner) <= params.max_distance &&
         headingDeviation(outer, inner) < 0.5 * linemap::kPi;
}

void FusionMoments::add(const Segment2& s, double w)
{
  const Vec2 d = s.end - s.start;
  const double n = d.norm();
  const Vec2 c = s.midpoint();
  if (weight == 0.0) reference = c;
  weight += w;
  centroid_sum += w * c;
  if (n > 0.0) direction_sum += (w / n) * d;
  const double m = w * n;
  const Vec2 r = c - reference;
  mass += m;
  first += m * r;
  second += m * (r * r.transpose() + d * d.transpose() / 12.0);
}

void FusionMoments::add(const FusionMoments& m)
{
  if (m.weight == 0.0) return;
  if (weight == 0.0)
  {
    *this = m;
    return;
  }
  weight += m.weight;
  centroid_sum += m.centroid_sum;
  direction_sum += m.direction_sum;
  // Parallel axis theorem: m's moments about this reference.
  const Vec2 delta = m.reference - reference;
  mass += m.mass;
  first += m.first + m.mass * delta;
  second += m.second + delta * m.first.transpose() + m.first * delta.transpose() +
            m.mass * delta * delta.transpose();
}

Vec2 FusionMoments::centroid(FusionWeighting weighting) const
{
  if (weighting == FusionWeighting::length && mass > 0.0) return reference + first / mass;
  return centroid_sum / weight;
}

Vec2 FusionMoments::direction(FusionWeighting weighting) const
{
  const double n = direction_sum.norm();
  // Headings within max_angle of each other never cancel; a zero sum only comes from degenerate input.
  const Vec2 mean = n > 0.0 ? Vec2(direction_sum / n) : Vec2(1.0, 0.0);
  if (weighting != FusionWeighting::length || !(mass > 0.0)) return mean;
  const Vec2 mu = first / mass;
  const Eigen::Matrix2d cov = second / mass - mu * mu.transpose();
  // Principal axis of a symmetric 2x2 matrix in closed form.
  const double angle = 0.5 * std::atan2(2.0 * cov(0, 1), cov(0, 0) - cov(1, 1));
  const Vec2 axis(std::cos(angle), std::sin(angle));
  return axis.dot(mean) < 0.0 ? Vec2(-axis) : axis;
}

FusedLine::FusedLine(const FusionMoments& moments, FusionWeighting weighting)
    : origin_(moments.centroid(weighting)),
      direction_(moments.direction(weighting)),
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

Segment2 fuse(const std::vector<WeightedSegment>& segments, FusionWeighting weighting)
{
  if (segments.empty()) throw std::invalid_argument("fuse: no segments to fuse");
  FusionMoments moments;
  for (const auto& s : segments)
  {
    if (!(s.weight > 0.0)) throw std::invalid_argument("fuse: segment weight must be > 0");
    moments.add(s.segment, s.weight);
  }
  FusedLine line(moments, weighting);
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
