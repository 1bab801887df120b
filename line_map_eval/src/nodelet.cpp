// The evaluator nodelet: accumulates registered keyframe scans (scan + tf), re-registers them
// when an optimised trajectory arrives, and scores every new line map against them.
// Only parameter reading and message conversion live here; the metrics are in the core.
#include <diagnostic_updater/diagnostic_updater.h>
#include <line_map_msgs/Evaluate.h>
#include <line_map_msgs/LineMap.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <line_map_msgs/MapQuality.h>
#include <message_filters/subscriber.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>

#include "line_extraction/ros/param_loader.hpp"
#include "line_map_eval/map_evaluator.hpp"

namespace line_map_eval
{
namespace
{
linemap::Pose2 toPose2(const geometry_msgs::Transform& t)
{
  return {t.translation.x, t.translation.y, tf2::getYaw(t.rotation)};
}

linemap::Pose2 toPose2(const geometry_msgs::Pose& p)
{
  return {p.position.x, p.position.y, tf2::getYaw(p.orientation)};
}

linemap::Vec2 toVec2(const geometry_msgs::Point& p)
{
  return {p.x, p.y};
}

std::vector<linemap::Segment2> toSegments(const line_map_msgs::LineMap& map)
{
  std::vector<linemap::Segment2> out;
  out.reserve(map.segments.size());
  for (const auto& s : map.segments) out.emplace_back(toVec2(s.segment.start), toVec2(s.segment.end));
  return out;
}
}  // namespace

class LineMapEvalNodelet : public nodelet::Nodelet
{
 public:
  ~LineMapEvalNodelet() override
  {
    scan_filter_.reset();
    segment_filter_.reset();
  }

