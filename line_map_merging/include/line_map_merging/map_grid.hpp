// The occupancy grid of a live map (ROS-free): what to draw (gridInputOf, a copy taken while the map
// is locked, so that the grid is built without holding up the scans) and when (GridSchedule: after a
// change, while someone listens, at a bounded rate). The drawing itself is occupancy_grid.hpp's.
#pragma once

#include <limits>
#include <vector>

#include "line_map_merging/merger.hpp"
#include "line_map_merging/occupancy_grid.hpp"

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

}  // namespace line_map_merging
