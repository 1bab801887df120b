#include "line_map_eval/metrics/segment_tree.hpp"

#include <algorithm>
#include <stdexcept>

namespace line_map_eval
{
SegmentBox segmentBox(const linemap::Segment2& s, double pad)
{
  return SegmentBox(
      SegmentPoint(std::min(s.start.x(), s.end.x()) - pad, std::min(s.start.y(), s.end.y()) - pad),
      SegmentPoint(std::max(s.start.x(), s.end.x()) + pad, std::max(s.start.y(), s.end.y()) + pad));
}

std::vector<SegmentEntry> segmentBoxes(const std::vector<linemap::Segment2>& map, double pad,
                                       const std::string& what)
{
  std::vector<SegmentEntry> entries;
  entries.reserve(map.size());
  for (std::size_t j = 0; j < map.size(); ++j)
  {
    const linemap::Segment2& m = map[j];
    if (!m.start.allFinite() || !m.end.allFinite())
      throw std::invalid_argument(what + ": map segment " + std::to_string(j) +
                                  " has non-finite coordinates");
    entries.emplace_back(segmentBox(m, pad), j);
  }
  return entries;
}

SegmentTree segmentTree(const std::vector<linemap::Segment2>& map, double pad, const std::string& what)
{
  const std::vector<SegmentEntry> entries = segmentBoxes(map, pad, what);
  return SegmentTree(entries.begin(), entries.end());
}

}  // namespace line_map_eval
