#include "line_map_eval/metrics/redundant_pairs.hpp"

#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <iterator>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
using linemap::Segment2;

double pairOverlap(const Segment2& a, const Segment2& b)
{
  const bool a_longer = a.length() >= b.length();
  return std::max(0.0, line_map_merging::horizontalOverlap(a_longer ? a : b, a_longer ? b : a));
}

RedundancyResult findRedundantPairs(const std::vector<Segment2>& map,
                                    const line_map_merging::FusionParams& params)
{
  namespace bg = boost::geometry;
  namespace bgi = boost::geometry::index;
  using Point = bg::model::point<double, 2, bg::cs::cartesian>;
  using Box = bg::model::box<Point>;
  using Entry = std::pair<Box, std::size_t>;

  params.validate();
  // Padding one side by the whole search padding suffices: a partner meeting the conditions with this
  // segment as M lies within it of this segment's box, and with the partner as M, this segment lies
  // within it of the partner's box (searchPadding() bounds both).
  const double pad = params.searchPadding();
  std::vector<Entry> entries;
  entries.reserve(map.size());
  for (std::size_t j = 0; j < map.size(); ++j)
  {
    const Segment2& m = map[j];
    if (!m.start.allFinite() || !m.end.allFinite())
      throw std::invalid_argument("redundant pairs: map segment " + std::to_string(j) +
                                  " has non-finite coordinates");
    entries.emplace_back(Box(Point(std::min(m.start.x(), m.end.x()), std::min(m.start.y(), m.end.y())),
                             Point(std::max(m.start.x(), m.end.x()), std::max(m.start.y(), m.end.y()))),
                         j);
  }
  const bgi::rtree<Entry, bgi::quadratic<16>> tree(entries.begin(), entries.end());

  RedundancyResult r;
  std::vector<Entry> hits;
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    const Box& b = entries[i].first;
    const Box padded(Point(b.min_corner().get<0>() - pad, b.min_corner().get<1>() - pad),
                     Point(b.max_corner().get<0>() + pad, b.max_corner().get<1>() + pad));
    hits.clear();
    tree.query(bgi::intersects(padded), std::back_inserter(hits));
    std::sort(hits.begin(), hits.end(), [](const Entry& x, const Entry& y) { return x.second < y.second; });
    for (const Entry& e : hits)
    {
      const std::size_t j = e.second;
      if (j <= i || !line_map_merging::meetEachOther(map[i], map[j], params)) continue;
      ++r.pairs;
      r.overlap_length += pairOverlap(map[i], map[j]);
      r.pair_indices.emplace_back(i, j);
    }
  }
  return r;
}

}  // namespace line_map_eval
