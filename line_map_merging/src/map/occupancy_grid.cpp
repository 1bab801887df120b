// Occupancy grid from a line map and its provenance (see occupancy_grid.hpp).
#include "line_map_merging/map/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
bool finite(const Segment2& s)
{
  return s.start.allFinite() && s.end.allFinite();
}

struct Bounds
{
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  void add(const Vec2& p)
  {
    min_x = std::min(min_x, p.x());
    min_y = std::min(min_y, p.y());
    max_x = std::max(max_x, p.x());
    max_y = std::max(max_y, p.y());
  }
  bool empty() const { return min_x > max_x; }
};

void setCell(OccupancyGrid& grid, int column, int row, std::int8_t value)
{
  if (grid.contains(column, row)) grid.cells[static_cast<std::size_t>(row) * grid.width + column] = value;
}

/// Marks free every cell whose centre lies in the triangle, row by row: the triangle's extent along
/// the row's centre line, then the columns whose centres fall within it.
void fillTriangle(OccupancyGrid& grid, const Vec2& a, const Vec2& b, const Vec2& c)
{
  const double res = grid.resolution;
  const double low = std::min({a.y(), b.y(), c.y()}), high = std::max({a.y(), b.y(), c.y()});
  const int first_row = std::max(0, static_cast<int>(std::ceil((low - grid.origin.y()) / res - 0.5)));
  const int last_row =
      std::min(grid.height - 1, static_cast<int>(std::floor((high - grid.origin.y()) / res - 0.5)));
  const Vec2* corners[3] = {&a, &b, &c};
  for (int row = first_row; row <= last_row; ++row)
  {
    const double y = grid.origin.y() + (row + 0.5) * res;
    double left = std::numeric_limits<double>::infinity(), right = -left;
    for (int i = 0; i < 3; ++i)
    {
      const Vec2& p = *corners[i];
      const Vec2& q = *corners[(i + 1) % 3];
      if (y < std::min(p.y(), q.y()) || y > std::max(p.y(), q.y())) continue;
      // A horizontal edge on the centre line contributes both its ends.
      const double x = p.y() == q.y() ? p.x() : p.x() + (y - p.y()) / (q.y() - p.y()) * (q.x() - p.x());
      const double other = p.y() == q.y() ? q.x() : x;
      left = std::min({left, x, other});
      right = std::max({right, x, other});
    }
    if (left > right) continue;
    const int first = std::max(0, static_cast<int>(std::ceil((left - grid.origin.x()) / res - 0.5)));
    const int last =
        std::min(grid.width - 1, static_cast<int>(std::floor((right - grid.origin.x()) / res - 0.5)));
    for (int column = first; column <= last; ++column) setCell(grid, column, row, OccupancyGrid::kFree);
  }
}

/// Marks occupied every cell the segment passes through (Amanatides & Woo's grid traversal), so a
/// wall is a 4-connected line of cells that a planner cannot slip through diagonally.
void drawWall(OccupancyGrid& grid, const Segment2& wall)
{
  const Vec2 a = (wall.start - grid.origin) / grid.resolution;  // in cells
  const Vec2 b = (wall.end - grid.origin) / grid.resolution;
  int column, row, last_column, last_row;
  grid.cellOf(wall.start, column, row);
  grid.cellOf(wall.end, last_column, last_row);
  const Vec2 d = b - a;
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  // Parameter t in [0, 1] along the segment at which the next column / row boundary is crossed.
  double next_x = d.x() == 0 ? inf : (step_x > 0 ? column + 1 - a.x() : a.x() - column) / std::abs(d.x());
  double next_y = d.y() == 0 ? inf : (step_y > 0 ? row + 1 - a.y() : a.y() - row) / std::abs(d.y());
  const double delta_x = d.x() == 0 ? inf : 1.0 / std::abs(d.x());
  const double delta_y = d.y() == 0 ? inf : 1.0 / std::abs(d.y());
  // Exactly one step per column and row between the end cells, whatever rounding does to t.
  int steps = std::abs(last_column - column) + std::abs(last_row - row);
  setCell(grid, column, row, OccupancyGrid::kOccupied);
  while (steps-- > 0)
  {
    const bool column_left = column != last_column, row_left = row != last_row;
    if (column_left && (!row_left || next_x < next_y))
    {
      column += step_x;
      next_x += delta_x;
    }
    else
    {
      row += step_y;
      next_y += delta_y;
    }
    setCell(grid, column, row, OccupancyGrid::kOccupied);
  }
}
}  // namespace

void OccupancyGridParams::validate() const
{
  if (!(resolution > 0.0) || !std::isfinite(resolution))
    throw std::invalid_argument("occupancy grid: 'resolution' must be a positive number, got " +
                                std::to_string(resolution));
  if (!(margin >= 0.0) || !std::isfinite(margin))
    throw std::invalid_argument("occupancy grid: 'margin' must be >= 0, got " + std::to_string(margin));
  if (max_cells == 0) throw std::invalid_argument("occupancy grid: 'max_cells' must be positive");
}

