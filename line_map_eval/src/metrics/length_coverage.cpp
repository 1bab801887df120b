#include "line_map_eval/metrics/length_coverage.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

#include "line_map_eval/metrics/segment_tree.hpp"
#include "line_map_merging/mergers/fusion.hpp"

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// Narrows [t0, t1] to the t with lo <= c0 + c1 t <= hi; returns false when nothing is left.
bool clipLinear(double c0, double c1, double lo, double hi, double& t0, double& t1)
{
  if (c1 == 0.0) return c0 >= lo && c0 <= hi && t0 <= t1;
  double a = (lo - c0) / c1, b = (hi - c0) / c1;
  if (a > b) std::swap(a, b);
  t0 = std::max(t0, a);
  t1 = std::min(t1, b);
  return t0 <= t1;
}
}  // namespace

LengthCoverage computeLengthCoverage(const std::vector<Segment2>& originals, const std::vector<Segment2>& map,
                                     double max_distance, double max_angle)
{
  if (!(max_distance >= 0.0) || !std::isfinite(max_distance))
    throw std::invalid_argument("length coverage: max_distance must be finite and >= 0");
  if (!(max_angle >= 0.0) || !std::isfinite(max_angle))
    throw std::invalid_argument("length coverage: max_angle must be finite and >= 0");
  // A represented point lies within max_distance of M's line with its foot on M: inside M's box
  // padded by max_distance.
  const SegmentTree tree = segmentTree(map, max_distance, "length coverage");

  LengthCoverage c;
  std::vector<SegmentEntry> hits;
  std::vector<std::pair<double, double>> intervals;
  for (std::size_t i = 0; i < originals.size(); ++i)
  {
    const Segment2& o = originals[i];
    if (!o.start.allFinite() || !o.end.allFinite())
      throw std::invalid_argument("length coverage: original segment " + std::to_string(i) +
                                  " has non-finite coordinates");
    const double length = o.length();
    if (!(length > 0.0)) continue;
    c.total += length;
    hits.clear();
    tree.query(boost::geometry::index::intersects(segmentBox(o)), std::back_inserter(hits));
    intervals.clear();
    const Vec2 d = o.end - o.start;  // p(t) = o.start + t d, t in [0, 1]
    for (const SegmentEntry& e : hits)
    {
      const Segment2& m = map[e.second];
      const double lm = m.length();
      if (!(lm > 0.0) || line_map_merging::headingDeviation(m, o) > max_angle) continue;
      const Vec2 u = (m.end - m.start) / lm, n(-u.y(), u.x());
      const Vec2 r = o.start - m.start;
      double t0 = 0.0, t1 = 1.0;
      // Foot on M: 0 <= (p - m.start).u <= |M|; near M's line: |(p - m.start).n| <= max_distance.
      if (clipLinear(r.dot(u), d.dot(u), 0.0, lm, t0, t1) &&
          clipLinear(r.dot(n), d.dot(n), -max_distance, max_distance, t0, t1) && t1 > t0)
        intervals.emplace_back(t0, t1);
    }
    std::sort(intervals.begin(), intervals.end());
    double covered = 0.0, end = 0.0;
    for (const auto& [a, b] : intervals)
    {
      const double from = std::max(a, end);
      if (b > from) covered += b - from;
      end = std::max(end, b);
    }
    c.covered += covered * length;
  }
  return c;
}

}  // namespace line_map_eval
