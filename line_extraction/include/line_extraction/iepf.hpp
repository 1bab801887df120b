// Iterative end-point fit: the splitting step, shared by the iepf and smsm extractors.
#pragma once

#include <vector>

#include "line_extraction/types.hpp"

namespace line_extraction
{
class IepfSplitter
{
 public:
  /// Splits the points [range.begin, range.end) at gaps wider than `max_gap` and,
  /// recursively, at the point farthest from the chord between a piece's first and
  /// last point while that distance exceeds `threshold`. Appends the pieces in scan
  /// order; the two pieces of a chord split share the split point (resolve with
  /// resolveOverlaps).
  void split(const PreparedScan& scan, PointRange range, double threshold, double max_gap,
             std::vector<PointRange>& pieces);

 private:
  void splitGapFree(const PreparedScan& scan, PointRange range, double threshold,
                    std::vector<PointRange>& pieces);
  std::vector<PointRange> stack_;
};

}  // namespace line_extraction
