// Point coverage of a line map (ROS-free): the share of the observed scan points the map still
// represents, so that a map cannot score quality by leaving walls out.
#pragma once

#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct PointCoverage
{
  std::size_t points = 0;              ///< scan points given
  std::size_t covered = 0;             ///< of which within the radius of a map segment
  std::vector<std::size_t> uncovered;  ///< indices of the others, ascending (for figures)
  /// covered / points in [0, 1]; 0 without points.
  double fraction() const
  {
    return points ? static_cast<double>(covered) / static_cast<double>(points) : 0.0;
  }
};

/// A point is covered when its distance to the nearest map segment (the closed segment, not its
/// line) is at most `radius`. Candidates come from an R-tree of the segments' boxes padded by the
/// radius. Throws std::invalid_argument naming the segment or point for non-finite coordinates or
/// a negative radius.
PointCoverage computePointCoverage(const std::vector<linemap::Vec2>& points,
                                   const std::vector<linemap::Segment2>& map, double radius);

}  // namespace line_map_eval
