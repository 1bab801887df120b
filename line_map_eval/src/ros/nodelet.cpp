// The evaluator nodelet: keyframe scans (scan + tf) and original segments in, re-registered on each
// optimized_trajectory; every new line_map scored against them. With ~robots, several robots' scans. Reads
// the parameters, converts messages, looks up tf, calls the core (online_evaluator.hpp), publishes.
#include <diagnostic_updater/diagnostic_updater.h>
#include <line_map_msgs/Evaluate.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <string>
#include <vector>

#include "eval_messages.hpp"
#include "line_map_eval/online/online_evaluator.hpp"
#include "linemap_ros/message_conversions.hpp"
#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/tf_wait_queue.hpp"
#include "linemap_ros/transport.hpp"
#include "linemap_ros/wall_diagnostics.hpp"

namespace line_map_eval
{
class LineMapEvalNodelet : public nodelet::Nodelet
{
 private:
  template <class M>
  using Wait = linemap_ros::TfWaitQueue<M>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    try
    {
      core_ = std::make_unique<OnlineEvaluator>(
          OnlineEvaluatorParams::fromParams(linemap_ros::loadParamSet(pnh)));
    }
    catch (const linemap::ParameterError& e)
    {
      NODELET_FATAL("line_map_eval: %s; the evaluator stays idle", e.what());
      return;
    }
    std::tie(map_frame_, base_frame_, odom_frame_) = linemap_ros::frameParams(pnh);
    tf_ = std::make_shared<tf2_ros::Buffer>(linemap_ros::tfCacheParam(pnh));
    tf_listener_ = std::make_shared<tf2_ros::TransformListener>(*tf_, true, linemap_ros::noDelay());
    quality_pub_ = nh.advertise<line_map_msgs::MapQuality>("map_quality", 1, true);
    grid_pub_ = nh.advertise<nav_msgs::OccupancyGrid>("lookup_table", 1, true);
    const std::uint32_t queue = linemap_ros::queueSizeParam(pnh);
    // With ~robots, every robot's scans and segments (their frames placed in the map by the fleet's merger);
    // each robot's trajectory is in its own map frame and names its own stamps: the scans stay where tf put
    // them.
    const auto robots = pnh.param("robots", std::vector<std::string>{});
    if (robots.empty()) subscribeRobot(nh, "", queue);
    for (const std::string& robot : robots) subscribeRobot(nh, robot + "/", queue);
    map_sub_ = nh.subscribe("line_map", 1, &LineMapEvalNodelet::onMap, this, linemap_ros::noDelay());
    // Every trajectory counts: its new nodes choose the stored scans (map_evaluator.hpp).
    if (robots.empty())
      trajectory_sub_ = nh.subscribe("optimized_trajectory", 10, &LineMapEvalNodelet::onTrajectory, this,
                                     linemap_ros::noDelay());
    evaluate_srv_ = pnh.advertiseService("evaluate", &LineMapEvalNodelet::onEvaluate, this);
    diagnostics_ = std::make_unique<linemap_ros::WallDiagnostics>(nh, pnh, "evaluator", this,
                                                                  &LineMapEvalNodelet::diagnose);
    // A map that arrived within min_period of the last evaluation is published by this timer.
    // The evaluation's parallel loops (structure classification) run on at most `threads` cores, so that
    // the extractor and the merger keep one on a small machine.
    if (pnh.hasParam("threads") || pnh.hasParam("stamp_tolerance"))
      NODELET_WARN(
          "line_map_eval: ~threads and ~stamp_tolerance are now ~eval/threads and ~eval/stamp_tolerance; "
          "the former are ignored");
    const int threads = pnh.param("eval/threads", 1);
    arena_ = std::make_unique<tbb::task_arena>(threads > 0 ? threads : tbb::info::default_concurrency());
    publish_timer_ = nh.createWallTimer(ros::WallDuration(std::max(0.05, pnh.param("min_period", 1.0))),
                                        [this](const ros::WallTimerEvent&) { publish(); });
  }

