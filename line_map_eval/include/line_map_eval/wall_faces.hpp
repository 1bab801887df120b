// The surfaces a laser can see in a world of walls with thickness (ROS-free): each wall is a
// solid rectangle around its centre line (or, at thickness 0, a line seen from both sides), and
// its faces are the straight pieces of the boundary of the union of all solids.
#pragma once

#include <cstddef>
#include <vector>

#include "line_extraction/geometry.hpp"

namespace line_map_eval
{
/// One wall of a world: its centre line and how thick it is.
struct Wall
{
  linemap::Segment2 segment;  ///< centre line
  double thickness = 0.0;     ///< [m]; 0: an infinitely thin wall, seen from both sides
};

/// A true line: a straight piece of wall surface, directed so that free space (where a laser can
/// be) lies on its LEFT, i.e. its outward normal is its direction turned by +90 degrees. This is
/// the orientation convention of every segment in the project.
struct WallFace
{
  linemap::Segment2 segment;
  std::size_t wall = 0;  ///< the lowest index of the walls whose surface it is part of
};

/// The faces of `walls`. A wall of thickness t > 0 is the rectangle of width t centred on its
/// line; at an end that touches another thick wall (an endpoint within 1e-6 m of that wall's
/// centre line: corners, T-junctions, collinear continuations) it extends by half that wall's
/// thickness, so walls meeting at a corner form a solid corner; a free end (a door jamb) stays
/// flush with the endpoint and shows an end cap. A thin wall (t = 0) gives two faces, one per
/// direction. Face pieces strictly inside another solid are removed, and collinear faces of one
/// direction that touch or overlap are joined, so for axis-aligned and generic layouts each face
/// is a maximal straight piece of the union's boundary. Order: by wall, then left side, end
/// cap, right side, start cap (the order of a clockwise walk); a joined face takes the place of
/// its first piece. Throws std::invalid_argument
/// naming the wall for a zero-length wall or a negative or non-finite thickness.
std::vector<WallFace> wallFaces(const std::vector<Wall>& walls);

/// Just the segments of `faces`.
std::vector<linemap::Segment2> faceSegments(const std::vector<WallFace>& faces);

}  // namespace line_map_eval
