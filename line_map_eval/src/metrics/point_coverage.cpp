#include "line_map_eval/metrics/point_coverage.hpp"

#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

PointCoverage computePointCoverage(const std::vector<Vec2>& points, const std::vector<Segment2>& map,
                                   double radius)
{
  namespace bg = boost::geometry;
  namespace bgi = boost::geometry::index;
  using Point = bg::model::point<double, 2, bg::cs::cartesian>;
  using Box = bg::model::box<Point>;
  using Entry = std::pair<Box, std::size_t>;

  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("point coverage: radius " + std::to_string(radius) +
                                " must be finite and >= 0");
  std::vector<Entry> entries;
  entries.reserve(map.size());
  for (std::size_t j = 0; j < map.size(); ++j)
  {
    const Segment2& m = map[j];
    if (!m.start.allFinite() || !m.end.allFinite())
      throw std::invalid_argument("point coverage: map segment " + std::to_string(j) +
                                  " has non-finite coordinates");
    entries.emplace_back(
        Box(Point(std::min(m.start.x(), m.end.x()) - radius, std::min(m.start.y(), m.end.y()) - radius),
            Point(std::max(m.start.x(), m.end.x()) + radius, std::max(m.start.y(), m.end.y()) + radius)),
        j);
  }
  const bgi::rtree<Entry, bgi::quadratic<16>> tree(entries.begin(), entries.end());

  PointCoverage c;
  c.points = points.size();
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const Vec2& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument("point coverage: scan point " + std::to_string(i) + " is not finite");
    bool covered = false;
    // Stops at the first segment close enough: most points lie on a wall, near one segment.
    for (auto it = tree.qbegin(bgi::intersects(Point(p.x(), p.y()))); it != tree.qend() && !covered; ++it)
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