  /// One robot's scan and line_segments (`prefix`: its namespace and a slash, or nothing), held until tf
  /// places them (no time limit: the evaluator has no tf_timeout), each frame in order.
  void subscribeRobot(ros::NodeHandle& nh, const std::string& prefix, std::uint32_t queue)
  {
    scan_waits_.push_back(std::make_unique<Wait<sensor_msgs::LaserScan>>(
        *tf_, map_frame_, queue, ros::Duration(), nh, [this](const ScanEvent& e) { onScan(e.getMessage()); },
        [this](const ScanEvent& e, const std::string& why)
        {
          std::lock_guard<std::mutex> lock(mutex_);
          core_->countDroppedScan();
          NODELET_WARN_THROTTLE(10.0, "line_map_eval: scan at %.3f dropped: %s",
                                e.getConstMessage()->header.stamp.toSec(), why.c_str());
        }));
    segment_waits_.push_back(std::make_unique<Wait<line_map_msgs::LineSegmentArray>>(
        *tf_, map_frame_, queue, ros::Duration(), nh,
        [this](const SegmentsEvent& e) { onSegments(e.getMessage()); },
        [this](const SegmentsEvent&, const std::string& why)
        { NODELET_WARN_THROTTLE(10.0, "line_map_eval: segments dropped: %s", why.c_str()); }));
    scan_waits_.back()->subscribe(nh, prefix + "scan", queue,
                                  [this](const ScanEvent& e) { return arrive(e, OnlineEvaluator::kScans); });
    segment_waits_.back()->subscribe(nh, prefix + "line_segments", queue,
                                     [this](const SegmentsEvent& e)
                                     { return arrive(e, OnlineEvaluator::kSegments); });
  }

