#include "line_map_merging/mergers/crossing_pairs.hpp"

#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

namespace line_map_merging
{
using linemap::Segment2;
using linemap::Vec2;

using linemap::cross;

bool segmentsCross(const Segment2& a, const Segment2& b, double min_overhang, Vec2* point)
{
  const Vec2 r = a.end - a.start;
  const Vec2 s = b.end - b.start;
  const double la = r.norm(), lb = s.norm();
  // Both overhangs together need more than 2 * min_overhang of length; this also drops points.
  if (la <= 2.0 * min_overhang || lb <= 2.0 * min_overhang || la <= 0.0 || lb <= 0.0) return false;
  const double denom = cross(r, s);
  // Parallel lines (relative test, so scale does not matter) have no single intersection.
  if (std::abs(denom) <= 1e-12 * la * lb) return false;
  const Vec2 qp = b.start - a.start;
  const double t = cross(qp, s) / denom;  // along a, in [0, 1] on the segment
  const double u = cross(qp, r) / denom;  // along b
  const double ta = t * la, tb = u * lb;  // arc lengths from the starts
  if (ta <= min_overhang || la - ta <= min_overhang || tb <= min_overhang || lb - tb <= min_overhang)
    return false;
  if (point) *point = a.start + t * r;
  return true;
}

std::vector<CrossingPair> findCrossingPairs(const std::vector<Segment2>& map, double min_overhang)
{
  namespace bg = boost::geometry;
  namespace bgi = boost::geometry::index;
  using Point = bg::model::point<double, 2, bg::cs::cartesian>;
  using Box = bg::model::box<Point>;
  using Entry = std::pair<Box, int>;

  if (!std::isfinite(min_overhang) || min_overhang < 0.0)
    throw std::invalid_argument("crossing pairs: min_overhang must be finite and >= 0, got " +
                                std::to_string(min_overhang));
  std::vector<Entry> entries;
  entries.reserve(map.size());
  for (std::size_t j = 0; j < map.size(); ++j)
  {
    const Segment2& m = map[j];
    if (!m.start.allFinite() || !m.end.allFinite())
      throw std::invalid_argument("crossing pairs: map segment " + std::to_string(j) +
                                  " has non-finite coordinates");
    entries.emplace_back(Box(Point(std::min(m.start.x(), m.end.x()), std::min(m.start.y(), m.end.y())),
                             Point(std::max(m.start.x(), m.end.x()), std::max(m.start.y(), m.end.y()))),
                         static_cast<int>(j));
  }
  const bgi::rtree<Entry, bgi::quadratic<16>> tree(entries.begin(), entries.end());

  std::vector<CrossingPair> pairs;
  std::vector<Entry> hits;
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    hits.clear();
    // Crossing segments intersect, so their boxes do.
    tree.query(bgi::intersects(entries[i].first), std::back_inserter(hits));
    for (const Entry& e : hits)
    {
      const int j = e.second;
      Vec2 p;
      if (j <= static_cast<int>(i) || !segmentsCross(map[i], map[j], min_overhang, &p)) continue;
      pairs.push_back({static_cast<int>(i), j, p});
    }
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const CrossingPair& x, const CrossingPair& y)
            { return std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b); });
  return pairs;
}

}  // namespace line_map_merging
