// Crossing map segments (ROS-free): pairs of map segments that intersect with both running on
// past the intersection, i.e. an X. A bent wall drawn as two crossing chords, or two walls drawn
// through each other, is a map defect; an L corner, a T junction and a chain meeting at a bend
// are not crossings.
#pragma once

#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct CrossingPair
{
  int a;                ///< index into the map, a < b
  int b;                ///< index into the map
  linemap::Vec2 point;  ///< the intersection point
};

/// Every pair of map segments that cross: they intersect, and each extends beyond the intersection
/// point by more than min_overhang [m] on both sides. Pairs with a < b, sorted by (a, b).
/// Candidates come from an R-tree of the segments' boxes. Parallel (and collinear) segments never
/// cross. Throws std::invalid_argument naming the segment for non-finite coordinates, and for a
/// negative or non-finite min_overhang.
std::vector<CrossingPair> findCrossingPairs(const std::vector<linemap::Segment2>& map, double min_overhang);

/// The test of findCrossingPairs for one pair (no argument checks): whether a and b cross with both
/// overhanging the intersection by more than min_overhang; if so and point is given, the
/// intersection goes there.
bool segmentsCross(const linemap::Segment2& a, const linemap::Segment2& b, double min_overhang,
                   linemap::Vec2* point = nullptr);

}  // namespace line_map_merging
