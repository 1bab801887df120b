// The occupancy grid of a live map: its input and its schedule (see map_grid.hpp).
#include "line_map_merging/map/map_grid.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
GridInput gridInputOf(const Merger& merger)
{
  GridInput input;
  const std::vector<MapSegment> map = merger.map();
  input.walls.reserve(map.size());
  for (const MapSegment& m : map) input.walls.push_back(m.segment);
  const std::vector<KeyframeInfo> keyframes = merger.keyframes();
  for (const KeyframeInfo& k : keyframes) input.newest_stamp = std::max(input.newest_stamp, k.stamp);
  if (!merger.hasProvenance()) return input;

  std::vector<Leaf> leaves;
  leaves.reserve(merger.leafCount());
  const auto take = [&](std::uint64_t id)
  {
    std::vector<Leaf> mine = merger.leaves(id);
    leaves.insert(leaves.end(), mine.begin(), mine.end());
  };
  // CAE-RLSM withholds single-view segments from map(); the space in front of them was still seen.
  if (const auto* cae = dynamic_cast<const CaeRlsm*>(&merger))
    for (std::uint64_t id = 0; id < cae->nextId(); ++id) take(id);
  else
    for (const MapSegment& m : map) take(m.id);
  input.sightings = sightingsOf(keyframes, leaves);
  return input;
}

GridSchedule::GridSchedule(double min_period) : min_period_(min_period)
{
  if (!(min_period >= 0.0) || !std::isfinite(min_period))
    throw std::invalid_argument("grid_period must be a number >= 0, got " + std::to_string(min_period));
}

bool GridSchedule::due(double now, bool subscribed) const
{
  // A clock behind the last start (not monotonic after all) must not stop the grids for good.
  return stale_ && subscribed && (now - last_ >= min_period_ || now < last_);
}

void GridSchedule::started(double now)
{
  stale_ = false;
  last_ = now;
}

LiveGrid::LiveGrid(const OccupancyGridParams& params, double min_period)
    : params_(params), schedule_(min_period)
{
  params_.validate();
}

std::optional<GridInput> LiveGrid::due(const Merger& merger, bool subscribed)
{
  const double now =
      std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  if (!schedule_.due(now, subscribed)) return std::nullopt;
  schedule_.started(now);
  return gridInputOf(merger);
}

void LiveGrid::made(const OccupancyGrid& grid, double ms)
{
  ++made_;
  last_ms_ = ms;
  last_size_ = std::to_string(grid.width) + " x " + std::to_string(grid.height);
}

std::vector<std::pair<std::string, std::string>> LiveGrid::diagnostics() const
{
  std::ostringstream ms;
  ms << last_ms_;
  return {{"grids published", std::to_string(made_)},
          {"grid size [cells]", last_size_},
          {"grid build [ms]", ms.str()}};
}

}  // namespace line_map_merging
