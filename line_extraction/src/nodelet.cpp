// ROS wrapper of the extraction pipeline: sensor_msgs/LaserScan on `scan` ->
// line_map_msgs/LineSegmentArray on `line_segments` (+ RViz markers), in the
// scan's frame and with its stamp. All the work is in the ROS-free core.
#include <diagnostic_updater/diagnostic_updater.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/scan_geometry_monitor.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "linemap/small_helpers.hpp"
#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/transport.hpp"
#include "linemap_ros/wall_diagnostics.hpp"

namespace line_extraction
{
namespace
{
geometry_msgs::Point point(const Vec2& p)
{
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  return q;
}
}  // namespace

/// The ROS side: reads the parameters, converts messages, calls the core.
class LineExtractionRos
{
 public:
  LineExtractionRos(ros::NodeHandle nh, ros::NodeHandle private_nh)
  {
    const linemap::ParamSet params = linemap_ros::loadParamSet(private_nh);
    // Throws linemap::ParameterError naming the parameter; the nodelet reports it.
    extractor_ = std::make_unique<LineExtractor>(params);
    submap_ =
        std::make_unique<SubmapExtractor>(SubmapParams::fromParams(params), extractor_->params().sensor);
    if (submap_->params().enabled)
    {
      // The window is registered in the odometry frame: locally consistent, never jumps.
      private_nh.param<std::string>("submap/odom_frame", odom_frame_, "odom");
      private_nh.param("submap/tf_timeout", tf_timeout_, 0.1);
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
    }
    // Scans that may wait, and segment sets for a slow subscriber (a checker in python under load): past it
    // the oldest are lost without a trace.
    const std::uint32_t queue = linemap_ros::queueSizeParam(private_nh);
    segments_pub_ = nh.advertise<line_map_msgs::LineSegmentArray>("line_segments", queue);
    markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("line_segments_markers", 1);
    // Room for bursts: a bag played fast, or the manager's worker threads busy elsewhere (an autosave, the
    // SLAM's search for the robot in a saved session). Extraction takes microseconds, so a long queue adds
    // no latency in steady state.
    scan_sub_ = nh.subscribe("scan", queue, &LineExtractionRos::scanCallback, this, linemap_ros::noDelay());
    diagnostics_ = std::make_unique<linemap_ros::WallDiagnostics>(nh, private_nh, "line extraction", this,
                                                                  &LineExtractionRos::produceDiagnostics);
    ROS_INFO("line_extraction: algorithm '%s'%s", extractor_->params().algorithm.c_str(),
             extractor_->params().clustering ? " with breakpoint clustering" : "");
  }

 private:
  void scanCallback(const sensor_msgs::LaserScan::ConstPtr& msg)
  {
    const bool want_segments = segments_pub_.getNumSubscribers() > 0;
    const bool want_markers = markers_pub_.getNumSubscribers() > 0;
    if (!want_segments && !want_markers) return;
    std::lock_guard<std::mutex> lock(mutex_);
    ++scans_;
    checkGeometry(*msg);
    const ExtractionResult* result = nullptr;
    const auto t0 = std::chrono::steady_clock::now();
    try
    {
      result = &extractor_->extract(scanInputOf(*msg));
    }
    catch (const ScanError& e)
    {
      ++rejected_scans_;
      ROS_WARN_THROTTLE(5.0, "line_extraction: scan from frame '%s' skipped (%zu so far): %s",
                        msg->header.frame_id.c_str(), rejected_scans_, e.what());
      return;
    }
    last_ms_ = linemap::millisecondsSince(t0);
    if (submap_->params().enabled) addSubmapSegments(*msg);
    segments_ += result->segments.size();
    if (want_segments) publishSegments(msg->header, *result);
    if (want_markers) publishMarkers(msg->header, *result);
  }

  /// Appends the submap's segments to the extractor's result, the laser posed by tf in the odometry frame.
  void addSubmapSegments(const sensor_msgs::LaserScan& msg)
  {
    submap_->observeStamp(msg.header.stamp.toNSec());
    geometry_msgs::TransformStamped odom_laser;
    try
    {
      odom_laser = tf_buffer_->lookupTransform(odom_frame_, msg.header.frame_id, msg.header.stamp,
                                               ros::Duration(tf_timeout_));
    }
    catch (const tf2::TransformException& e)
    {
      ++submap_skipped_;
      ROS_WARN_THROTTLE(5.0, "line_extraction: no submap for this scan (%zu so far): %s", submap_skipped_,
                        e.what());
      return;
    }
    const auto& t = odom_laser.transform;
    const Pose2 laser(t.translation.x, t.translation.y, tf2::getYaw(t.rotation));
    submap_segments_ += submap_->appendTo(extractor_->preparedScan(), extractor_->mutableResult(), laser);
  }

