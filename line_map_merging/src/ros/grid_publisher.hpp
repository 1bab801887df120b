// The merging nodelet's occupancy grid on the latched `grid` topic (ROS side, header-only). The grid
// is built from a copy of the map on the multi-threaded callback queue, so scans (on the nodelet's
// serial queue) merge meanwhile; one grid is built at a time. The tick also notices the first
// subscriber, who then gets the map as it is.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/map/map_grid.hpp"
#include "linemap/small_helpers.hpp"
#include "map_messages.hpp"

namespace line_map_merging
{
class GridPublisher
{
 public:
  /// `map()`, called under `map_lock`: the merger whose map to draw; `newest` (read under the lock):
  /// the newest input stamp.
  using MapSource = std::function<const Merger&()>;

  /// Parameters ~grid_resolution and ~grid_period (the shortest time between two grids). Throws
  /// std::invalid_argument for a bad resolution or period (LiveGrid).
  GridPublisher(ros::NodeHandle& nh, ros::NodeHandle& mt_nh, const ros::NodeHandle& pnh,
                const std::string& frame, std::mutex& map_lock, MapSource map, const ros::Time& newest)
      : frame_(frame),
        live_(paramsOf(pnh), pnh.param("grid_period", 2.0)),
        map_lock_(map_lock),
        map_(std::move(map)),
        newest_(newest)
  {
    pub_ = nh.advertise<nav_msgs::OccupancyGrid>("grid", 1, true);
    timer_ = mt_nh.createWallTimer(ros::WallDuration(0.1), &GridPublisher::tick, this);
  }

  /// The map changed (caller holds the map's lock).
  void mapChanged() { live_.mapChanged(); }
  /// Caller holds the map's lock.
  std::vector<std::pair<std::string, std::string>> diagnostics() const { return live_.diagnostics(); }

  /// Stops the ticks and waits for a grid in progress.
  void stop()
  {
    timer_.stop();
    std::lock_guard<std::mutex> building(building_);
  }

 private:
  static OccupancyGridParams paramsOf(const ros::NodeHandle& pnh)
  {
    OccupancyGridParams params;
    params.resolution = pnh.param("grid_resolution", 0.05);
    return params;
  }

  void tick(const ros::WallTimerEvent&)
  {
    std::unique_lock<std::mutex> building(building_, std::try_to_lock);
    if (!building.owns_lock()) return;  // the last tick's grid is still being built
    std::optional<GridInput> input;
    ros::Time newest;
    {
      std::lock_guard<std::mutex> lock(map_lock_);
      input = live_.due(map_(), pub_.getNumSubscribers() > 0);
      newest = newest_;
    }
    if (!input) return;
    const auto start = std::chrono::steady_clock::now();
    try
    {
      const OccupancyGrid grid = buildOccupancyGrid(*input, live_.params());
      pub_.publish(toGridMessage(grid, frame_, gridStamp(input->newest_stamp, newest)));
      std::lock_guard<std::mutex> lock(map_lock_);
      live_.made(grid, linemap::millisecondsSince(start));
    }
    catch (const std::exception& e)  // a map too large for the resolution: again after the next change
    {
      ROS_WARN_THROTTLE(30.0, "line_map_merging: no occupancy grid: %s", e.what());
    }
  }

  std::string frame_;
  LiveGrid live_;  // guarded by map_lock_
  std::mutex& map_lock_;
  MapSource map_;
  const ros::Time& newest_;
  std::mutex building_;  // held while a grid is built
  ros::Publisher pub_;
  ros::WallTimer timer_;
};
}  // namespace line_map_merging
