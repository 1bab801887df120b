// line_map_merging/LocalizationNodelet: a thin ROS wrapper of LineMapLocalizer (line_map_localizer.hpp).
// The map comes from `~map_file` (a saved line map) or, without one, the latched `line_map` topic.
// Subscribes to `scan`, takes the odometry prior from tf odom -> base at the scan's stamp, publishes
// tf map -> odom, `amcl_pose`-style geometry_msgs/PoseWithCovarianceStamped on `localization_pose`,
// and diagnostics. `initialpose` (RViz' 2D Pose Estimate) sets the pose; the `global_localization`
// service (std_srvs/Empty) forgets it and searches the whole map.
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <line_map_msgs/LineMap.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>

#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "linemap_ros/message_conversions.hpp"
#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/tf_wait_queue.hpp"
#include "linemap_ros/transport.hpp"
#include "linemap_ros/wall_diagnostics.hpp"

namespace line_map_merging
{
class LocalizationNodelet : public nodelet::Nodelet
{
 private:
  using ScanQueue = linemap_ros::TfWaitQueue<sensor_msgs::LaserScan>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::tie(map_frame_, base_frame_, odom_frame_) = linemap_ros::frameParams(pnh);
    tf_timeout_ = pnh.param("tf_timeout", 0.1);
    try
    {
      params_ = LocalizerParams::fromParams(linemap_ros::loadParamSet(pnh));
      time_jumps_.setTolerance(params_.time_jump_tolerance);
    }
    catch (const linemap::ParameterError& e)
    {
      NODELET_ERROR("localization: bad parameter (%s); running on the built-in defaults", e.what());
    }
    buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(30.0));
    listener_ = std::make_unique<tf2_ros::TransformListener>(*buffer_, nh, true, linemap_ros::noDelay());
    pose_pub_ = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("localization_pose", 10);
    const std::string map_file = pnh.param("map_file", std::string());
    if (!map_file.empty())
      loadFile(map_file);
    else
      map_sub_ = nh.subscribe("line_map", 1, &LocalizationNodelet::onMap, this, linemap_ros::noDelay());
    map_file_timer_ = nh.createWallTimer(ros::WallDuration(5.0),
                                         [this, map_file](const ros::WallTimerEvent&)
                                         {
                                           // A map file that failed to load is tried again: it may be
                                           // being written.
                                           std::lock_guard<std::mutex> lock(mutex_);
                                           if (!map_file.empty() && !localizer_) loadFile(map_file);
                                         });
    initial_sub_ = nh.subscribe("initialpose", 1, &LocalizationNodelet::onInitialPose, this);
    // Scans wait until tf places them in the odometry frame; one that waits tf_timeout in vain is
    // matched without the odometry.
    scans_ = std::make_unique<ScanQueue>(
        *buffer_, odom_frame_, 100, ros::Duration(tf_timeout_), nh,
        [this](const ScanQueue::Event& e) { onScan(*e.getConstMessage(), true); },
        [this](const ScanQueue::Event& e, const std::string& why)
        { onScan(*e.getConstMessage(), false, why); });
    scans_->subscribe(nh, "scan", 100, [this](const ScanQueue::Event& e) { return onArrival(e); });
    global_srv_ = nh.advertiseService("global_localization", &LocalizationNodelet::onGlobal, this);
    diagnostics_ = std::make_unique<linemap_ros::WallDiagnostics>(nh, pnh, "line map localization", this,
                                                                  &LocalizationNodelet::diagnose);
  }

  // Caller holds mutex_ (or is onInit).
  void loadFile(const std::string& path)
  {
    try
    {
      setMap(loadLineMapSegments(path));
      NODELET_INFO("localization: %zu segments from %s", localizer_->index().segments().size(), path.c_str());
      map_error_.clear();
    }
    catch (const std::exception& e)
    {
      if (map_error_ != e.what())  // once per distinct error, not at every retry
        NODELET_ERROR("localization: %s; waiting for a good map file (retrying every 5 s)", e.what());
      map_error_ = e.what();
    }
  }

  void setMap(const std::vector<linemap::Segment2>& segments)
  {
    if (localizer_) return localizer_->setMap(segments);
    localizer_ = std::make_unique<LineMapLocalizer>(segments, params_);
    if (pending_initial_) localizer_->setPose(*pending_initial_);
  }

  void onMap(const line_map_msgs::LineMap::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    setMap(linemap_ros::toSegments(*msg));
  }

  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& p = msg->pose.pose;
    const auto given = linemap_ros::toPose2(p.position.x, p.position.y, p.orientation);
    if (!given)
    {
      NODELET_WARN("localization: initialpose ignored: its orientation is not a unit quaternion");
      return;
    }
    NODELET_INFO("localization: initial pose (%.2f, %.2f, %.1f deg)", given->x, given->y,
                 given->theta * 180.0 / M_PI);
    pending_initial_ = given;
    if (localizer_) localizer_->setPose(*given);
  }

  bool onGlobal(std_srvs::Empty::Request&, std_srvs::Empty::Response&)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    NODELET_INFO("localization: global localization requested");
    pending_initial_.reset();
    if (localizer_) localizer_->startGlobalLocalization();
    return true;
  }

  /// On arrival, before the scan waits for tf: a clock or stamp going back (a replayed bag) empties
  /// the tf buffer, which holds the future, and the scans waiting.
  bool onArrival(const ScanQueue::Event& event)
  {
    const double stamp = event.getConstMessage()->header.stamp.toSec();
    std::lock_guard<std::mutex> lock(mutex_);
    if (time_jumps_.observe(ros::Time::now().toSec(), stamp))
    {
      NODELET_WARN("localization: %s: tf and the waiting scans are cleared", time_jumps_.cause().c_str());
      buffer_->clear();
      scans_->clear();
    }
    return true;
  }

  /// A scan tf can place in the odometry frame, or one that waited for it in vain (`odometry` false):
  /// matched without the odometry prior when at least the laser's mount is known.
  void onScan(const sensor_msgs::LaserScan& msg, bool odometry, const std::string& why = {})
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!localizer_) return;
    const ros::Time stamp = msg.header.stamp;
    const std::string laser_frame = linemap_ros::stripLeadingSlash(msg.header.frame_id);
    // The transforms now in the buffer (the wait queue has waited for them), if any.
    const auto mount = linemap_ros::lookupPose(*buffer_, base_frame_, laser_frame, stamp);
    if (!mount)
    {
      ++dropped_;
      NODELET_WARN_THROTTLE(10.0, "localization: no tf %s -> %s: scan dropped (%s)", base_frame_.c_str(),
                            laser_frame.c_str(), why.c_str());
      return;
    }
    LocalizerScan scan;
    scan.stamp = stamp.toSec();
    scan.sensor = mount->translation();
    if (odometry) scan.odom = linemap_ros::lookupPose(*buffer_, odom_frame_, base_frame_, stamp);
    if (!scan.odom)
    {
      ++no_odometry_;
      NODELET_WARN_THROTTLE(10.0, "localization: no odometry tf %s -> %s (%s): matching without it",
                            odom_frame_.c_str(), base_frame_.c_str(), why.c_str());
    }
    const line_extraction::ScanInput ranges{msg.ranges.data(),   msg.ranges.size(), msg.angle_min,
                                            msg.angle_increment, msg.range_min,     msg.range_max};
    scan.points = beamPoints(ranges, *mount);
    const LocalizerResult r = localizer_->addScan(scan);
    if (r.outcome == LocalizerOutcome::kRejected) return;
    if (r.outcome == LocalizerOutcome::kRecovered)
      NODELET_INFO("localization: global localization found (%.2f, %.2f, %.1f deg)", r.pose.x, r.pose.y,
                   r.pose.theta * 180.0 / M_PI);
    if (!r.localized) return;  // a hypothesis is not published as the pose
    pending_initial_.reset();
    // map -> odom from the pose and the odometry at the same stamp; without odometry it is kept.
    if (scan.odom) map_odom_ = r.pose * scan.odom->inverse();
    if (map_odom_)
      broadcaster_.sendTransform(linemap_ros::toTransform(*map_odom_, map_frame_, odom_frame_, stamp));
    publishPose(r, stamp);
  }

  void publishPose(const LocalizerResult& r, const ros::Time& stamp)
  {
    geometry_msgs::PoseWithCovarianceStamped out;
    out.header.stamp = stamp;
    out.header.frame_id = map_frame_;
    out.pose.pose = linemap_ros::toPoseMsg(r.pose);
    const int idx[3] = {0, 1, 5};  // the covariance is 6x6 row-major over (x, y, z, roll, pitch, yaw)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.pose.covariance[idx[i] * 6 + idx[j]] = r.covariance(i, j);
    pose_pub_.publish(out);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!localizer_)
    {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   map_error_.empty() ? "waiting for a line map" : "no map: " + map_error_);
      return;
    }
    const bool ok = localizer_->localized();
    stat.summary(ok ? diagnostic_msgs::DiagnosticStatus::OK : diagnostic_msgs::DiagnosticStatus::WARN,
                 ok ? "tracking" : "global localization");
    for (const auto& [key, value] : localizer_->diagnostics()) stat.add(key, value);
    stat.add("scans dropped (no base -> laser tf)", dropped_);
    stat.add("scans without odometry tf", no_odometry_);
  }

  std::mutex mutex_;
  LocalizerParams params_;
  std::unique_ptr<LineMapLocalizer> localizer_;
  std::unique_ptr<tf2_ros::Buffer> buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
  tf2_ros::TransformBroadcaster broadcaster_;
  std::unique_ptr<ScanQueue> scans_;
  ros::Subscriber map_sub_, initial_sub_;
  ros::Publisher pose_pub_;
  ros::ServiceServer global_srv_;
  ros::WallTimer map_file_timer_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  std::string map_frame_, odom_frame_, base_frame_, map_error_;
  double tf_timeout_ = 0.1;
  linemap::TimeJumpDetector time_jumps_;
  std::optional<linemap::Pose2> map_odom_, pending_initial_;
  std::size_t dropped_ = 0, no_odometry_ = 0;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::LocalizationNodelet, nodelet::Nodelet)
