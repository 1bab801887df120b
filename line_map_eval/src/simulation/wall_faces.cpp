// Wall faces: the boundary of the union of the walls' solids, as directed straight pieces.
#include "line_map_eval/simulation/wall_faces.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kTouch = 1e-6;   // [m] an endpoint this close to a centre line joins that wall
constexpr double kInside = 1e-9;  // [m] depth below which a point counts as on a solid's boundary
constexpr double kLength =
    1e-6;  // [m] shorter face pieces (slivers kInside long where a face enters a solid) are dropped

using linemap::cross;

// A wall's solid: a rectangle, or a trapezoid where an arc's chords meet in a mitre; convex, corners in
// clockwise order (the solid is on each edge's right).
using Rectangle = std::array<Vec2, 4>;

/// Parameter interval (s0, s1) of p + s d, s in [0, 1], lying inside `r` (empty: s0 >= s1). Only a
/// face reaching deeper than kInside is cut (one on the boundary is not), and it is cut where it
/// crosses the boundary, so the pieces end exactly on the other solid's faces.
std::pair<double, double> insideInterval(const Vec2& p, const Vec2& d, const Rectangle& r)
{
  double s0 = 0.0, s1 = 1.0, deep0 = 0.0, deep1 = 1.0;
  for (std::size_t k = 0; k < 4; ++k)
  {
    const Vec2 e = r[(k + 1) % 4] - r[k];
    const double len = e.norm();
    // Depth inside across this edge along the face: f0 + s f1 (the solid is on the edge's right).
    const double f0 = -cross(e, p - r[k]) / len, f1 = -cross(e, d) / len;
    if (std::abs(f1) < 1e-15)
    {
      if (f0 <= kInside) return {1.0, 0.0};
      continue;
    }
    if (f1 > 0.0)
    {
      s0 = std::max(s0, -f0 / f1);
      deep0 = std::max(deep0, (kInside - f0) / f1);
    }
    else
    {
      s1 = std::min(s1, -f0 / f1);
      deep1 = std::min(deep1, (kInside - f0) / f1);
    }
  }
  if (deep0 >= deep1) return {1.0, 0.0};
  return {s0, s1};
}

constexpr std::size_t kNone = static_cast<std::size_t>(-1);

Vec2 leftNormal(const Segment2& s)
{
  const Vec2 u = (s.end - s.start) / s.length();
  return {-u.y(), u.x()};
}

/// The piece of the same arc that ends where wall i starts (next = false) or starts where it ends
/// (next = true), or kNone.
std::size_t arcNeighbour(const std::vector<Wall>& walls, std::size_t i, bool next)
{
  if (walls[i].arc < 0) return kNone;
  for (std::size_t j = 0; j < walls.size(); ++j)
    if (j != i && walls[j].arc == walls[i].arc &&
        (next ? walls[j].segment.start == walls[i].segment.end
              : walls[j].segment.end == walls[i].segment.start))
      return j;
  return kNone;
}

/// Offset from the joint of two consecutive pieces to the corner of their solids on the left: along
/// the bisector of their normals, to where both left sides meet. Symmetric in its computation, so
/// both pieces get the very same corners and share their end edge exactly.
Vec2 mitre(const Wall& first, const Wall& second)
{
  const Vec2 n1 = leftNormal(first.segment), n2 = leftNormal(second.segment);
  const Vec2 m = (n1 + n2).normalized();
  return (0.5 * first.thickness / (0.5 * (m.dot(n1) + m.dot(n2)))) * m;
}

/// Whether b continues a: collinear, same direction, touching or overlapping.
bool joins(const Segment2& a, const Segment2& b)
{
  const Vec2 u = (a.end - a.start) / a.length();
  const Vec2 v = (b.end - b.start) / b.length();
  if (u.dot(v) < 1.0 - 1e-12) return false;
  if (linemap::distanceToLine(b.start, a.start, a.end) > kLength ||
      linemap::distanceToLine(b.end, a.start, a.end) > kLength)
    return false;
  const double t0 = u.dot(b.start - a.start), t1 = u.dot(b.end - a.start);
  return t1 >= -kLength && t0 <= a.length() + kLength;
}