 private:
  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    try
    {
      evaluator_ =
          std::make_unique<MapEvaluator>(EvaluatorParams::fromParams(linemap_ros::loadParamSet(pnh)));
    }
    catch (const linemap::ParameterError& e)
    {
      NODELET_FATAL("line_map_eval: %s; the evaluator stays idle", e.what());
      return;
    }
    map_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("map_frame", "map"));
    base_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("base_frame", "base_link"));
    // Frames also keep their pose in the odometry frame: trajectory corrections are interpolated
    // there, across the jumps of map -> odom (empty: in the map frame).
    odom_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("odom_frame", "odom"));
    min_period_ = pnh.param("min_period", 1.0);
    const double tf_timeout = pnh.param("tf_timeout", 0.5);
    time_jump_tolerance_ = std::max(0.0, pnh.param("time_jump_tolerance", 1.0));

    tf_buffer_ = std::make_shared<tf2_ros::Buffer>(ros::Duration(600.0));
    tf_listener_ = std::make_shared<tf2_ros::TransformListener>(*tf_buffer_);

    quality_pub_ = nh.advertise<line_map_msgs::MapQuality>("map_quality", 1, true);
    grid_pub_ = nh.advertise<nav_msgs::OccupancyGrid>("lookup_table", 1, true);

    scan_sub_.subscribe(nh, "scan", 50);
    scan_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::LaserScan>>(scan_sub_, *tf_buffer_,
                                                                                    map_frame_, 50, nh);
    scan_filter_->setTolerance(ros::Duration(tf_timeout));
    scan_filter_->registerCallback(&LineMapEvalNodelet::onScan, this);
    scan_filter_->registerFailureCallback(
        [this](const sensor_msgs::LaserScan::ConstPtr& msg,
               tf2_ros::filter_failure_reasons::FilterFailureReason)
        {
          ++dropped_scans_;
          NODELET_WARN_THROTTLE(10.0, "line_map_eval: no transform %s -> %s at %.3f; scan dropped",
                                map_frame_.c_str(), msg->header.frame_id.c_str(), msg->header.stamp.toSec());
        });

    segment_sub_.subscribe(nh, "line_segments", 50);
    segment_filter_ = std::make_unique<tf2_ros::MessageFilter<line_map_msgs::LineSegmentArray>>(
        segment_sub_, *tf_buffer_, map_frame_, 50, nh);
    segment_filter_->setTolerance(ros::Duration(tf_timeout));
    segment_filter_->registerCallback(&LineMapEvalNodelet::onSegments, this);

    map_sub_ = nh.subscribe("line_map", 1, &LineMapEvalNodelet::onMap, this);
    trajectory_sub_ = nh.subscribe("optimized_trajectory", 1, &LineMapEvalNodelet::onTrajectory, this);
    evaluate_srv_ = pnh.advertiseService("evaluate", &LineMapEvalNodelet::onEvaluate, this);

    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
    diagnostics_->setHardwareID("line_map_eval");
    diagnostics_->add("evaluator", this, &LineMapEvalNodelet::diagnose);
    // Wall time and force_update(): update() waits for the next period in ROS time, which never comes
    // after the clock jumped back (rosbag play --loop).
    diagnostics_timer_ = nh.createWallTimer(
        ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->force_update(); });
    // A map that arrived within min_period of the last publication is published by this timer.
    publish_timer_ = nh.createWallTimer(ros::WallDuration(std::max(0.05, min_period_)),
                                        [this](const ros::WallTimerEvent&)
                                        {
                                          std::lock_guard<std::mutex> lock(mutex_);
                                          publish(false);
                                        });
  }

  /// Time going backwards (a `rosbag play --loop` restart under use_sim_time): the tf buffer holds
  /// the previous pass, whose transforms would pose the replayed scans; it is cleared. The stored
  /// scans and segments are kept (the gates compare with the last stored pose, which only decides
  /// whether the first scan of the new pass is stored).
  /// `source` 0 = scans, 1 = segments: each stream is monotonic, but segments lag their scans.
  void checkTimeJump(const ros::Time& stamp, int source)
  {
    ros::Time& last_stamp = last_stamp_[source];
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time now = ros::Time::now();
    const bool clock_back = !last_now_.isZero() && (last_now_ - now).toSec() > time_jump_tolerance_;
    const bool stamp_back = !last_stamp.isZero() && (last_stamp - stamp).toSec() > time_jump_tolerance_;
    if (clock_back || stamp_back)
    {
      ++time_jumps_;
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: time jumped backwards (%s); tf buffer cleared (%zu jumps)",
                            clock_back ? "clock" : "stamp", time_jumps_);
      tf_buffer_->clear();
      last_stamp_[0] = last_stamp_[1] = ros::Time();
    }
    last_now_ = now;
    last_stamp = std::max(last_stamp, stamp);
  }

  bool lookupLaserPose(const std::string& frame, const ros::Time& stamp, linemap::Pose2& pose, int source)
  {
    checkTimeJump(stamp, source);
    try
    {
      pose = toPose2(
          tf_buffer_->lookupTransform(map_frame_, linemap_ros::stripLeadingSlash(frame), stamp).transform);
      return true;
    }
    catch (const tf2::TransformException& e)
    {
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: %s", e.what());
      return false;
    }
  }

  /// The laser pose in odom_frame_ at `stamp`, when that frame exists.
  std::optional<linemap::Pose2> lookupOdomPose(const std::string& frame, const ros::Time& stamp)
  {
    if (odom_frame_.empty() || odom_frame_ == map_frame_) return std::nullopt;
    try
    {
      return toPose2(
          tf_buffer_->lookupTransform(odom_frame_, linemap_ros::stripLeadingSlash(frame), stamp).transform);
    }
    catch (const tf2::TransformException&)
    {
      return std::nullopt;
    }
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan)
  {
    if (!std::isfinite(scan->angle_increment) || scan->angle_increment == 0.0f)
    {
      ++rejected_scans_;
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: scan with angle_increment %f ignored",
                            scan->angle_increment);
      return;
    }
    linemap::Pose2 pose;
    if (!lookupLaserPose(scan->header.frame_id, scan->header.stamp, pose, 0)) return;
    laser_frame_ = linemap_ros::stripLeadingSlash(scan->header.frame_id);
    std::vector<linemap::Vec2> points;
    points.reserve(scan->ranges.size());
    for (std::size_t i = 0; i < scan->ranges.size(); ++i)
    {
      const double r = scan->ranges[i];
      if (!std::isfinite(r) || r < scan->range_min || r >= scan->range_max) continue;
      const double a = scan->angle_min + static_cast<double>(i) * scan->angle_increment;
      points.emplace_back(r * std::cos(a), r * std::sin(a));
    }
    const auto odom = lookupOdomPose(scan->header.frame_id, scan->header.stamp);
    std::lock_guard<std::mutex> lock(mutex_);
    if (evaluator_->addScan(scan->header.stamp.toSec(), pose, std::move(points), odom)) dirty_ = true;
  }

  void onSegments(const line_map_msgs::LineSegmentArray::ConstPtr& msg)
  {
    linemap::Pose2 pose;
    if (!lookupLaserPose(msg->header.frame_id, msg->header.stamp, pose, 1)) return;
    std::vector<linemap::Segment2> segments;
    segments.reserve(msg->segments.size());
    for (const auto& s : msg->segments) segments.emplace_back(toVec2(s.start), toVec2(s.end));
    const auto odom = lookupOdomPose(msg->header.frame_id, msg->header.stamp);
    std::lock_guard<std::mutex> lock(mutex_);
    evaluator_->addSegments(msg->header.stamp.toSec(), pose, std::move(segments), odom);
  }

  void onTrajectory(const nav_msgs::Path::ConstPtr& path)
  {
    if (path->poses.empty())
    {
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: empty optimized_trajectory ignored");
      return;
    }
    // The trajectory holds base poses; the stored frames are laser poses.
    linemap::Pose2 base_to_laser;
    if (!laser_frame_.empty())
    {
      try
      {
        base_to_laser =
            toPose2(tf_buffer_->lookupTransform(base_frame_, laser_frame_, ros::Time(0)).transform);
      }
      catch (const tf2::TransformException& e)
      {
        NODELET_WARN_THROTTLE(10.0, "line_map_eval: no %s -> %s transform (%s); using identity",
                              base_frame_.c_str(), laser_frame_.c_str(), e.what());
      }
    }
    std::vector<std::pair<double, linemap::Pose2>> poses;
    poses.reserve(path->poses.size());
    for (const auto& p : path->poses)
    {
      const auto& q = p.pose.orientation;
      const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
      if (!std::isfinite(norm) || norm < 1e-9)
      {
        ++rejected_poses_;
        continue;
      }
      poses.emplace_back(p.header.stamp.toSec(), toPose2(p.pose) * base_to_laser);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    unmatched_poses_ += evaluator_->applyTrajectory(poses);
    dirty_ = true;
    publish(false);
  }

  void onMap(const line_map_msgs::LineMap::ConstPtr& map)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map_ = toSegments(*map);
    map_stamp_ = map->header.stamp;
    have_map_ = true;
    dirty_ = true;
    publish(false);
  }

  bool onEvaluate(line_map_msgs::Evaluate::Request& req, line_map_msgs::Evaluate::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (req.use_given_map)
    {
      const std::vector<linemap::Segment2> given = toSegments(req.map);
      try
      {
        res.quality = toMessage(evaluator_->evaluate(given), req.map.header.stamp);
      }
      catch (const std::exception& e)
      {
        res.success = false;
        res.message = std::string("cannot evaluate the given map: ") + e.what();
        return true;
      }
      res.success = true;
      res.message = "evaluated the given map (" + std::to_string(given.size()) + " segments) against " +
                    std::to_string(evaluator_->scanCount()) + " keyframe scans";
      return true;
    }
    if (!have_map_)
    {
      res.success = false;
      res.message = "no line_map received yet";
      return true;
    }
    res.quality = evaluateNow();
    res.success = true;
    res.message = "evaluated " + std::to_string(map_.size()) + " map segments against " +
                  std::to_string(evaluator_->scanCount()) + " keyframe scans";
    return true;
  }

  /// Publishes the metrics unless the last publication is younger than min_period (forced by the service).
  void publish(bool force)
  {
    if (!have_map_ || !dirty_) return;
    const ros::WallTime now = ros::WallTime::now();
    if (!force && (now - last_publish_).toSec() < min_period_) return;
    last_publish_ = now;
    quality_pub_.publish(evaluateNow());
    if (grid_pub_.getNumSubscribers() > 0 || grid_pub_.isLatched()) publishGrid();
  }

  line_map_msgs::MapQuality evaluateNow()
  {
    const auto start = ros::WallTime::now();
    const line_map_msgs::MapQuality q = toMessage(evaluator_->evaluate(map_), map_stamp_);
    last_eval_ms_ = (ros::WallTime::now() - start).toSec() * 1e3;
    dirty_ = false;
    last_quality_ = q.quality;
    return q;
  }

  line_map_msgs::MapQuality toMessage(const MapMetrics& m, const ros::Time& stamp) const
  {
    line_map_msgs::MapQuality q;
    q.header.stamp = stamp;
    q.header.frame_id = map_frame_;
    q.quality = m.quality.quality;
    q.error = m.error.mean_error;
    q.segment_count = static_cast<uint32_t>(m.statistics.segment_count);
    q.shortest_length = m.statistics.shortest_length;
    q.longest_length = m.statistics.longest_length;
    q.mean_length = m.statistics.mean_length;
    q.redundant_pixels = static_cast<uint32_t>(m.quality.redundant_pixels);
    q.unassigned_originals = static_cast<uint32_t>(m.error.unassigned);
    q.point_coverage = m.point_coverage.fraction() * 100.0;
    q.length_coverage = m.length_coverage.fraction() * 100.0;
    q.redundant_pairs = static_cast<uint32_t>(m.redundancy.pairs);
    q.redundant_overlap = m.redundancy.overlap_length;
    return q;
  }

  void publishGrid()
  {
    const LookupTable& table = evaluator_->table();
    if (table.empty()) return;
    nav_msgs::OccupancyGrid grid;
    grid.header.stamp = map_stamp_;
    grid.header.frame_id = map_frame_;
    grid.info.map_load_time = map_stamp_;
    grid.info.resolution = static_cast<float>(table.resolution());
    grid.info.width = static_cast<uint32_t>(table.width());
    grid.info.height = static_cast<uint32_t>(table.height());
    grid.info.origin.position.x = table.origin().x();
    grid.info.origin.position.y = table.origin().y();
    grid.info.origin.orientation.w = 1.0;
    grid.data.resize(table.values().size());
    for (std::size_t i = 0; i < grid.data.size(); ++i)
      grid.data[i] = static_cast<int8_t>(std::lround(100.0 * table.values()[i]));
    grid_pub_.publish(grid);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, have_map_ ? "evaluating" : "waiting for line_map");
    status.add("keyframe scans", evaluator_ ? evaluator_->scanCount() : 0);
    status.add("original segments", evaluator_ ? evaluator_->originalCount() : 0);
    status.add("dropped scans (tf)", dropped_scans_);
    status.add("rejected scans", rejected_scans_);
    status.add("rejected trajectory poses", rejected_poses_);
    status.add("unmatched trajectory poses", unmatched_poses_);
    status.add("time jumps", time_jumps_);
    status.add("last quality [%]", last_quality_);
    status.add("last evaluation [ms]", last_eval_ms_);
  }

  std::unique_ptr<MapEvaluator> evaluator_;
  std::string map_frame_, base_frame_, odom_frame_, laser_frame_;
  double min_period_ = 1.0;
  std::shared_ptr<tf2_ros::Buffer> tf_buffer_;
  std::shared_ptr<tf2_ros::TransformListener> tf_listener_;
  message_filters::Subscriber<sensor_msgs::LaserScan> scan_sub_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::LaserScan>> scan_filter_;
  message_filters::Subscriber<line_map_msgs::LineSegmentArray> segment_sub_;
  std::unique_ptr<tf2_ros::MessageFilter<line_map_msgs::LineSegmentArray>> segment_filter_;
  ros::Subscriber map_sub_, trajectory_sub_;
  ros::Publisher quality_pub_, grid_pub_;
  ros::ServiceServer evaluate_srv_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_, publish_timer_;

  std::mutex mutex_;
  std::vector<linemap::Segment2> map_;
  ros::Time map_stamp_;
  bool have_map_ = false;
  bool dirty_ = false;
  ros::WallTime last_publish_;
  double last_quality_ = 0.0, last_eval_ms_ = 0.0;
  std::size_t dropped_scans_ = 0, rejected_scans_ = 0, rejected_poses_ = 0, unmatched_poses_ = 0;
  double time_jump_tolerance_ = 1.0;
  ros::Time last_now_, last_stamp_[2];  // latest clock reading and scan / segments stamps seen
  std::size_t time_jumps_ = 0;
};

}  // namespace line_map_eval

PLUGINLIB_EXPORT_CLASS(line_map_eval::LineMapEvalNodelet, nodelet::Nodelet)
