// The surfaces a laser can see in a world of walls with thickness (ROS-free): each wall is a
// solid rectangle around its centre line (or, at thickness 0, a line seen from both sides), and
// its faces are the straight pieces of the boundary of the union of all solids.
#pragma once

#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
/// One wall of a world: its centre line and how thick it is.
struct Wall
{
  linemap::Segment2 segment;  ///< centre line
  double thickness = 0.0;     ///< [m]; 0: an infinitely thin wall, seen from both sides
  /// A piece of a curved wall (arcPieces()): the index of its arc, -1 for a straight wall. Two
  /// pieces of one arc where one ends exactly (==) where the other starts meet in a mitred joint.
  int arc = -1;
};

/// A curved wall: the circle arc of `radius` around `centre` from `start` to `end` (angles in
/// radians, counter-clockwise when end > start), as a chain of chords.
struct Arc
{
  linemap::Vec2 centre = linemap::Vec2::Zero();
  double radius = 1.0;  ///< [m]
  double start = 0.0;   ///< [rad]
  double end = 0.0;     ///< [rad]; |end - start| in (0, 2 pi]
};

/// The chords of `arc`: the fewest equal pieces whose sagitta (largest distance of the arc from
/// its chord, radius (1 - cos(step / 2))) is at most `max_sagitta`, and at least one piece per
/// 45 degrees of sweep, so a short arc of small radius still turns; the vertices lie on the circle,
/// each computed once, so consecutive pieces share them exactly (a full circle closes on its first
/// vertex). Each piece gets `thickness` and `arc` = `index`. Throws std::invalid_argument for a
/// radius or sagitta <= 0, a zero sweep or one above 360 degrees.
std::vector<Wall> arcPieces(const Arc& arc, double thickness, double max_sagitta, int index);

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
/// direction. Consecutive pieces of one arc (Wall::arc) meet in a mitred joint instead: both solids
/// end on the bisector of the two pieces, with no end cap, so the arc's two faces are polylines
/// through the joints (a concave joint has no notch and a convex one no spike). Face pieces strictly inside
/// another solid are removed, and collinear faces of one direction that touch or overlap are joined, so for
/// axis-aligned and generic layouts each face is a maximal straight piece of the union's boundary. Order: by
/// wall, then left side, end cap, right side, start cap (the order of a clockwise walk); a joined face takes
/// the place of its first piece. Throws std::invalid_argument naming the wall for a zero-length wall or a
/// negative or non-finite thickness.
std::vector<WallFace> wallFaces(const std::vector<Wall>& walls);

/// The faces of each curved surface: per arc of `walls` (Wall::arc), the faces along its left
/// side and those along its right side (end caps excluded), each list in order along the arc.
/// `faces` are wallFaces(walls).
std::vector<std::vector<std::size_t>> curveFaces(const std::vector<Wall>& walls,
                                                 const std::vector<WallFace>& faces);

/// Just the segments of `faces`.
std::vector<linemap::Segment2> faceSegments(const std::vector<WallFace>& faces);

}  // namespace line_map_eval
