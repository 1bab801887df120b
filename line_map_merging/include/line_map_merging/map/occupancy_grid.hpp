// Occupancy grid from a line map with provenance (ROS-free): walls are the cells the map segments
// pass through; free space is what the original segments prove empty, since each was seen from its
// keyframe's laser pose, so nothing stood in the triangle between that pose and the segment; every
// other cell is unknown. Walls win over free. The map_server PGM + YAML writer is in
// map_server_file.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
class CaeRlsm;

/// An original segment and the point it was seen from, both in the map frame.
struct Sighting
{
  linemap::Vec2 viewpoint = linemap::Vec2::Zero();
  linemap::Segment2 seen;
};

struct OccupancyGridParams
{
  double resolution = 0.05;  ///< [m] cell side
  double margin = 0.25;      ///< [m] unknown border around everything drawn
  /// Refuses grids larger than this (a corrupt coordinate would otherwise allocate without bound).
  std::size_t max_cells = 200'000'000;

  /// Throws std::invalid_argument naming the field for a non-positive or non-finite value.
  void validate() const;
};

/// Cell values as nav_msgs/OccupancyGrid has them; rows run from the lowest y up (row 0 at origin).
struct OccupancyGrid
{
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;

  double resolution = 0.05;
  /// Map-frame corner of cell (0, 0), the one with the lowest x and y; a multiple of the resolution,
  /// so grids of one map at one resolution line up.
  linemap::Vec2 origin = linemap::Vec2::Zero();
  int width = 0;                   ///< columns (x)
  int height = 0;                  ///< rows (y)
  std::vector<std::int8_t> cells;  ///< row-major, width * height

  bool contains(int column, int row) const
  {
    return column >= 0 && row >= 0 && column < width && row < height;
  }
  std::int8_t at(int column, int row) const { return cells[static_cast<std::size_t>(row) * width + column]; }
  /// The value of the cell holding `p`, kUnknown outside the grid.
  std::int8_t valueAt(const linemap::Vec2& p) const;
  /// Column and row of the cell holding `p` (possibly outside the grid).
  void cellOf(const linemap::Vec2& p, int& column, int& row) const;
  linemap::Vec2 cellCentre(int column, int row) const;
  std::size_t count(std::int8_t value) const;
};

/// World-frame sightings of the originals: each leaf placed by its keyframe's laser pose. Throws
/// std::invalid_argument for a leaf naming no keyframe.
std::vector<Sighting> sightingsOf(const std::vector<KeyframeInfo>& keyframes,
                                  const std::vector<Leaf>& leaves);

/// The grid covering every wall and sighting (plus the margin). Non-finite input is skipped.
/// Throws std::invalid_argument for bad parameters or a grid above max_cells.
OccupancyGrid buildOccupancyGrid(const std::vector<linemap::Segment2>& walls,
                                 const std::vector<Sighting>& sightings,
                                 const OccupancyGridParams& params = {});

/// The grid of a CAE-RLSM map: walls are the segments map() shows; free space comes from every
/// original, those under segments the single-view rule withholds included (a passer-by seen once is
/// no wall, but the space in front of it was still seen empty).
OccupancyGrid buildOccupancyGrid(const CaeRlsm& map, const OccupancyGridParams& params = {});

}  // namespace line_map_merging
