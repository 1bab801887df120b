// ROS wrapper of the online mapper (concurrent_mapper.hpp): line_segments (+ tf) and optimized_trajectory
// in; line_map, its markers and its occupancy grid (grid_publisher.hpp) out. With ~robots, one map of several
// robots: each robot's <robot>/line_segments and <robot>/optimized_trajectory in its own frames
// (<robot>/map ...), every robot but the first placed in the first's map by FleetPlacement, and the
// placements published as tf map -> <robot>/map.
#include <diagnostic_updater/diagnostic_updater.h>
#include <line_map_msgs/AppendMap.h>
#include <line_map_msgs/LoadMap.h>
#include <line_map_msgs/ResetMap.h>
#include <line_map_msgs/SaveMap.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "grid_publisher.hpp"
#include "line_map_merging/localization/fleet_placement.hpp"
#include "line_map_merging/online/concurrent_mapper.hpp"
#include "line_map_merging/online/recent_scans.hpp"
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
    robots_.clear();
    if (mapper_) autosave(INFINITY);  // the changes since the last autosave
  }

 private:
  using SegmentsEvent = ros::MessageEvent<const line_map_msgs::LineSegmentArray>;
  /// One robot's inputs (the only one's without ~robots): its segments wait for tf into its own map frame.
  struct Robot
  {
    std::size_t lane = 0;
    std::string name, map_frame, base_frame, odom_frame;
    std::unique_ptr<linemap_ros::TfWaitQueue<line_map_msgs::LineSegmentArray>> waiting;
    ros::Subscriber trajectory_sub;
    ros::Subscriber scan_sub;  ///< with the map-level lines: the scans the segments come from
    ScanPairing<ros::Time> pairing;
  };

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
    // A SLAM that lags the scans (a session search) publishes map -> odom for stamps this far back.
    tf_ = std::make_unique<tf2_ros::Buffer>(linemap_ros::tfCacheParam(pnh));
    const ros::TransportHints hints = linemap_ros::noDelay();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_, nh, true, hints);
    map_pub_ = nh.advertise<line_map_msgs::LineMap>("line_map", 1, true);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("line_map_markers", 1, true);
    const std::uint32_t queue = linemap_ros::queueSizeParam(pnh);
    addRobots(nh, pnh, queue);
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
  bool arrive(const SegmentsEvent& event, const Robot& robot)
  {
    const std_msgs::Header& header = event.getConstMessage()->header;
    const std::string frame = linemap_ros::stripLeadingSlash(header.frame_id);
    const bool known = !frame.empty() && (frame == robot.map_frame || tf_->_frameExists(frame));
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
    for (const auto& robot : robots_) mapper_->countDropped(robot->waiting->clear());
    newest_ = ros::Time();  // the old time line's stamps are ahead of every new one
    NODELET_WARN_THROTTLE(5.0,
                          "line_map_merging: time jumped back: tf buffer cleared, gate reset, map kept (%zu)",
                          counters().time_jumps);
  }

  /// The robots of ~robots (or the one robot in the map frame), and with two or more their placement.
  void addRobots(ros::NodeHandle& nh, ros::NodeHandle& pnh, std::uint32_t queue)
  {
    const auto names = pnh.param("robots", std::vector<std::string>{});
    if (names.empty()) addRobot(nh, "", queue);
    for (const std::string& name : names) addRobot(nh, name, queue);
    if (names.size() < 2) return;
    try
    {
      placement_ = std::make_unique<FleetPlacement>(
          LocalizerParams::fromParams(linemap_ros::loadParamSet(ros::NodeHandle(pnh, "placement"))),
          pnh.param("placement_confirm_path", 10.0));
    }
    catch (const std::exception& e)
    {
      NODELET_FATAL("line_map_merging: ~placement: %s", e.what());
      throw;
    }
    placements_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
    publishPlacements();
  }

  void addRobot(ros::NodeHandle& nh, const std::string& name, std::uint32_t queue)
  {
    auto robot = std::make_unique<Robot>();
    robot->lane = robots_.size();
    robot->name = name;
    const std::string prefix = name.empty() ? "" : name + "/";
    robot->map_frame = prefix + map_frame_;
    robot->base_frame = prefix + base_frame_;
    robot->odom_frame = prefix + odom_frame_;
    Robot& r = *robot;
    r.waiting = std::make_unique<linemap_ros::TfWaitQueue<line_map_msgs::LineSegmentArray>>(
        *tf_, r.map_frame, queue, ros::Duration(tf_timeout_), nh,
        [this, &r](const SegmentsEvent& e) { onSegments(e, r); },
        [this](const SegmentsEvent&, const std::string& why)
        {
          std::lock_guard<std::mutex> lock(mutex_);
          drop(why);
        });
    r.waiting->subscribe(nh, prefix + "line_segments", queue,
                         [this, &r](const SegmentsEvent& e) { return arrive(e, r); });
    if (mapper_->mapper().params().map_level.enabled)
      r.scan_sub = nh.subscribe<sensor_msgs::LaserScan>(
          prefix + "scan", queue,
          [this, &r](const sensor_msgs::LaserScan::ConstPtr& s)
          {
            std::lock_guard<std::mutex> lock(mutex_);
            r.pairing.addScan(s->header.stamp.toSec(), toKeyframeScan(*s));
            mergeReady(r);
          },
          ros::VoidConstPtr(), linemap_ros::noDelay());
    r.trajectory_sub = nh.subscribe<nav_msgs::Path>(
        prefix + "optimized_trajectory", 10,
        [this, &r](const nav_msgs::Path::ConstPtr& p) { onTrajectory(p, r); }, ros::VoidConstPtr(),
        linemap_ros::noDelay());
    robots_.push_back(std::move(robot));
  }

  void onSegments(const SegmentsEvent& event, Robot& robot)
  {
    const auto& msg = event.getConstMessage();
    const std::string frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
    bool mount_found = true;
    auto scan =
        toStampedScan(*tf_, *msg, frame, robot.map_frame, robot.base_frame, robot.odom_frame, mount_found);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!scan) return drop("no valid transform " + robot.map_frame + " -> " + frame);
    if (!mount_found)  // a bag without it lacks it for good: once is enough
      NODELET_WARN_ONCE("line_map_merging: no %s -> %s transform; taking them as the same frame",
                        robot.base_frame.c_str(), frame.c_str());
    newest_ = std::max(newest_, msg->header.stamp);
    scan->lane = robot.lane;
    robot.pairing.addSegments(std::move(*scan), msg->header.stamp);
    mergeReady(robot);
  }

  /// Merges the robot's segment sets whose scans came (or will not). Lock held.
  void mergeReady(Robot& robot)
  {
    for (const auto& [scan, stamp] : robot.pairing.ready())
    {
      const bool adjusted = mapper_->poll();
      const bool placed = place(scan, robot);
      if (mapper_->addScan(scan) == ScanOutcome::kKeyframe || adjusted || placed) publish(stamp);
    }
  }

  /// A scan of a robot not placed yet is looked for in the fleet's map; whether it placed the robot. Lock
  /// held.
  bool place(const StampedScan& scan, const Robot& robot)
  {
    if (!placement_ || mapper_->mapper().lanePlacement(robot.lane)) return false;
    if (mapper_->mapper().revision() != searched_revision_)
    {
      std::vector<linemap::Segment2> map;
      for (const MapSegment& s : merger().map()) map.push_back(s.segment);
      placement_->setMap(map);
      searched_revision_ = mapper_->mapper().revision();
    }
    const auto found = placement_->addScan(robot.lane, scan.stamp, scan.segments, scan.laser, scan.mount);
    if (!found) return false;
    NODELET_INFO("line_map_merging: robot '%s' placed in the map after %zu scans at (%.2f, %.2f, %.3f)",
                 robot.name.c_str(), placement_->searched(robot.lane), found->x, found->y, found->theta);
    const bool changed = mapper_->placeLane(robot.lane, *found);
    publishPlacements();
    return changed;
  }

  /// tf map -> <robot>/map of every placed robot (with ~robots). Lock held, or in onInit.
  void publishPlacements()
  {
    if (!placement_) return;
    std::vector<geometry_msgs::TransformStamped> placed;
    for (const auto& robot : robots_)
      if (const auto pose = robot->lane == 0 ? linemap::Pose2() : placement_->placement(robot->lane))
      {
        geometry_msgs::TransformStamped t;
        t.header.stamp = ros::Time::now();
        t.header.frame_id = map_frame_;
        t.child_frame_id = robot->map_frame;
        t.transform.translation.x = pose->x;
        t.transform.translation.y = pose->y;
        t.transform.rotation.z = std::sin(0.5 * pose->theta);
        t.transform.rotation.w = std::cos(0.5 * pose->theta);
        placed.push_back(t);
      }
    placements_->sendTransform(placed);
  }

  void onTrajectory(const nav_msgs::Path::ConstPtr& path, const Robot& robot)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::size_t bad = 0;
    const auto nodes = toNodes(*path, robot.map_frame, bad);
    if (!nodes)
    {
      mapper_->countIgnoredTrajectory();
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: optimized_trajectory in frame '%s', not '%s'; ignored",
                            path->header.frame_id.c_str(), robot.map_frame.c_str());
      return;
    }
    mapper_->countBadPoses(bad);
    if (bad > 0)
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: %zu invalid optimized_trajectory poses ignored", bad);
    newest_ = std::max(newest_, path->header.stamp.isZero() ? ros::Time::now() : path->header.stamp);
    if (mapper_->addTrajectory(*nodes, robot.lane)) publish(newest_);
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
    if (placement_)
      for (const auto& [key, value] : placement_->diagnostics()) stat.add(key, value);
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
  std::vector<std::unique_ptr<Robot>> robots_;
  std::unique_ptr<FleetPlacement> placement_;  ///< with two robots or more
  std::uint64_t searched_revision_ = ~std::uint64_t{0};
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> placements_;
  ros::Publisher map_pub_, marker_pub_;
  ros::ServiceServer save_srv_, load_srv_, append_srv_, reset_srv_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  ros::WallTimer autosave_timer_, poll_timer_;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::LineMapMergingNodelet, nodelet::Nodelet)
