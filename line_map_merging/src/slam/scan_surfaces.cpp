#include "line_map_merging/slam/scan_surfaces.hpp"

#include <cmath>

#include "line_extraction/breakpoint_clustering.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
std::vector<linemap::Segment2> scanSurfaces(const std::vector<linemap::Vec2>& points,
                                            const SurfaceParams& params)
{
  std::vector<linemap::Segment2> out;
  const int n = static_cast<int>(points.size());
  if (!(params.lambda > 0.0)) return out;
  line_extraction::PreparedScan scan;
  scan.points = points;
  std::vector<double> steps;
  for (const auto& p : points)
  {
    scan.ranges.push_back(p.norm());
    scan.angles.push_back(std::atan2(p.y(), p.x()));
    if (scan.angles.size() > 1)
      steps.push_back(std::fabs(scan.angles.back() - scan.angles[scan.angles.size() - 2]));
  }
  // Neighbouring beams: no more than one and a half of the scan's usual angular step apart.
  const double neighbour = steps.empty() ? 0.0 : 1.5 * linemap::median(steps);
  line_extraction::BreakpointParams breakpoint;
  breakpoint.lambda = params.lambda;
  breakpoint.sigma = params.range_sigma;
  // joined[i]: points i - 1 and i lie on one surface.
  std::vector<bool> joined(static_cast<std::size_t>(n), false);
  for (int i = 1; i < n; ++i) joined[i] = !line_extraction::isBreakpoint(scan, i, breakpoint);
  // Whether c continues the line from a through b, beyond b, with no beam skipped between b and c.
  const double tolerance = 3.0 * params.range_sigma;
  auto continues = [&](int a, int b, int c)
  {
    const linemap::Vec2 &pa = points[a], &pb = points[b], &pc = points[c];
    return steps[std::min(b, c)] <= neighbour && (pc - pb).dot(pb - pa) > 0.0 &&
           linemap::distanceToLine(pc, pa, pb) <= tolerance;
  };
  // A pair the breakpoint test joins is kept only when a third point continues it along its line: two
  // points alone may be two objects at similar ranges, and a phantom wall between them pulls a match.
  std::vector<bool> straight(joined.size(), false);
  for (int i = 1; i < n; ++i)
    straight[i] = joined[i] && ((i >= 2 && joined[i - 1] && continues(i - 2, i - 1, i)) ||
                                (i + 1 < n && joined[i + 1] && continues(i + 1, i, i - 1)));
  joined = straight;
  // A grazing wall's points lie farther apart than the breakpoint test allows: extend the joined
  // pairs along their lines, both ways (the wall may run away from either end of the scan).
  for (int i = 2; i < n; ++i)
    if (!joined[i] && joined[i - 1] && continues(i - 2, i - 1, i)) joined[i] = true;
  for (int i = n - 2; i >= 1; --i)
    if (!joined[i] && joined[i + 1] && continues(i + 1, i, i - 1)) joined[i] = true;
  for (int i = 1; i < n; ++i)
    if (joined[i]) out.emplace_back(points[i - 1], points[i]);
  return out;
}

}  // namespace line_map_merging
