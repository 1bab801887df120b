// Error metric e of a line map (ROS-free): how far the original (scan) segments lie from
// the map segment each was merged into.
#pragma once

#include <cstddef>
#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct ErrorMetricResult
{
  double mean_error = 0.0;     ///< e [m]: mean over the assigned originals; 0 when none is assigned
  double max_error = 0.0;      ///< [m]
  std::size_t assigned = 0;    ///< originals with a final segment
  std::size_t unassigned = 0;  ///< originals with index -1 (left out of the mean)
};

/// e = mean over originals i with final_index[i] >= 0 of the distance from the midpoint
/// (barycentre) of originals[i] to the infinite line of map[final_index[i]]. All in world
/// coordinates. Throws std::invalid_argument when the sizes differ or an index is outside
/// [-1, map.size()), naming the original.
ErrorMetricResult computeErrorMetric(const std::vector<linemap::Segment2>& originals,
                                     const std::vector<int>& final_index,
                                     const std::vector<linemap::Segment2>& map);

/// Provenance for mergers that do not keep it: for each original, the map segment that meets
/// the fusion conditions of line_map_merging (line_map_merging::meetsFusionConditions with the
/// map segment as M and the original as S) and whose line is nearest to the original's
/// midpoint; -1 when none meets them. Candidates come from an R-tree of the map segments'
/// boxes padded by FusionParams::searchPadding().
std::vector<int> assignToMapSegments(const std::vector<linemap::Segment2>& originals,
                                     const std::vector<linemap::Segment2>& map,
                                     const line_map_merging::FusionParams& params);

}  // namespace line_map_eval
