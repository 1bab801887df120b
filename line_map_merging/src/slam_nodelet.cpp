// line_map_merging/SlamNodelet: a thin ROS wrapper of LaserSlam (laser_slam.hpp). Subscribes to
// `scan`, takes odometry from tf odom -> base at the scan's stamp (optional), publishes tf
// map -> odom (and, laser only, odom -> base from the front end), the optimised keyframe poses on
// `optimized_trajectory` (nav_msgs/Path, each pose stamped with its scan's stamp) and diagnostics.
#include <diagnostic_updater/diagnostic_updater.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>

#include "line_extraction/ros/param_loader.hpp"
#include "line_extraction/ros/tf_wait_queue.hpp"
#include "line_extraction/ros/transport.hpp"
#include "line_extraction/ros/wall_diagnostics.hpp"
#include "line_map_merging/laser_slam.hpp"

namespace line_map_merging
{
namespace
{
linemap::Pose2 toPose(const geometry_msgs::Transform& t)
{
  return {t.translation.x, t.translation.y, tf2::getYaw(t.rotation)};
}

geometry_msgs::TransformStamped toTransform(const linemap::Pose2& p, const std::string& parent,
                                            const std::string& child, const ros::Time& stamp)
{
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = p.x;
  t.transform.translation.y = p.y;
  t.transform.rotation.z = std::sin(0.5 * p.theta);
  t.transform.rotation.w = std::cos(0.5 * p.theta);
  return t;
}
}  // namespace

class SlamNodelet : public nodelet::Nodelet
{
 private:
  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::tie(map_frame_, base_frame_, odom_frame_) = linemap_ros::frameParams(pnh);
    use_odometry_ = pnh.param("use_odometry", true);
    tf_timeout_ = pnh.param("tf_timeout", 0.1);
    publish_period_ = pnh.param("publish_period", 0.0);
    LaserSlamParams params;
    try
    {
      params = LaserSlamParams::fromParams(linemap_ros::loadParamSet(pnh));
    }
    catch (const linemap::ParameterError& e)
    {
      NODELET_ERROR("slam: bad parameter (%s); running on the built-in defaults", e.what());
    }
    slam_ = std::make_unique<LaserSlam>(params);
    buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(600.0));  // the SLAM may lag the bag
    listener_ = std::make_unique<tf2_ros::TransformListener>(*buffer_, nh, true, linemap_ros::noDelay());
    path_pub_ = nh.advertise<nav_msgs::Path>("optimized_trajectory", 1, true);
    scan_sub_ = nh.subscribe("scan", std::max(1, pnh.param("queue_size", 1000)), &SlamNodelet::onScan, this,
                             linemap_ros::noDelay());
    diagnostics_ =
        std::make_unique<linemap_ros::WallDiagnostics>(nh, pnh, "laser slam", this, &SlamNodelet::diagnose);
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time stamp = msg->header.stamp;
    if (stamp.isZero())
    {
      ++zero_stamps_;
      NODELET_WARN_THROTTLE(10.0, "slam: scan stamped zero dropped");
      return;
    }
    if (have_stamp_ && stamp.toSec() < last_stamp_ - slam_->params().time_jump_tolerance)
    {
      // A replay from the start: a new trajectory on a clean tf buffer.
      NODELET_WARN("slam: time jumped back by %.1f s: new trajectory", last_stamp_ - stamp.toSec());
      ++resets_;
      slam_->reset();
      buffer_->clear();
      last_publish_ = 0.0;
    }
    const std::string laser_frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
    std::string error;
    std::optional<linemap::Pose2> mount = lookup(base_frame_, laser_frame, stamp, error);
    if (!mount && (base_frame_ == laser_frame || !use_odometry_)) mount = linemap::Pose2();  // laser = base
    if (!mount)
    {
      ++dropped_;
      NODELET_WARN_THROTTLE(10.0, "slam: no tf %s -> %s (%s): scan dropped", base_frame_.c_str(),
                            laser_frame.c_str(), error.c_str());
      return;
    }
    SlamScan scan;
    scan.stamp = stamp.toSec();
    if (use_odometry_ && !(scan.odom = lookup(odom_frame_, base_frame_, stamp, error)))
      NODELET_WARN_THROTTLE(10.0, "slam: no odometry tf %s -> %s (%s): matching without it",
                            odom_frame_.c_str(), base_frame_.c_str(), error.c_str());
    for (std::size_t i = 0; i < msg->ranges.size(); ++i)
    {
      const double r = msg->ranges[i];
      if (!(r >= msg->range_min && r <= msg->range_max)) continue;
      const double a = msg->angle_min + static_cast<double>(i) * msg->angle_increment;
      scan.points.push_back(mount->apply({r * std::cos(a), r * std::sin(a)}));
    }
    if (slam_->addScan(scan) == SlamOutcome::kRejected) return;
    have_stamp_ = true;
    last_stamp_ = scan.stamp;
    publishTf(stamp, scan.odom);
    if (slam_->graphOptimized() || (slam_->keyframeAdded() && publish_period_ > 0.0 &&
                                    ros::WallTime::now().toSec() - last_publish_ >= publish_period_))
      publishPath(stamp);
  }

  /// tf at the stamp, waiting up to ~tf_timeout for it to arrive: in ROS time, and at most that or 1 s
  /// of wall time (tf2_ros' own wait runs on ROS time only, and the clock stops when a bag ends: a SLAM
  /// behind the bag waited for ever). A stamp before the buffer's data is not waited for: it never comes.
  std::optional<linemap::Pose2> lookup(const std::string& target, const std::string& source,
                                       const ros::Time& stamp, std::string& error)
  {
    const ros::Time end = ros::Time::now() + ros::Duration(tf_timeout_);
    const ros::WallTime wall_end = ros::WallTime::now() + ros::WallDuration(std::max(tf_timeout_, 1.0));
    while (!buffer_->canTransform(target, source, stamp, &error))
    {
      if (linemap_ros::extrapolatesIntoThePast(error) || ros::Time::now() >= end ||
          ros::WallTime::now() >= wall_end)
        return std::nullopt;
      ros::WallDuration(0.001).sleep();
    }
    try
    {
      return toPose(buffer_->lookupTransform(target, source, stamp).transform);
    }
    catch (const tf2::TransformException& e)  // pruned since canTransform
    {
      error = e.what();
      return std::nullopt;
    }
  }

  void publishTf(const ros::Time& stamp, const std::optional<linemap::Pose2>& odom)
  {
    const linemap::Pose2 map_base = slam_->currentPose();
    // Without odometry the front end is the odometry: odom -> base is its pose.
    const linemap::Pose2 odom_base = odom ? *odom : slam_->currentLocal();
    std::vector<geometry_msgs::TransformStamped> out{
        toTransform(map_base * odom_base.inverse(), map_frame_, odom_frame_, stamp)};
    if (!use_odometry_) out.push_back(toTransform(odom_base, odom_frame_, base_frame_, stamp));
    broadcaster_.sendTransform(out);
  }

  void publishPath(const ros::Time& stamp)
  {
    nav_msgs::Path path;
    path.header.stamp = stamp;
    path.header.frame_id = map_frame_;
    for (const auto& [t, p] : slam_->trajectory())
    {
      geometry_msgs::PoseStamped ps;
      ps.header.stamp.fromSec(t);
      ps.header.frame_id = map_frame_;
      ps.pose.position.x = p.x;
      ps.pose.position.y = p.y;
      ps.pose.orientation.z = std::sin(0.5 * p.theta);
      ps.pose.orientation.w = std::cos(0.5 * p.theta);
      path.poses.push_back(ps);
    }
    path_pub_.publish(path);
    ++paths_;
    last_publish_ = ros::WallTime::now().toSec();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stat.summary(dropped_ ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                 dropped_ ? "scans dropped (no base -> laser tf)" : "ok");
    for (const auto& [key, value] : slam_->diagnostics()) stat.add(key, value);
    stat.add("scans dropped (no tf)", dropped_);
    stat.add("scans stamped zero", zero_stamps_);
    stat.add("new trajectories (time jumped back)", resets_);
    stat.add("trajectories published", paths_);
  }

  std::mutex mutex_;
  std::unique_ptr<LaserSlam> slam_;
  std::unique_ptr<tf2_ros::Buffer> buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Subscriber scan_sub_;
  ros::Publisher path_pub_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  std::string map_frame_, odom_frame_, base_frame_;
  bool use_odometry_ = true, have_stamp_ = false;
  double tf_timeout_ = 0.1, publish_period_ = 0.0, last_stamp_ = 0.0, last_publish_ = 0.0;
  std::size_t dropped_ = 0, zero_stamps_ = 0, resets_ = 0, paths_ = 0;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::SlamNodelet, nodelet::Nodelet)
