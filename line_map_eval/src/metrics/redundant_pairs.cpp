#include "line_map_eval/metrics/redundant_pairs.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <string>

#include "line_map_eval/metrics/segment_tree.hpp"

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
  params.validate();
  // Padding one side by the whole search padding suffices: a partner meeting the conditions with this
  // segment as M lies within it of this segment's box, and with the partner as M, this segment lies
  // within it of the partner's box (searchPadding() bounds both).
  const double pad = params.searchPadding();
  const SegmentTree tree = segmentTree(map, 0.0, "redundant pairs");

  RedundancyResult r;
  std::vector<SegmentEntry> hits;
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    hits.clear();
    tree.query(boost::geometry::index::intersects(segmentBox(map[i], pad)), std::back_inserter(hits));
    std::sort(hits.begin(), hits.end(),
              [](const SegmentEntry& x, const SegmentEntry& y) { return x.second < y.second; });
    for (const SegmentEntry& e : hits)
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