  void checkGeometry(const sensor_msgs::LaserScan& msg)
  {
    const std::size_t n = msg.ranges.size();
    const auto found = geometry_.observe(msg.angle_min, msg.angle_max, msg.angle_increment, n);
    if (found.inconsistent_angle_max)
      ROS_WARN_THROTTLE(5.0,
                        "line_extraction: scan from frame '%s': angle_max %.6f differs from angle_min + "
                        "(n - 1) * angle_increment = %.6f; beams placed by angle_min and angle_increment",
                        msg.header.frame_id.c_str(), msg.angle_max, found.expected_angle_max);
    if (found.changed)
      ROS_INFO_THROTTLE(5.0,
                        "line_extraction: the scan geometry changed (%zu beams from %.4f rad by %.6f rad)", n,
                        msg.angle_min, msg.angle_increment);
  }

  void produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stat.summary(
        rejected_scans_ > 0 ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
        rejected_scans_ > 0 ? "unusable scans skipped" : "extracting");
    stat.add("algorithm", extractor_->params().algorithm);
    stat.add("scans", scans_);
    stat.add("rejected scans", rejected_scans_);
    stat.add("inconsistent angle_max", geometry_.inconsistentAngleMax());
    stat.add("geometry changes", geometry_.changes());
    stat.add("segments", segments_);
    if (submap_->params().enabled)
    {
      stat.add("submap segments", submap_segments_);
      stat.add("scans without submap (no tf)", submap_skipped_);
    }
    stat.add("last extraction time [ms]", last_ms_);
  }

  void publishSegments(const std_msgs::Header& header, const ExtractionResult& result)
  {
    line_map_msgs::LineSegmentArrayPtr out(new line_map_msgs::LineSegmentArray);
    out->header = header;
    out->segments.resize(result.segments.size());
    for (std::size_t i = 0; i < result.segments.size(); ++i)
    {
      const Segment& s = result.segments[i];
      line_map_msgs::LineSegment& m = out->segments[i];
      m.start = point(s.start);
      m.end = point(s.end);
      m.angle = s.angle;
      m.radius = s.radius;
      m.covariance = {s.covariance(0, 0), s.covariance(0, 1), s.covariance(1, 0), s.covariance(1, 1)};
      m.num_points = static_cast<uint32_t>(s.num_points);
    }
    segments_pub_.publish(out);
  }

  /// Lines, start points red, end points green; an empty marker is deleted rather than sent without points.
  void publishMarkers(const std_msgs::Header& header, const ExtractionResult& result)
  {
    using visualization_msgs::Marker;
    visualization_msgs::MarkerArrayPtr out(new visualization_msgs::MarkerArray);
    const char* ns[3] = {"lines", "start_points", "end_points"};
    const float rgb[3][3] = {{0.2f, 0.4f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
    for (int k = 0; k < 3; ++k)
    {
      Marker m;
      m.header = header;
      m.ns = ns[k];
      m.type = k == 0 ? Marker::LINE_LIST : Marker::POINTS;
      m.action = result.segments.empty() ? Marker::DELETE : Marker::ADD;
      m.pose.orientation.w = 1.0;
      m.scale.x = k == 0 ? 0.03 : 0.08;
      m.scale.y = 0.08;
      m.color.r = rgb[k][0];
      m.color.g = rgb[k][1];
      m.color.b = rgb[k][2];
      m.color.a = 1.0f;
      for (const Segment& s : result.segments)
      {
        if (k != 2) m.points.push_back(point(s.start));
        if (k != 1) m.points.push_back(point(s.end));
      }
      out->markers.push_back(m);
    }
    markers_pub_.publish(out);
  }

  std::mutex mutex_;  // the scan callback and the diagnostics timer
  std::unique_ptr<LineExtractor> extractor_;
  std::unique_ptr<SubmapExtractor> submap_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::string odom_frame_;
  double tf_timeout_ = 0.1;
  std::size_t submap_segments_ = 0, submap_skipped_ = 0;
  ros::Publisher segments_pub_, markers_pub_;
  ros::Subscriber scan_sub_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  ScanGeometryMonitor geometry_;
  std::size_t scans_ = 0, rejected_scans_ = 0, segments_ = 0;
  double last_ms_ = 0.0;
};

class LineExtractionNodelet : public nodelet::Nodelet
{
 private:
  void onInit() override
  {
    try
    {
      ros_ = std::make_unique<LineExtractionRos>(getNodeHandle(), getPrivateNodeHandle());
    }
    catch (const linemap::ParameterError& e)
    {
      // Stay loaded but idle: nothing is subscribed, the error names the parameter.
      NODELET_FATAL("line_extraction: not starting: %s (namespace %s)", e.what(),
                    getPrivateNodeHandle().getNamespace().c_str());
    }
  }

  std::unique_ptr<LineExtractionRos> ros_;
};

}  // namespace line_extraction

PLUGINLIB_EXPORT_CLASS(line_extraction::LineExtractionNodelet, nodelet::Nodelet)