/// a extended over b (joins(a, b)); endpoints are copied, not recomputed, so coordinates stay exact.
Segment2 joined(const Segment2& a, const Segment2& b)
{
  const Vec2 u = (a.end - a.start) / a.length();
  const double t0 = u.dot(b.start - a.start), t1 = u.dot(b.end - a.start);
  return {t0 < 0.0 ? b.start : a.start, t1 > a.length() ? b.end : a.end};
}
void checkWalls(const std::vector<Wall>& walls)
{
  for (std::size_t i = 0; i < walls.size(); ++i)
  {
    const Wall& w = walls[i];
    if (!w.segment.start.allFinite() || !w.segment.end.allFinite() || !(w.segment.length() > 1e-9))
      throw std::invalid_argument("wall faces: walls[" + std::to_string(i) +
                                  "] has zero length or no finite ends");
    if (!(w.thickness >= 0.0) || !std::isfinite(w.thickness))
      throw std::invalid_argument("wall faces: walls[" + std::to_string(i) + "] has thickness " +
                                  std::to_string(w.thickness) + " (must be finite and >= 0)");
  }
}

/// The solids of the thick walls (`solid` marks them) and the candidate faces in clockwise order
/// (outward normal on the left).
std::vector<WallFace> candidateFaces(const std::vector<Wall>& walls, std::vector<Rectangle>& solids,
                                     std::vector<bool>& solid)
{
  std::vector<WallFace> candidates;
  for (std::size_t i = 0; i < walls.size(); ++i)
  {
    const Segment2& c = walls[i].segment;
    if (walls[i].thickness == 0.0)
    {
      candidates.push_back({c, i});
      candidates.push_back({Segment2(c.end, c.start), i});
      continue;
    }
    const std::size_t before = arcNeighbour(walls, i, false), after = arcNeighbour(walls, i, true);
    double extend_start = 0.0, extend_end = 0.0;
    for (std::size_t j = 0; j < walls.size(); ++j)
    {
      if (j == i || walls[j].thickness == 0.0) continue;
      const Segment2& o = walls[j].segment;
      if (before == kNone && linemap::distanceToSegment(c.start, o.start, o.end) <= kTouch)
        extend_start = std::max(extend_start, 0.5 * walls[j].thickness);
      if (after == kNone && linemap::distanceToSegment(c.end, o.start, o.end) <= kTouch)
        extend_end = std::max(extend_end, 0.5 * walls[j].thickness);
    }
    const Vec2 u = (c.end - c.start) / c.length();
    const Vec2 a = c.start - extend_start * u, b = c.end + extend_end * u,
               h = 0.5 * walls[i].thickness * leftNormal(c);
    const Vec2 hs = before == kNone ? h : mitre(walls[before], walls[i]);
    const Vec2 he = after == kNone ? h : mitre(walls[i], walls[after]);
    solids[i] = {a + hs, b + he, b - he, a - hs};
    solid[i] = true;
    for (std::size_t k = 0; k < 4; ++k)
      if (!(k == 1 && after != kNone) && !(k == 3 && before != kNone))  // a mitred end has no cap
        candidates.push_back({Segment2(solids[i][k], solids[i][(k + 1) % 4]), i});
  }
  return candidates;
}

/// The candidates without what lies inside other solids.
std::vector<WallFace> outsideSolids(const std::vector<WallFace>& candidates,
                                    const std::vector<Rectangle>& solids, const std::vector<bool>& solid)
{
  std::vector<WallFace> faces;
  std::vector<std::pair<double, double>> removed;
  for (const WallFace& f : candidates)
  {
    const Vec2 p = f.segment.start, d = f.segment.end - f.segment.start;
    removed.clear();
    for (std::size_t j = 0; j < solids.size(); ++j)
    {
      if (!solid[j] || j == f.wall) continue;
      const auto in = insideInterval(p, d, solids[j]);
      if (in.first < in.second) removed.push_back(in);
    }
    std::sort(removed.begin(), removed.end());
    double from = 0.0;
    const double length = d.norm();
    for (std::size_t k = 0; k <= removed.size(); ++k)
    {
      const double to = k < removed.size() ? removed[k].first : 1.0;
      if ((to - from) * length > kLength)
        faces.push_back(
            {Segment2(from == 0.0 ? f.segment.start : p + from * d, to == 1.0 ? f.segment.end : p + to * d),
             f.wall});
      if (k < removed.size()) from = std::max(from, removed[k].second);
    }
  }
  return faces;
}

