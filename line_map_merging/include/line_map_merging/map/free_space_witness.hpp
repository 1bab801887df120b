// What one extracted segment shows of the space around it (ROS-free): every beam that hit the segment crossed
// the triangle between the laser and the segment, so that triangle, eroded by a margin on its three sides, is
// free space; the band along the segment (within the margin) was seen occupied. CAE-RLSM's see-through
// retirement (a later session's scan seeing through an earlier wall) and the placement of a fleet's robots
// (a placement under which a robot's scans see through the fleet's walls is wrong) judge segments by it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// A half-plane h(x) = n.x - c >= 0.
struct HalfPlane
{
  linemap::Vec2 n;
  double c;
};

/// The part [lo, hi] (fractions along `s`) inside every half-plane (Liang-Barsky clipping); lo >= hi: none.
std::pair<double, double> clipToHalfPlanes(const linemap::Segment2& s, const HalfPlane* planes,
                                           std::size_t count);

/// The bins of `s` (`bins` <= 32, by position along it) whose centres lie inside every half-plane, as a bit
/// mask.
std::uint32_t insideBins(const linemap::Segment2& s, const HalfPlane* planes, std::size_t count,
                         std::size_t bins);

struct FreeSpaceWitness
{
  HalfPlane free[3];          ///< inside both sides' rays and before the segment, each by the margin
  HalfPlane band[4];          ///< within the rays, and within the margin of the segment's line
  std::array<double, 4> box;  ///< min x, min y, max x, max y of the triangle
};

/// The witness of `segment` seen from `laser` (both in one frame); false when it shows nothing (a segment
/// through the laser, or too short to leave a free triangle after the erosion).
bool makeWitness(const linemap::Vec2& laser, linemap::Segment2 segment, double margin, FreeSpaceWitness& w);

}  // namespace line_map_merging