void OccupancyGrid::cellOf(const Vec2& p, int& column, int& row) const
{
  // Clamped before the cast: a far point must not overflow int.
  const double limit = static_cast<double>(std::numeric_limits<int>::max() / 2);
  column = static_cast<int>(std::clamp(std::floor((p.x() - origin.x()) / resolution), -limit, limit));
  row = static_cast<int>(std::clamp(std::floor((p.y() - origin.y()) / resolution), -limit, limit));
}

std::int8_t OccupancyGrid::valueAt(const Vec2& p) const
{
  int column, row;
  cellOf(p, column, row);
  return contains(column, row) ? at(column, row) : kUnknown;
}

Vec2 OccupancyGrid::cellCentre(int column, int row) const
{
  return origin + resolution * Vec2(column + 0.5, row + 0.5);
}

std::size_t OccupancyGrid::count(std::int8_t value) const
{
  return static_cast<std::size_t>(std::count(cells.begin(), cells.end(), value));
}

std::vector<Sighting> sightingsOf(const std::vector<KeyframeInfo>& keyframes, const std::vector<Leaf>& leaves)
{
  std::unordered_map<std::uint64_t, const KeyframeInfo*> by_index;
  for (const KeyframeInfo& k : keyframes) by_index.emplace(k.index, &k);
  std::vector<Sighting> out;
  out.reserve(leaves.size());
  for (const Leaf& leaf : leaves)
  {
    auto it = by_index.find(leaf.keyframe);
    if (it == by_index.end())
      throw std::invalid_argument("occupancy grid: an original names keyframe " +
                                  std::to_string(leaf.keyframe) + ", which is not among the keyframes");
    const linemap::Pose2& laser = it->second->pose;
    out.push_back({laser.translation(), leaf.segment.transformed(laser)});
  }
  return out;
}

OccupancyGrid buildOccupancyGrid(const std::vector<Segment2>& walls, const std::vector<Sighting>& sightings,
                                 const OccupancyGridParams& params)
{
  params.validate();
  Bounds bounds;
  for (const Segment2& w : walls)
    if (finite(w))
    {
      bounds.add(w.start);
      bounds.add(w.end);
    }
  for (const Sighting& s : sightings)
    if (finite(s.seen) && s.viewpoint.allFinite())
    {
      bounds.add(s.viewpoint);
      bounds.add(s.seen.start);
      bounds.add(s.seen.end);
    }
  OccupancyGrid grid;
  grid.resolution = params.resolution;
  if (bounds.empty()) return grid;

  const double res = params.resolution;
  const double min_x = std::floor((bounds.min_x - params.margin) / res);
  const double min_y = std::floor((bounds.min_y - params.margin) / res);
  // Up to and including the cell holding the far corner (floor + 1: it may lie on a cell boundary).
  const double columns = std::floor((bounds.max_x + params.margin) / res) + 1.0 - min_x;
  const double rows = std::floor((bounds.max_y + params.margin) / res) + 1.0 - min_y;
  const double cells = columns * rows;
  if (cells > static_cast<double>(params.max_cells))
    throw std::invalid_argument("occupancy grid: " + std::to_string(bounds.max_x - bounds.min_x) + " m x " +
                                std::to_string(bounds.max_y - bounds.min_y) + " m at " + std::to_string(res) +
                                " m would need " + std::to_string(cells) +
                                " cells, more than max_cells = " + std::to_string(params.max_cells));
  // Rounded to the nanometre, so the YAML reads -2.3 rather than -2.3000000000000003.
  const auto nanometres = [](double v) { return std::round(v * 1e9) / 1e9; };
  grid.origin = Vec2(nanometres(min_x * res), nanometres(min_y * res));
  grid.width = static_cast<int>(columns);
  grid.height = static_cast<int>(rows);
  grid.cells.assign(static_cast<std::size_t>(grid.width) * grid.height, OccupancyGrid::kUnknown);

  for (const Sighting& s : sightings)
    if (finite(s.seen) && s.viewpoint.allFinite()) fillTriangle(grid, s.viewpoint, s.seen.start, s.seen.end);
  // After the free space: a wall cell stays a wall however often it was seen through.
  for (const Segment2& w : walls)
    if (finite(w)) drawWall(grid, w);
  return grid;
}

OccupancyGrid buildOccupancyGrid(const CaeRlsm& map, const OccupancyGridParams& params)
{
  std::vector<Segment2> walls;
  for (const MapSegment& m : map.map()) walls.push_back(m.segment);
  // Ids are below nextId(); leaves() of an id no segment holds (merged away) is empty.
  std::vector<Leaf> leaves;
  leaves.reserve(map.leafCount());
  for (std::uint64_t id = 0; id < map.nextId(); ++id)
  {
    std::vector<Leaf> mine = map.leaves(id);
    leaves.insert(leaves.end(), mine.begin(), mine.end());
  }
  return buildOccupancyGrid(walls, sightingsOf(map.keyframes(), leaves), params);
}

}  // namespace line_map_merging