/// Joins collinear pieces of one direction (a wall continued by another, an end cap flush with a
/// neighbour's side) until none is left to join.
void joinCollinear(std::vector<WallFace>& faces)
{
  for (bool changed = true; changed;)
  {
    changed = false;
    for (std::size_t i = 0; i < faces.size(); ++i)
      for (std::size_t j = i + 1; j < faces.size();)
        if (joins(faces[i].segment, faces[j].segment))
        {
          faces[i].segment = joined(faces[i].segment, faces[j].segment);
          faces[i].wall = std::min(faces[i].wall, faces[j].wall);
          faces.erase(faces.begin() + static_cast<std::ptrdiff_t>(j));
          changed = true;
        }
        else
          ++j;
  }
}
}  // namespace

std::vector<WallFace> wallFaces(const std::vector<Wall>& walls)
{
  checkWalls(walls);
  std::vector<Rectangle> solids(walls.size());
  std::vector<bool> solid(walls.size(), false);
  const std::vector<WallFace> candidates = candidateFaces(walls, solids, solid);
  std::vector<WallFace> faces = outsideSolids(candidates, solids, solid);
  joinCollinear(faces);
  return faces;
}

std::vector<Wall> arcPieces(const Arc& arc, double thickness, double max_sagitta, int index)
{
  const double sweep = arc.end - arc.start;
  if (!(arc.radius > 0.0) || !std::isfinite(arc.radius))
    throw std::invalid_argument("arc: radius must be > 0, got " + std::to_string(arc.radius));
  if (!(max_sagitta > 0.0))
    throw std::invalid_argument("arc: the sagitta bound must be > 0, got " + std::to_string(max_sagitta));
  if (!(std::abs(sweep) > 1e-9) || !std::isfinite(sweep))
    throw std::invalid_argument("arc: zero sweep (start and end angles are equal)");
  if (std::abs(sweep) > 2.0 * linemap::kPi + 1e-9)
    throw std::invalid_argument("arc: the sweep exceeds 360 degrees");
  // Largest step with sagitta r (1 - cos(step / 2)) <= max_sagitta.
  const double step = 2.0 * std::acos(std::clamp(1.0 - max_sagitta / arc.radius, -1.0, 1.0));
  const double max_step = std::min(step, 0.25 * linemap::kPi);
  const auto pieces = static_cast<std::size_t>(std::ceil(std::abs(sweep) / max_step - 1e-9));
  const bool closed = std::abs(std::abs(sweep) - 2.0 * linemap::kPi) <= 1e-9;
  std::vector<Vec2> vertices;
  for (std::size_t k = 0; k <= pieces; ++k)
  {
    const double a = arc.start + sweep * static_cast<double>(k) / static_cast<double>(pieces);
    vertices.push_back(closed && k == pieces ? vertices.front()
                                             : arc.centre + arc.radius * Vec2(std::cos(a), std::sin(a)));
  }
  std::vector<Wall> out;
  for (std::size_t k = 0; k < pieces; ++k)
    out.push_back({Segment2(vertices[k], vertices[k + 1]), thickness, index});
  return out;
}

std::vector<std::vector<std::size_t>> curveFaces(const std::vector<Wall>& walls,
                                                 const std::vector<WallFace>& faces)
{
  int arcs = 0;
  for (const Wall& w : walls) arcs = std::max(arcs, w.arc + 1);
  // Per arc and side: (piece, position along it, face).
  std::vector<std::vector<std::tuple<std::size_t, double, std::size_t>>> sides(
      2 * static_cast<std::size_t>(arcs));
  for (std::size_t f = 0; f < faces.size(); ++f)
  {
    const std::size_t w = faces[f].wall;
    if (w >= walls.size() || walls[w].arc < 0) continue;
    const Segment2& c = walls[w].segment;
    const Vec2 u = (c.end - c.start) / c.length();
    const Segment2& s = faces[f].segment;
    const double along = u.dot((s.end - s.start) / s.length());
    if (std::abs(along) < 0.5) continue;  // an end cap
    sides[2 * static_cast<std::size_t>(walls[w].arc) + (along > 0.0 ? 0 : 1)].emplace_back(
        w, u.dot(s.midpoint() - c.start), f);
  }
  std::vector<std::vector<std::size_t>> out;
  for (auto& side : sides)
  {
    if (side.empty()) continue;
    std::sort(side.begin(), side.end());
    out.emplace_back();
    for (const auto& entry : side) out.back().push_back(std::get<2>(entry));
  }
  return out;
}

std::vector<Segment2> faceSegments(const std::vector<WallFace>& faces)
{
  std::vector<Segment2> out;
  out.reserve(faces.size());
  for (const WallFace& f : faces) out.push_back(f.segment);
  return out;
}

}  // namespace line_map_eval
