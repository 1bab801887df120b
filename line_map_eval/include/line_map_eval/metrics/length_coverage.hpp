// Length coverage of a line map (ROS-free): the share of the originals' length the map still
// represents, where an original could have been fused into it.
#pragma once

#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct LengthCoverage
{
  double total = 0.0;    ///< [m] total length of the originals
  double covered = 0.0;  ///< [m] length of their represented parts
  /// covered / total in [0, 1]; 0 without originals.
  double fraction() const { return total > 0.0 ? covered / total : 0.0; }
};

/// The share of the originals' length the map still represents. A point p of an original O is
/// represented when some map segment M has a directed heading within `max_angle` of O's
/// (line_map_merging::headingDeviation), p's perpendicular foot on M's line falls within M, and p
/// lies within `max_distance` of M's line: per original, the union over such M of these intervals
/// (each an interval of O, exactly computed), so overlapping map segments count the length once.
/// With the fusion thresholds (theta_max, d_max) an original counts where it could have been fused
/// into the map. Zero-length originals add nothing. Candidates come from an R-tree of the map
/// segments' boxes padded by max_distance. Throws std::invalid_argument naming the segment for
/// non-finite coordinates or negative thresholds.
LengthCoverage computeLengthCoverage(const std::vector<linemap::Segment2>& originals,
                                     const std::vector<linemap::Segment2>& map, double max_distance,
                                     double max_angle);

}  // namespace line_map_eval