  /// The laser pose in `target` at `stamp` (identity in its own frame), after noting the time.
  std::optional<linemap::Pose2> lookup(const std::string& target, const std::string& frame,
                                       const ros::Time& stamp)
  {
    const auto pose = linemap_ros::lookupPose(*tf_, target, frame, stamp);
    if (!pose && target == map_frame_)
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: no valid tf %s -> %s at %.3f", target.c_str(),
                            frame.c_str(), stamp.toSec());
    return pose;
  }

  /// In arrival order, before the tf wait: time jumping back (rosbag play --loop) clears the tf
  /// buffer and the messages held for it, which belong to the old time line (held scans count as dropped).
  template <class M>
  bool arrive(const ros::MessageEvent<const M>& event, OnlineEvaluator::Stream stream)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!core_->observeTime(ros::Time::now().toSec(), event.getConstMessage()->header.stamp.toSec(), stream))
      return true;
    NODELET_WARN_THROTTLE(10.0, "line_map_eval: time jumped backwards (%s); tf buffer cleared",
                          core_->timeJumpCause().c_str());
    tf_->clear();
    for (const auto& wait : segment_waits_) wait->clear();
    for (const auto& wait : scan_waits_)
      for (std::size_t n = wait->clear(); n > 0; --n) core_->countDroppedScan();
    return true;
  }

  /// The laser's poses at the stamp.
  bool pose(const std_msgs::Header& header, linemap::Pose2& laser, std::optional<linemap::Pose2>& odom)
  {
    const std::string frame = linemap_ros::stripLeadingSlash(header.frame_id);
    const auto in_map = lookup(map_frame_, frame, header.stamp);
    if (!in_map) return false;
    laser = *in_map;
    if (!odom_frame_.empty() && odom_frame_ != map_frame_) odom = lookup(odom_frame_, frame, header.stamp);
    return true;
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan)
  {
    linemap::Pose2 laser;
    std::optional<linemap::Pose2> odom;
    if (!pose(scan->header, laser, odom)) return;
    laser_frame_ = linemap_ros::stripLeadingSlash(scan->header.frame_id);
    const ScanRanges ranges{scan->angle_min, scan->angle_increment, scan->range_min, scan->range_max,
                            scan->ranges};
    std::lock_guard<std::mutex> lock(mutex_);
    core_->addScan(scan->header.stamp.toSec(), ranges, laser, odom);
    if (core_->counters().rejected_scans > 0)
      NODELET_WARN_THROTTLE(10.0, "line_map_eval: scans with a zero or non-finite angle_increment ignored");
  }

  void onSegments(const line_map_msgs::LineSegmentArray::ConstPtr& msg)
  {
    linemap::Pose2 laser;
    std::optional<linemap::Pose2> odom;
    if (!pose(msg->header, laser, odom)) return;
    std::vector<linemap::Segment2> segments = linemap_ros::toSegments(*msg);
    std::lock_guard<std::mutex> lock(mutex_);
    core_->addSegments(msg->header.stamp.toSec(), std::move(segments), laser, odom);
  }

  void onTrajectory(const nav_msgs::Path::ConstPtr& path)
  {
    // The trajectory holds base poses; the stored frames are laser poses.
    std::optional<linemap::Pose2> mount =
        laser_frame_.empty() ? linemap::Pose2() : lookup(base_frame_, laser_frame_, {});
    if (!mount)
      NODELET_WARN_ONCE("line_map_eval: no %s -> %s transform; taking them as the same frame",
                        base_frame_.c_str(), laser_frame_.c_str());
    const auto poses = toLaserPoses(*path, mount.value_or(linemap::Pose2()));
    std::lock_guard<std::mutex> lock(mutex_);
    core_->addTrajectory(poses);
    publish(false);
  }

  void onMap(const line_map_msgs::LineMap::ConstPtr& map)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    core_->setMap(linemap_ros::toSegments(*map), map->header.stamp.toSec());
    publish(false);
  }

  bool onEvaluate(line_map_msgs::Evaluate::Request& req, line_map_msgs::Evaluate::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!req.use_given_map && !core_->hasMap())
    {
      res.success = false;
      res.message = "no line_map received yet";
      return true;
    }
    const std::vector<linemap::Segment2> map =
        req.use_given_map ? linemap_ros::toSegments(req.map) : core_->map();
    try
    {
      const MapMetrics metrics = arena_->execute([&] { return core_->evaluate(map); });
      res.quality = toMessage(metrics, map_frame_,
                              req.use_given_map ? req.map.header.stamp : ros::Time(core_->mapStamp()));
    }
    catch (const std::exception& e)
    {
      res.success = false;
      res.message = std::string("cannot evaluate the map: ") + e.what();
      return true;
    }
    res.success = true;
    res.message = "evaluated " + std::string(req.use_given_map ? "the given map (" : "") +
                  std::to_string(map.size()) + " map segments against " +
                  std::to_string(core_->evaluator().scanCount()) + " keyframe scans";
    return true;
  }

  void publish()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    publish(false);
  }

  /// The metrics when due (lock held).
  void publish(bool force)
  {
    const auto metrics =
        arena_->execute([&] { return core_->evaluateIfDue(ros::WallTime::now().toSec(), force); });
    if (!metrics) return;
    quality_pub_.publish(toMessage(*metrics, map_frame_, ros::Time(core_->mapStamp())));
    const LookupTable& table = core_->evaluator().table();
    if (!table.empty()) grid_pub_.publish(toGrid(table, map_frame_, ros::Time(core_->mapStamp())));
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!core_) return status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "bad parameters");
    status.summary(diagnostic_msgs::DiagnosticStatus::OK,
                   core_->hasMap() ? "evaluating" : "waiting for line_map");
    for (const auto& [key, value] : core_->diagnostics()) status.add(key, value);
  }

  std::unique_ptr<tbb::task_arena> arena_;
  std::mutex mutex_;  // guards core_
  std::unique_ptr<OnlineEvaluator> core_;
  std::string map_frame_, base_frame_, odom_frame_, laser_frame_;
  std::shared_ptr<tf2_ros::Buffer> tf_;
  using ScanEvent = ros::MessageEvent<const sensor_msgs::LaserScan>;
  using SegmentsEvent = ros::MessageEvent<const line_map_msgs::LineSegmentArray>;
  std::vector<std::unique_ptr<Wait<sensor_msgs::LaserScan>>> scan_waits_;
  std::vector<std::unique_ptr<Wait<line_map_msgs::LineSegmentArray>>> segment_waits_;
  std::shared_ptr<tf2_ros::TransformListener> tf_listener_;  // after the waits: its thread calls into them
  ros::Subscriber map_sub_, trajectory_sub_;
  ros::Publisher quality_pub_, grid_pub_;
  ros::ServiceServer evaluate_srv_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  ros::WallTimer publish_timer_;
};

}  // namespace line_map_eval

PLUGINLIB_EXPORT_CLASS(line_map_eval::LineMapEvalNodelet, nodelet::Nodelet)
