// Size statistics of a line map (ROS-free): the columns of the paper's Table III.
#pragma once

#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct MapStatistics
{
  std::size_t segment_count = 0;
  std::size_t original_count = 0;
  double shortest_length = 0.0;  ///< [m]; 0 for an empty map
  double longest_length = 0.0;   ///< [m]
  double mean_length = 0.0;      ///< [m]
  double total_length = 0.0;     ///< [m]
  /// segment_count / original_count (lower is more compact); 0 when there are no originals.
  double reduction_rate = 0.0;
};

/// Statistics of `map`, given how many original (scan) segments it was built from.
MapStatistics computeMapStatistics(const std::vector<linemap::Segment2>& map, std::size_t original_count);

}  // namespace line_map_eval
