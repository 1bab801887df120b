// The occupancy grid of a live map (ROS-free): what to draw (gridInputOf, a copy taken while the map
// is locked, so that the grid is built without holding up the scans), when (GridSchedule: after a
// change, while someone listens, at a bounded rate) and both with the figures of the grids made
// (LiveGrid). The drawing itself is occupancy_grid.hpp's.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/map/occupancy_grid.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace line_map_merging
{
/// Everything buildOccupancyGrid needs, copied out of a merger.
struct GridInput
{
  std::vector<linemap::Segment2> walls;  ///< the map segments, map frame
  /// The originals seen from their keyframes' laser poses; empty for a merger without provenance.
  std::vector<Sighting> sightings;
  /// Stamp of the newest keyframe [s]; -infinity for a map without keyframes.
  double newest_stamp = -std::numeric_limits<double>::infinity();
};

/// The walls are the segments map() shows. Free space needs provenance: CAE-RLSM gives every original
/// (under withheld segments too, as buildOccupancyGrid(const CaeRlsm&) does, which it matches cell for
/// cell); another merger with provenance the originals under its map segments; a merger without
/// provenance none, so its grid is walls in unknown space (nothing says where the robot saw through).
GridInput gridInputOf(const Merger& merger);

inline OccupancyGrid buildOccupancyGrid(const GridInput& input, const OccupancyGridParams& params)
{
  return buildOccupancyGrid(input.walls, input.sightings, params);
}

/// When a grid is due: the map changed since the last grid (or none was made yet), someone subscribes,
/// and at least `min_period` has passed since the last grid was started (a grid costs far more than a
/// scan, and a map changes at every keyframe). A change while nobody listens waits, so the first
/// subscriber gets the current map. Times are seconds on a monotonic clock. Not thread-safe.
class GridSchedule
{
 public:
  /// Throws std::invalid_argument for a negative or non-finite period.
  explicit GridSchedule(double min_period);

  void mapChanged() { stale_ = true; }
  bool due(double now, bool subscribed) const;
  /// A grid of the map as it is now is being made: current until the next mapChanged().
  void started(double now);

  bool stale() const { return stale_; }
  double minPeriod() const { return min_period_; }

 private:
  double min_period_;
  bool stale_ = true;  // no grid yet
  double last_ = -std::numeric_limits<double>::infinity();
};

/// The grids of a live map: GridSchedule on the steady clock, the input taken when a grid is due,
/// and the figures of the grids made. Not thread-safe: the caller serialises the calls (build a grid
/// from the input while the map goes on).
class LiveGrid
{
 public:
  /// Throws std::invalid_argument for a bad period or resolution.
  LiveGrid(const OccupancyGridParams& params, double min_period);

  void mapChanged() { schedule_.mapChanged(); }
  /// The input of a grid of the map as it is now when one is due, else nothing.
  std::optional<GridInput> due(const Merger& merger, bool subscribed);
  const OccupancyGridParams& params() const { return params_; }
  /// A grid was made from the input due() gave, in `ms`.
  void made(const OccupancyGrid& grid, double ms);
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

 private:
  OccupancyGridParams params_;
  GridSchedule schedule_;
  std::size_t made_ = 0;
  double last_ms_ = 0.0;
  std::string last_size_ = "none";
};

}  // namespace line_map_merging
