#include "line_map_eval/metrics/map_statistics.hpp"

#include <algorithm>
#include <limits>

namespace line_map_eval
{
MapStatistics computeMapStatistics(const std::vector<linemap::Segment2>& map, std::size_t original_count)
{
  MapStatistics s;
  s.segment_count = map.size();
  s.original_count = original_count;
  if (original_count > 0)
    s.reduction_rate = static_cast<double>(map.size()) / static_cast<double>(original_count);
  if (map.empty()) return s;
  s.shortest_length = std::numeric_limits<double>::infinity();
  for (const linemap::Segment2& seg : map)
  {
    const double l = seg.length();
    s.shortest_length = std::min(s.shortest_length, l);
    s.longest_length = std::max(s.longest_length, l);
    s.total_length += l;
  }
  s.mean_length = s.total_length / static_cast<double>(map.size());
  return s;
}

}  // namespace line_map_eval
