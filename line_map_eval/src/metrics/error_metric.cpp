#include "line_map_eval/metrics/error_metric.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "line_map_eval/metrics/segment_tree.hpp"

namespace line_map_eval
{
using linemap::Segment2;

ErrorMetricResult computeErrorMetric(const std::vector<Segment2>& originals,
                                     const std::vector<int>& final_index, const std::vector<Segment2>& map)
{
  if (originals.size() != final_index.size())
    throw std::invalid_argument("error metric: " + std::to_string(originals.size()) +
                                " original segments but " + std::to_string(final_index.size()) +
                                " final indices");
  ErrorMetricResult r;
  double sum = 0.0;
  for (std::size_t i = 0; i < originals.size(); ++i)
  {
    const int f = final_index[i];
    if (f < -1 || f >= static_cast<int>(map.size()))
      throw std::invalid_argument("error metric: original segment " + std::to_string(i) +
                                  " has final index " + std::to_string(f) + ", outside [-1, " +
                                  std::to_string(map.size()) + ")");
    if (f < 0)
    {
      ++r.unassigned;
      continue;
    }
    const Segment2& m = map[static_cast<std::size_t>(f)];
    const double d = linemap::distanceToLine(originals[i].midpoint(), m.start, m.end);
    if (!std::isfinite(d))
      throw std::invalid_argument("error metric: original segment " + std::to_string(i) + " or map segment " +
                                  std::to_string(f) + " has non-finite coordinates");
    sum += d;
    r.max_error = std::max(r.max_error, d);
    ++r.assigned;
  }
  if (r.assigned > 0) r.mean_error = sum / static_cast<double>(r.assigned);
  return r;
}

std::vector<int> assignToMapSegments(const std::vector<Segment2>& originals, const std::vector<Segment2>& map,
                                     const line_map_merging::FusionParams& params)
{
  params.validate();
  const SegmentTree tree = segmentTree(map, params.searchPadding(), "assignToMapSegments");

  std::vector<int> out(originals.size(), -1);
  std::vector<SegmentEntry> hits;
  for (std::size_t i = 0; i < originals.size(); ++i)
  {
    const Segment2& s = originals[i];
    if (!s.start.allFinite() || !s.end.allFinite())
      throw std::invalid_argument("assignToMapSegments: original segment " + std::to_string(i) +
                                  " has non-finite coordinates");
    hits.clear();
    tree.query(boost::geometry::index::intersects(segmentBox(s)), std::back_inserter(hits));
    double best = std::numeric_limits<double>::infinity();
    for (const SegmentEntry& e : hits)
    {
      const Segment2& m = map[e.second];
      const int j = static_cast<int>(e.second);
      if (!line_map_merging::meetsFusionConditions(m, s, params)) continue;
      const double d = linemap::distanceToLine(s.midpoint(), m.start, m.end);
      // Ties (collinear pieces of one wall) go to the lower index, so the result is deterministic.
      if (d < best || (d == best && j < out[i]))
      {
        best = d;
        out[i] = j;
      }
    }
  }
  return out;
}

}  // namespace line_map_eval
