#include "line_map_merging/slam/scan_surfaces.hpp"

#include <cmath>

#include "line_extraction/breakpoint_clustering.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
std::vector<linemap::Segment2> scanSurfaces(const std::vector<linemap::Vec2>& points, const SurfaceParams& params)
{
  std::vector<linemap::Segment2> out;
  const int n = static_cast<int>(points.size());
  line_extraction::PreparedScan scan;
  scan.points = points;
  std::vector<double> steps;
  for (const auto& p : points)
  {
    scan.ranges.push_back(p.norm());
    scan.angles.push_back(std::atan2(p.y(), p.x()));
    if (scan.angles.size() > 1) steps.push_back(std::fabs(scan.angles.back() - scan.angles[scan.angles.size() - 2]));
  }
  // Neighbouring beams: no more than one and a half of the scan's usual angular step apart.
  const double neighbour = steps.empty() ? 0.0 : 1.5 * linemap::median(steps);
  line_extraction::BreakpointParams breakpoint;
  breakpoint.lambda = params.lambda;
  breakpoint.sigma = params.range_sigma;
  const double tolerance = 3.0 * params.range_sigma;
  bool joined_before = false;  // the pair (i - 2, i - 1)
  for (int i = 1; i < n; ++i)
  {
    bool joined = !line_extraction::isBreakpoint(scan, i, breakpoint);
    if (!joined && joined_before && steps[i - 1] <= neighbour)
    {
      const linemap::Vec2 &a = points[i - 2], &b = points[i - 1], &c = points[i];
      joined = (c - b).dot(b - a) > 0.0 && linemap::distanceToLine(c, a, b) <= tolerance;
    }
    if (joined)
      out.emplace_back(points[i - 1], points[i]);
    else if (!joined_before)
      out.emplace_back(points[i - 1], points[i - 1]);  // alone
    joined_before = joined;
  }
  if (n > 0 && !joined_before) out.emplace_back(points[n - 1], points[n - 1]);
  return out;
}

}  // namespace line_map_merging
