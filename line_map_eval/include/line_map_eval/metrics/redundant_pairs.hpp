// Residual redundancy of a line map (ROS-free): pairs of map segments that a merger should have
// fused, because they meet the fusion conditions with each other.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct RedundancyResult
{
  std::size_t pairs = 0;        ///< pairs (i < j) with line_map_merging::meetEachOther
  double overlap_length = 0.0;  ///< [m] sum over the pairs of their overlap along the line (>= 0 each)
  std::vector<std::pair<std::size_t, std::size_t>> pair_indices;  ///< (i, j), i < j, sorted
};

/// Overlap of a pair along the line: the projection of the shorter segment onto the longer one's
/// line (line_map_merging::horizontalOverlap with the longer as M), clamped at 0 (a pair that fuses
/// across a gap overlaps by 0). The longer segment's line is the better estimate of the wall.
double pairOverlap(const linemap::Segment2& a, const linemap::Segment2& b);

/// Every pair of map segments that meets the fusion conditions with either as the map segment.
/// Candidates come from an R-tree of the segments' boxes padded by FusionParams::searchPadding().
/// Throws std::invalid_argument naming the segment for non-finite coordinates,
/// linemap::ParameterError for bad fusion parameters.
RedundancyResult findRedundantPairs(const std::vector<linemap::Segment2>& map,
                                    const line_map_merging::FusionParams& params);

}  // namespace line_map_eval
