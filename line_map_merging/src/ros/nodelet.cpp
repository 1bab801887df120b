// ROS wrapper of the online mapper (concurrent_mapper.hpp): line_segments (+ tf) and optimized_trajectory
// in; line_map, its markers and its occupancy grid (grid_publisher.hpp) out.
#include <diagnostic_updater/diagnostic_updater.h>
#include <line_map_msgs/AppendMap.h>
#include <line_map_msgs/LoadMap.h>
#include <line_map_msgs/ResetMap.h>
#include <line_map_msgs/SaveMap.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "grid_publisher.hpp"
#include "line_map_merging/online/concurrent_mapper.hpp"
#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/tf_wait_queue.hpp"
#include "linemap_ros/transport.hpp"
#include "linemap_ros/wall_diagnostics.hpp"
#include "map_messages.hpp"

namespace line_map_merging
{
class LineMapMergingNodelet : public nodelet::Nodelet
{
 public:
  ~LineMapMergingNodelet() override
  {
    autosave_timer_.stop();
    poll_timer_.stop();
    if (grid_) grid_->stop();
    tf_listener_.reset();  // its thread calls into the wait
    waiting_.reset();
    if (mapper_) autosave(INFINITY);  // the changes since the last autosave
  }

 private:
  using SegmentsEvent = ros::MessageEvent<const line_map_msgs::LineSegmentArray>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::tie(map_frame_, base_frame_, odom_frame_) = linemap_ros::frameParams(pnh);
    tf_timeout_ = pnh.param("tf_timeout", 0.5);
    publish_labels_ = pnh.param("publish_labels", false);
    marker_width_ = pnh.param("marker_width", 0.03);
    autosave_path_ = pnh.param<std::string>("autosave_path", "");
    try
    {
      mapper_ = ConcurrentMapper::fromParams(pnh.param<std::string>("method", "cae"),
                                             linemap_ros::loadParamSet(pnh));
      grid_ = std::make_unique<GridPublisher>(
          nh, getMTNodeHandle(), pnh, map_frame_, mutex_, [this]() -> const Merger& { return merger(); },
          newest_);
    }
    catch (const std::exception& e)
    {
      NODELET_FATAL("line_map_merging: %s", e.what());
      throw;
    }
    tf_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(120.0));
    const ros::TransportHints hints = linemap_ros::noDelay();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_, nh, true, hints);
    map_pub_ = nh.advertise<line_map_msgs::LineMap>("line_map", 1, true);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("line_map_markers", 1, true);
    const int queue = std::max(1, pnh.param("queue_size", 1000));
    waiting_ = std::make_unique<linemap_ros::TfWaitQueue<line_map_msgs::LineSegmentArray>>(
        *tf_, map_frame_, queue, ros::Duration(tf_timeout_), nh,
        [this](const SegmentsEvent& e) { onSegments(e); },
        [this](const SegmentsEvent&, const std::string& why)
        {
          std::lock_guard<std::mutex> lock(mutex_);
          drop(why);
        });
    waiting_->subscribe(nh, "line_segments", queue, [this](const SegmentsEvent& e) { return arrive(e); });
    trajectory_sub_ =
        nh.subscribe("optimized_trajectory", 10, &LineMapMergingNodelet::onTrajectory, this, hints);
    advertiseServices(pnh);
    const double period = mapper_->mapper().params().autosave_period;
    if (period > 0.0 && !autosave_path_.empty())
      autosave_timer_ = nh.createWallTimer(ros::WallDuration(period), [this](const ros::WallTimerEvent&)
                                           { autosave(ros::WallTime::now().toSec()); });
    else if (period > 0.0 || !autosave_path_.empty())
      NODELET_WARN("line_map_merging: autosave needs both ~autosave_period > 0 and ~autosave_path; off");
    // The clock also jumps back without scans: looked for before each report.
    diagnostics_ = std::make_unique<linemap_ros::WallDiagnostics>(
        nh, pnh, "line map merging", this, &LineMapMergingNodelet::diagnose,
        [this]
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (mapper_->observeTime(ros::Time::now().toSec(), 0.0)) forgetTimeLine();
        });
    // A finished adjustment replaces the map at the next scan, or here when none comes.
    poll_timer_ = nh.createWallTimer(ros::WallDuration(0.02), &LineMapMergingNodelet::poll, this);
    NODELET_INFO("line_map_merging: method '%s' in frame '%s'", merger().name(), map_frame_.c_str());
  }

  /// Segments turned away; counted here unless the core has (`counted`). Lock held.
  void drop(const std::string& why, bool counted = false)
  {
    if (!counted) mapper_->countDropped();
    NODELET_WARN_THROTTLE(5.0, "line_map_merging: segments dropped: %s (%zu so far, %zu stamped zero)",
                          why.c_str(), counters().dropped, counters().zero_stamps);
  }

  /// Before the tf wait (false: turned away, ConcurrentMapper::admit). The map frame needs no tf.
  bool arrive(const SegmentsEvent& event)
  {
    const std_msgs::Header& header = event.getConstMessage()->header;
    const std::string frame = linemap_ros::stripLeadingSlash(header.frame_id);
    const bool known = !frame.empty() && (frame == map_frame_ || tf_->_frameExists(frame));
    std::lock_guard<std::mutex> lock(mutex_);
    bool jumped = false;
    const std::string why = mapper_->admit(ros::Time::now().toSec(), header.stamp.toSec(), known, jumped);
    if (jumped) forgetTimeLine();
    if (!why.empty()) drop(why + " ('" + header.frame_id + "')", true);
    return why.empty();
  }

  /// Time jumped back (rosbag play --loop): the tf buffer and the held segment sets are of the old
  /// time line. Lock held.
  void forgetTimeLine()
  {
    tf_->clear();
    mapper_->countDropped(waiting_->clear());
    newest_ = ros::Time();  // the old time line's stamps are ahead of every new one
    NODELET_WARN_THROTTLE(5.0,
                          "line_map_merging: time jumped back: tf buffer cleared, gate reset, map kept (%zu)",
                          counters().time_jumps);
  }

  void onSegments(const SegmentsEvent& event)
  {
    const auto& msg = event.getConstMessage();
    const std::string frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
    bool mount_found = true;
    const auto scan = toStampedScan(*tf_, *msg, frame, map_frame_, base_frame_, odom_frame_, mount_found);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!scan) return drop("no valid transform " + map_frame_ + " -> " + frame);
    if (!mount_found)  // a bag without it lacks it for good: once is enough
      NODELET_WARN_ONCE("line_map_merging: no %s -> %s transform; taking them as the same frame",
                        base_frame_.c_str(), frame.c_str());
    newest_ = std::max(newest_, msg->header.stamp);
    const bool adjusted = mapper_->poll();
    if (mapper_->addScan(*scan) == ScanOutcome::kKeyframe || adjusted) publish(msg->header.stamp);
  }

  void onTrajectory(const nav_msgs::Path::ConstPtr& path)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::size_t bad = 0;
    const auto nodes = toNodes(*path, map_frame_, bad);
    if (!nodes)
    {
      mapper_->countIgnoredTrajectory();
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: optimized_trajectory in frame '%s', not '%s'; ignored",
                            path->header.frame_id.c_str(), map_frame_.c_str());
      return;
    }
    mapper_->countBadPoses(bad);
    if (bad > 0)
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: %zu invalid optimized_trajectory poses ignored", bad);
    newest_ = std::max(newest_, path->header.stamp.isZero() ? ros::Time::now() : path->header.stamp);
    if (mapper_->addTrajectory(*nodes)) publish(newest_);
  }

  void autosave(double now)  // infinite `now`: the last save, at shutdown
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (autosave_path_.empty()) return;
    const std::string error = mapper_->autosave(autosave_path_, now, !std::isfinite(now));
    if (!error.empty()) NODELET_WARN_THROTTLE(30.0, "line_map_merging: autosave failed: %s", error.c_str());
  }

  void advertiseServices(ros::NodeHandle& pnh)
  {
    save_srv_ = pnh.advertiseService("save_map", &LineMapMergingNodelet::onSave, this);
    load_srv_ = pnh.advertiseService("load_map", &LineMapMergingNodelet::onLoad, this);
    append_srv_ = pnh.advertiseService("append_map", &LineMapMergingNodelet::onAppend, this);
    reset_srv_ = pnh.advertiseService("reset_map", &LineMapMergingNodelet::onReset, this);
  }

  bool onSave(line_map_msgs::SaveMap::Request& req, line_map_msgs::SaveMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (mapper_->finish()) publish(newest_);  // the newest map, adjusted
    return answer(res, mapper_->saveMap(req.path));
  }

  bool onLoad(line_map_msgs::LoadMap::Request& req, line_map_msgs::LoadMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const MapCommandAnswer loaded = mapper_->loadMap(req.path);
    return answer(res, loaded) && (loaded.success ? publish(ros::Time::now()) : true);
  }

  bool onAppend(line_map_msgs::AppendMap::Request& req, line_map_msgs::AppendMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const MapCommandAnswer added =
        mapper_->appendMap(req.path, linemap::Pose2(req.pose.x, req.pose.y, req.pose.theta));
    return answer(res, added) && (added.success ? publish(ros::Time::now()) : true);
  }

  bool onReset(line_map_msgs::ResetMap::Request&, line_map_msgs::ResetMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    mapper_->reset();
    return answer(res, {true, "map cleared"}) && publish(ros::Time::now());
  }

  bool publish(const ros::Time& stamp)  // lock held
  {
    grid_->mapChanged();
    const line_map_msgs::LineMap msg = toLineMap(merger(), map_frame_, stamp);
    map_pub_.publish(msg);
    if (marker_pub_.getNumSubscribers() > 0)
      marker_pub_.publish(toMarkers(msg, marker_width_, publish_labels_));
    return true;
  }

  void poll(const ros::WallTimerEvent&)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (mapper_->poll()) publish(newest_);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool dropped = counters().dropped > 0;
    stat.summary(dropped ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                 dropped ? "scans dropped (no transform)" : "merging");
    for (const auto& [key, value] : mapper_->diagnostics()) stat.add(key, value);
    for (const auto& [key, value] : grid_->diagnostics()) stat.add(key, value);
  }

  const Merger& merger() const { return mapper_->mapper().merger(); }
  const MapperCounters& counters() const { return mapper_->mapper().counters(); }

  std::mutex mutex_;  // guards mapper_, newest_ and grid_
  std::unique_ptr<ConcurrentMapper> mapper_;
  ros::Time newest_;  // the newest input stamp: a map adjusted in the background is stamped with it
  std::string map_frame_, base_frame_, odom_frame_, autosave_path_;
  double tf_timeout_ = 0.5, marker_width_ = 0.03;
  bool publish_labels_ = false;
  std::unique_ptr<GridPublisher> grid_;
  std::unique_ptr<tf2_ros::Buffer> tf_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<linemap_ros::TfWaitQueue<line_map_msgs::LineSegmentArray>> waiting_;
  ros::Subscriber trajectory_sub_;
  ros::Publisher map_pub_, marker_pub_;
  ros::ServiceServer save_srv_, load_srv_, append_srv_, reset_srv_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  ros::WallTimer autosave_timer_, poll_timer_;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::LineMapMergingNodelet, nodelet::Nodelet)
