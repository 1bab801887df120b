#include "line_map_eval/metrics/point_coverage.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "line_map_eval/metrics/segment_tree.hpp"

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

PointCoverage computePointCoverage(const std::vector<Vec2>& points, const std::vector<Segment2>& map,
                                   double radius)
{
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("point coverage: radius " + std::to_string(radius) +
                                " must be finite and >= 0");
  const SegmentTree tree = segmentTree(map, radius, "point coverage");

  PointCoverage c;
  c.points = points.size();
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const Vec2& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument("point coverage: scan point " + std::to_string(i) + " is not finite");
    bool covered = false;
    // Stops at the first segment close enough: most points lie on a wall, near one segment.
    for (auto it = tree.qbegin(boost::geometry::index::intersects(SegmentPoint(p.x(), p.y())));
         it != tree.qend() && !covered; ++it)
    {
      const Segment2& m = map[it->second];
      covered = linemap::distanceToSegment(p, m.start, m.end) <= radius;
    }
    if (covered)
      ++c.covered;
    else
      c.uncovered.push_back(i);
  }
  return c;
}

}  // namespace line_map_eval
