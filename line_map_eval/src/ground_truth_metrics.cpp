#include "line_map_eval/ground_truth_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// Heading difference of two undirected lines, in [0, pi/2].
double undirectedAngle(const Segment2& a, const Segment2& b)
{
  const double d = std::abs(linemap::normalizeAngle(a.heading() - b.heading()));
  return std::min(d, linemap::kPi - d);
}

void requirePositive(double v, const char* key)
{
  if (!(v > 0.0) || !std::isfinite(v))
    throw linemap::ParameterError(std::string("parameter '") + key + "' must be positive, got " +
                                  std::to_string(v));
}

void checkFinite(const std::vector<Segment2>& segments, const char* what)
{
  for (std::size_t i = 0; i < segments.size(); ++i)
    if (!segments[i].start.allFinite() || !segments[i].end.allFinite())
      throw std::invalid_argument(std::string("ground truth metrics: ") + what + " " + std::to_string(i) +
                                  " has non-finite coordinates");
}
}  // namespace

GroundTruthParams GroundTruthParams::fromParams(const linemap::ParamSet& params)
{
  constexpr double deg = linemap::kPi / 180.0;
  GroundTruthParams p;
  p.coverage_tolerance = params.getDouble("eval/gt_coverage_tolerance", p.coverage_tolerance);
  p.sample_spacing = params.getDouble("eval/gt_sample_spacing", p.sample_spacing);
  p.association_angle = deg * params.getDouble("eval/gt_association_angle_deg", p.association_angle / deg);
  p.association_distance = params.getDouble("eval/gt_association_distance", p.association_distance);
  p.corner_tolerance = params.getDouble("eval/gt_corner_tolerance", p.corner_tolerance);
  p.corner_min_angle = deg * params.getDouble("eval/gt_corner_min_angle_deg", p.corner_min_angle / deg);
  p.vertex_radius = params.getDouble("eval/gt_vertex_radius", p.vertex_radius);
  p.validate();
  return p;
}

void GroundTruthParams::validate() const
{
  requirePositive(coverage_tolerance, "eval/gt_coverage_tolerance");
  requirePositive(sample_spacing, "eval/gt_sample_spacing");
  requirePositive(association_distance, "eval/gt_association_distance");
  requirePositive(corner_tolerance, "eval/gt_corner_tolerance");
  requirePositive(vertex_radius, "eval/gt_vertex_radius");
  if (!(association_angle >= 0.0) || association_angle > 0.5 * linemap::kPi)
    throw linemap::ParameterError("parameter 'eval/gt_association_angle_deg' must be in [0, 90]");
  if (!(corner_min_angle >= 0.0) || corner_min_angle > 0.5 * linemap::kPi)
    throw linemap::ParameterError("parameter 'eval/gt_corner_min_angle_deg' must be in [0, 90]");
}

std::vector<Vec2> findCorners(const std::vector<Segment2>& walls, const GroundTruthParams& params)
{
  std::vector<Vec2> corners;
  for (std::size_t i = 0; i < walls.size(); ++i)
    for (std::size_t j = i + 1; j < walls.size(); ++j)
    {
      if (undirectedAngle(walls[i], walls[j]) < params.corner_min_angle) continue;
      for (const Vec2& a : {walls[i].start, walls[i].end})
        for (const Vec2& b : {walls[j].start, walls[j].end})
        {
          if ((a - b).norm() > params.corner_tolerance) continue;
          const Vec2 c = 0.5 * (a + b);
          const bool known =
              std::any_of(corners.begin(), corners.end(),
                          [&](const Vec2& k) { return (k - c).norm() <= params.corner_tolerance; });
          if (!known) corners.push_back(c);
        }
    }
  return corners;
}

GroundTruthResult evaluateAgainstGroundTruth(const std::vector<Segment2>& walls,
                                             const std::vector<Segment2>& map,
                                             const GroundTruthParams& params)
{
  params.validate();
  checkFinite(walls, "wall");
  checkFinite(map, "map segment");
  GroundTruthResult r;
  double covered_length = 0.0, total_length = 0.0, vertex_sum = 0.0;
  std::vector<const Segment2*> assoc;
  for (std::size_t w = 0; w < walls.size(); ++w)
  {
    const Segment2& wall = walls[w];
    WallScore score;
    score.length = wall.length();
    if (!(score.length > 0.0))
      throw std::invalid_argument("ground truth metrics: wall " + std::to_string(w) + " has zero length");
    assoc.clear();
    for (const Segment2& m : map)
      if (undirectedAngle(m, wall) <= params.association_angle &&
          linemap::distanceToSegment(m.midpoint(), wall.start, wall.end) <= params.association_distance)
        assoc.push_back(&m);
    score.associated = assoc.size();

    const std::size_t steps = static_cast<std::size_t>(std::ceil(score.length / params.sample_spacing));
    std::size_t covered = 0;
    for (std::size_t k = 0; k <= steps; ++k)
    {
      const Vec2 p =
          wall.start + (static_cast<double>(k) / static_cast<double>(steps)) * (wall.end - wall.start);
      for (const Segment2* m : assoc)
        if (linemap::distanceToSegment(p, m->start, m->end) <= params.coverage_tolerance)
        {
          ++covered;
          break;
        }
    }
    score.coverage = static_cast<double>(covered) / static_cast<double>(steps + 1);

    if (assoc.empty())
    {
      score.endpoint_error = std::numeric_limits<double>::infinity();
      ++r.undetected_walls;
    }
    else
    {
      for (const Vec2& end : {wall.start, wall.end})
      {
        double nearest = std::numeric_limits<double>::infinity();
        for (const Segment2* m : assoc)
          nearest = std::min({nearest, (m->start - end).norm(), (m->end - end).norm()});
        score.endpoint_error = std::max(score.endpoint_error, nearest);
      }
      r.max_endpoint_error = std::max(r.max_endpoint_error, score.endpoint_error);
    }
    covered_length += score.coverage * score.length;
    total_length += score.length;
    r.walls.push_back(score);
  }
  if (total_length > 0.0) r.coverage = covered_length / total_length;

  std::size_t corners_with_endpoints = 0;
  for (const Vec2& c : findCorners(walls, params))
  {
    CornerScore cs;
    cs.corner = c;
    for (const Segment2& m : map)
      for (const Vec2& e : {m.start, m.end})
      {
        const double d = (e - c).norm();
        if (d > params.vertex_radius) continue;
        cs.vertex_error += d;
        ++cs.endpoints;
      }
    if (cs.endpoints == 0)
      ++r.missed_corners;
    else
    {
      vertex_sum += cs.vertex_error;
      ++corners_with_endpoints;
    }
    r.corners.push_back(cs);
  }
  if (corners_with_endpoints > 0)
    r.mean_vertex_error = vertex_sum / static_cast<double>(corners_with_endpoints);
  return r;
}

}  // namespace line_map_eval
