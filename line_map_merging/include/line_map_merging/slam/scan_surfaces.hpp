// The surfaces a scan samples, for the likelihood field of a map (ROS-free): consecutive points joined
// by a segment where one surface explains both, so that a wall seen at a grazing angle, whose points
// lie far apart, is a line in the field and not a row of dots. A field of dots peaks wherever a new
// scan's points fall on the old ones, i.e. at the pose the old scan was taken from; in a corridor the
// matcher then holds that pose along the axis, where the walls themselves say nothing (the reason
// PL-ICP matches points to the segments between a reference scan's points, Censi 2008).
#pragma once

#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct SurfaceParams
{
  /// Smallest incidence angle of a surface two neighbouring points are joined on (the adaptive
  /// breakpoint test of line_extraction, Borges & Aldon); 0: no point is joined.
  double lambda = 10.0 * linemap::kPi / 180.0;  ///< [rad]
  double range_sigma = 0.01;                    ///< [m] range noise
};

/// Segments between consecutive `points` (valid returns in beam order, in the frame of a sensor at the
/// origin) on one surface. Two neighbours are joined when the breakpoint test passes and a neighbour on
/// either side continues them along their line (within 3 range_sigma, no beam between them), or when they
/// continue a joined pair that way: a wall at grazing incidence.
std::vector<linemap::Segment2> scanSurfaces(const std::vector<linemap::Vec2>& points,
                                            const SurfaceParams& params);

}  // namespace line_map_merging
