// ROS side (not part of the ROS-free core): the diagnostics task every linemap nodelet publishes.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>

#include <functional>
#include <string>

namespace linemap_ros
{
/// One diagnostics task, published every second of wall time with force_update():
/// Updater::update() waits for its period in ROS time, which never comes after the clock jumped
/// back (rosbag play --loop). `before` runs first on each tick (the merger looks for a time jump).
class WallDiagnostics
{
 public:
  template <class Owner>
  WallDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& task, Owner* owner,
                  void (Owner::*report)(diagnostic_updater::DiagnosticStatusWrapper&),
                  std::function<void()> before = {})
      : updater_(nh, pnh), before_(std::move(before))
  {
    updater_.setHardwareID("none");
    updater_.add(task, owner, report);
    timer_ = nh.createWallTimer(ros::WallDuration(1.0), &WallDiagnostics::tick, this);
  }

  WallDiagnostics(const WallDiagnostics&) = delete;  // the timer calls back into this object
  WallDiagnostics& operator=(const WallDiagnostics&) = delete;

 private:
  void tick(const ros::WallTimerEvent&)
  {
    if (before_) before_();
    updater_.force_update();
  }

  diagnostic_updater::Updater updater_;
  std::function<void()> before_;
  ros::WallTimer timer_;
};
}  // namespace linemap_ros
