// line_map_merging/SlamNodelet: a thin ROS wrapper of LaserSlam (slam/laser_slam.hpp). Subscribes to
// `scan`, takes odometry from tf odom -> base at the scan's stamp (optional), publishes tf
// map -> odom (and, laser only, odom -> base from the front end), the optimised keyframe poses on
// `optimized_trajectory` (nav_msgs/Path, each pose stamped with its scan's stamp) and diagnostics.
// Services ~save_session and ~load_session write and read a session file (slam/session_file.hpp): the
// SLAM's graph with the merging nodelet's map (its save_map/load_map services, parameter `merger`).
// ~session (or ~load_session with start SEARCH or GIVEN_POSE) continues a session from an unknown or given
// start (localization/session_continuation.hpp): the scans search the saved map until the robot is found
// (or `initialpose` places it), then the SLAM maps on in it and the merger gets its map.
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <line_map_msgs/AppendMap.h>
#include <line_map_msgs/LoadMap.h>
#include <line_map_msgs/LoadSession.h>
#include <line_map_msgs/SaveMap.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <thread>

#include "line_map_merging/localization/session_continuation.hpp"
#include "line_map_merging/slam/laser_slam.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "linemap/atomic_file.hpp"
#include "linemap_ros/message_conversions.hpp"
#include "linemap_ros/param_loader.hpp"
#include "linemap_ros/tf_wait_queue.hpp"
#include "linemap_ros/transport.hpp"
#include "linemap_ros/wall_diagnostics.hpp"

namespace line_map_merging
{
class SlamNodelet : public nodelet::Nodelet
{
 public:
  ~SlamNodelet() override
  {
    listener_.reset();  // its thread calls into the wait
    waiting_.reset();
    if (merger_loader_.joinable()) merger_loader_.join();
  }

 private:
  using ScanEvent = ros::MessageEvent<const sensor_msgs::LaserScan>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::tie(map_frame_, base_frame_, odom_frame_) = linemap_ros::frameParams(pnh);
    use_odometry_ = pnh.param("use_odometry", true);
    const double tf_timeout = pnh.param("tf_timeout", 0.1);
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
    buffer_ = std::make_unique<tf2_ros::Buffer>(linemap_ros::tfCacheParam(pnh));  // the SLAM may lag the bag
    listener_ = std::make_unique<tf2_ros::TransformListener>(*buffer_, nh, true, linemap_ros::noDelay());
    path_pub_ = nh.advertise<nav_msgs::Path>("optimized_trajectory", 1, true);
    // A scan waits up to ~tf_timeout for the tf it needs (odom -> base -> laser, or base -> laser
    // without odometry); then it is matched with what tf has (see onScan).
    const std::uint32_t queue = linemap_ros::queueSizeParam(pnh);
    waiting_ = std::make_unique<linemap_ros::TfWaitQueue<sensor_msgs::LaserScan>>(
        *buffer_, use_odometry_ ? odom_frame_ : base_frame_, queue, ros::Duration(tf_timeout), nh,
        [this](const ScanEvent& e) { onScan(e); },
        [this](const ScanEvent& e, const std::string&) { onScan(e); });
    waiting_->subscribe(nh, "scan", queue, [this](const ScanEvent& e) { return arrive(e); });
    diagnostics_ =
        std::make_unique<linemap_ros::WallDiagnostics>(nh, pnh, "laser slam", this, &SlamNodelet::diagnose);
    merger_ = pnh.param<std::string>("merger", "line_map_merging");
    save_srv_ = pnh.advertiseService("save_session", &SlamNodelet::onSaveSession, this);
    load_srv_ = pnh.advertiseService("load_session", &SlamNodelet::onLoadSession, this);
    initial_sub_ = nh.subscribe("initialpose", 1, &SlamNodelet::onInitialPose, this);
    continueSession(pnh);
  }

  /// ~session: the scans look for the robot in that session's map before the SLAM maps on in it.
  void continueSession(ros::NodeHandle& pnh)
  {
    const std::string path = pnh.param<std::string>("session", "");
    try
    {
      const int search = pnh.param("session_search_scans", 400);
      if (search < 1) throw std::invalid_argument("~session_search_scans must be >= 1");
      search_scans_ = static_cast<std::size_t>(search);
      localizer_ =
          LocalizerParams::fromParams(linemap_ros::loadParamSet(ros::NodeHandle(pnh, "localization")));
      if (path.empty()) return;
      std::optional<linemap::Pose2> start;
      std::vector<double> given;
      if (pnh.getParam("session_start", given))
      {
        if (given.size() != 3)
          throw std::invalid_argument("~session_start must be [x, y, theta], got " +
                                      std::to_string(given.size()) + " numbers");
        start = linemap::Pose2(given[0], given[1], given[2]);
      }
      std::lock_guard<std::mutex> lock(mutex_);
      const std::string summary = beginContinuation(path, readSessionFile(path), start);
      NODELET_INFO("slam: continuing the session %s: %s", path.c_str(), summary.c_str());
    }
    catch (const std::exception& e)
    {
      NODELET_ERROR("slam: cannot continue the session (%s); mapping a new map", e.what());
    }
  }

  /// The scans from now on look for the robot in `session` (or place it at `start`) before the SLAM maps on
  /// in it; until then the SLAM keeps what it has. Returns the continuation's summary. Call under the mutex.
  std::string beginContinuation(const std::string& path, Session session,
                                const std::optional<linemap::Pose2>& start)
  {
    continuation_ =
        std::make_unique<SessionContinuation>(std::move(session.slam), localizer_, search_scans_, start);
    session_path_ = path;
    session_map_ = std::move(session.line_map);
    return continuation_->summary();
  }

  /// RViz' 2D Pose Estimate while the robot is looked for in a session: it is there at the next scan.
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& p = msg->pose.pose.position;
    const auto start = linemap_ros::toPose2(p.x, p.y, msg->pose.pose.orientation);
    if (!start)
    {
      NODELET_WARN(
          "slam: initialpose ignored: its position is not finite or its orientation not a unit quaternion");
      return;
    }
    if (linemap_ros::stripLeadingSlash(msg->header.frame_id) != map_frame_)
    {
      NODELET_WARN("slam: initialpose ignored: it is in frame '%s', not '%s'", msg->header.frame_id.c_str(),
                   map_frame_.c_str());
      return;
    }
    if (!continuation_ || !continuation_->giveStart(*start))
      NODELET_WARN("slam: initialpose ignored: no session is being looked for (see ~load_session)");
    else
      NODELET_INFO("slam: initialpose: the next scan continues the session there");
  }

  /// While the robot is looked for in the saved session: true when the SLAM is to take the scan.
  bool placedInSession(const SlamScan& scan, const linemap::Pose2& mount)
  {
    if (!continuation_ || continuation_->state() != SessionContinuation::State::kSearching) return true;
    const auto state = continuation_->addScan(scan, mount.translation(), *slam_);
    if (state == SessionContinuation::State::kSearching) return false;
    for (const SlamScan& held : continuation_->takeHeld()) addToSlam(held, mount);  // from the search's start
    if (state == SessionContinuation::State::kPlaced)
    {
      NODELET_INFO("slam: %s", continuation_->summary().c_str());
      if (!session_map_.empty())
        callMergerLater([this, path = session_path_, text = std::move(session_map_)]
                        { return loadMergerMap(path, text); });
    }
    else
      NODELET_WARN("slam: %s", continuation_->summary().c_str());
    return true;
  }

  /// The SLAM takes the scan; a run that gave its session up looks for itself in it meanwhile, and joins it
  /// when found: the graph here, the saved line map into the merger's (append_map, at the place found).
  SlamOutcome addToSlam(const SlamScan& scan, const linemap::Pose2& mount)
  {
    const SlamOutcome outcome = slam_->addScan(scan);
    if (!continuation_ || continuation_->state() != SessionContinuation::State::kGaveUp ||
        continuation_->afterScan(scan, mount.translation(), *slam_) != SessionContinuation::State::kJoined)
      return outcome;
    NODELET_INFO("slam: %s", continuation_->summary().c_str());
    if (!session_map_.empty())
      callMergerLater([this, path = session_path_, text = std::move(session_map_),
                       placed = *continuation_->joinedAt()] { return appendMergerMap(path, text, placed); });
    return outcome;
  }

  /// A call to the merger's services, which wait for the merger, on a thread of its own (not in the scan
  /// callback); `call` returns "; what happened".
  void callMergerLater(std::function<std::string()> call)
  {
    if (merger_loader_.joinable()) merger_loader_.join();  // an earlier session's, long done
    merger_loader_ =
        std::thread([this, call = std::move(call)] { NODELET_INFO("slam: %s", call().substr(2).c_str()); });
  }

  /// The merging nodelet's map through a file beside `path`: its text (empty: no merger answered).
  std::string mergerMap(const std::string& path, std::string& note)
  {
    line_map_msgs::SaveMap srv;
    srv.request.path = path + ".map.tmp";
    if (merger_.empty() || !ros::service::waitForService(merger_ + "/save_map", ros::Duration(1.0)) ||
        !ros::service::call(merger_ + "/save_map", srv) || !srv.response.success)
    {
      note = "; no line map (merger '" + merger_ + "' " +
             (srv.response.message.empty() ? "did not answer" : srv.response.message) + ")";
      return {};
    }
    std::string text = linemap::readWholeFile(srv.request.path, "map file");
    std::remove(srv.request.path.c_str());
    return text;
  }

  bool onSaveSession(line_map_msgs::SaveMap::Request& req, line_map_msgs::SaveMap::Response& res)
  {
    Session session;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      session.slam = slam_->session();
    }
    std::string note;
    try
    {
      session.line_map = mergerMap(req.path, note);  // outside the lock: scans go on meanwhile
      writeSessionFile(req.path, session);
      res.success = true;
      res.message =
          "saved " + std::to_string(session.slam.keyframes.size()) + " keyframes to " + req.path + note;
    }
    catch (const std::exception& e)
    {
      res.message = e.what();
    }
    return true;
  }

  bool onLoadSession(line_map_msgs::LoadSession::Request& req, line_map_msgs::LoadSession::Response& res)
  {
    using Request = line_map_msgs::LoadSession::Request;
    try
    {
      if (req.start > Request::NEWEST_KEYFRAME)
        throw std::invalid_argument("start must be SEARCH (0), GIVEN_POSE (1) or NEWEST_KEYFRAME (2), got " +
                                    std::to_string(req.start));
      Session session = readSessionFile(req.path);  // everything checked before anything changes
      const std::string loaded =
          "loaded " + std::to_string(session.slam.keyframes.size()) + " keyframes from ";
      if (req.start != Request::NEWEST_KEYFRAME)
      {
        std::optional<linemap::Pose2> start;
        if (req.start == Request::GIVEN_POSE)
        {
          if (!std::isfinite(req.pose.x) || !std::isfinite(req.pose.y) || !std::isfinite(req.pose.theta))
            throw std::invalid_argument("pose must be finite for start GIVEN_POSE");
          start = linemap::Pose2(req.pose.x, req.pose.y, req.pose.theta);
        }
        std::lock_guard<std::mutex> lock(mutex_);
        res.message = loaded + req.path + ": " + beginContinuation(req.path, std::move(session), start);
        res.success = true;
        return true;
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        slam_->restore(session.slam);
        continuation_.reset();  // an earlier session's search, if any, is over
        session_map_.clear();
        publishPath(ros::Time::now());
      }
      std::string note;
      if (!session.line_map.empty()) note = loadMergerMap(req.path, session.line_map);
      res.success = true;
      res.message = loaded + req.path + note;
    }
    catch (const std::exception& e)
    {
      res.message = e.what();  // the running SLAM is kept
    }
    return true;
  }

  std::string loadMergerMap(const std::string& path, const std::string& text)
  {
    line_map_msgs::LoadMap srv;
    srv.request.path = path + ".map.tmp";
    linemap::writeFileAtomically(srv.request.path, text, "map file");
    const bool done = !merger_.empty() &&
                      ros::service::waitForService(merger_ + "/load_map", ros::Duration(1.0)) &&
                      ros::service::call(merger_ + "/load_map", srv) && srv.response.success;
    std::remove(srv.request.path.c_str());
    return done ? "; the line map to " + merger_
                : "; the line map not loaded (merger '" + merger_ + "': " + srv.response.message + ")";
  }

  std::string appendMergerMap(const std::string& path, const std::string& text, const linemap::Pose2& placed)
  {
    line_map_msgs::AppendMap srv;
    srv.request.path = path + ".map.tmp";
    srv.request.pose.x = placed.x;
    srv.request.pose.y = placed.y;
    srv.request.pose.theta = placed.theta;
    linemap::writeFileAtomically(srv.request.path, text, "map file");
    const bool done = !merger_.empty() &&
                      ros::service::waitForService(merger_ + "/append_map", ros::Duration(1.0)) &&
                      ros::service::call(merger_ + "/append_map", srv) && srv.response.success;
    std::remove(srv.request.path.c_str());
    return done ? "; the saved line map merged into " + merger_ + "'s"
                : "; the saved line map not merged (merger '" + merger_ + "': " + srv.response.message + ")";
  }

  /// Before the tf wait (false: turned away): a zero stamp would be posed at the latest transform;
  /// a replay from the start makes a new trajectory on a clean tf buffer.
  bool arrive(const ScanEvent& event)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time stamp = event.getConstMessage()->header.stamp;
    if (stamp.isZero())
    {
      slam_->countZeroStamp();
      NODELET_WARN_THROTTLE(10.0, "slam: scan stamped zero dropped");
      return false;
    }
    if (slam_->restartOnTimeJump(stamp.toSec()))
    {
      NODELET_WARN("slam: time jumped back (a scan stamped %.3f s): new trajectory", stamp.toSec());
      buffer_->clear();
      for (std::size_t n = waiting_->clear(); n > 0; --n) slam_->countDropped();  // the old time line's
      last_publish_ = 0.0;
    }
    return true;
  }

  /// A scan tf can place, or one that waited for it in vain: without base -> laser it is dropped
  /// (unless the laser is the base), without odometry it is matched without.
  void onScan(const ScanEvent& event)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& msg = event.getConstMessage();
    const ros::Time stamp = msg->header.stamp;
    const std::string laser_frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
    std::string error;
    std::optional<linemap::Pose2> mount = lookup(base_frame_, laser_frame, stamp, error);
    if (!mount && (base_frame_ == laser_frame || !use_odometry_)) mount = linemap::Pose2();  // laser = base
    if (!mount)
    {
      slam_->countDropped();
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
    if (!placedInSession(scan, *mount)) return;
    if (addToSlam(scan, *mount) == SlamOutcome::kRejected) return;
    publishTf(stamp, scan.odom);
    if (slam_->graphOptimized() || (slam_->keyframeAdded() && publish_period_ > 0.0 &&
                                    ros::WallTime::now().toSec() - last_publish_ >= publish_period_))
      publishPath(stamp);
  }

  /// tf at the stamp, as the buffer has it now (the wait queue waited).
  std::optional<linemap::Pose2> lookup(const std::string& target, const std::string& source,
                                       const ros::Time& stamp, std::string& error)
  {
    try
    {
      const auto t = buffer_->lookupTransform(target, source, stamp).transform;
      return linemap_ros::toPose2(t.translation.x, t.translation.y, t.rotation);
    }
    catch (const tf2::TransformException& e)
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
        linemap_ros::toTransform(map_base * odom_base.inverse(), map_frame_, odom_frame_, stamp)};
    if (!use_odometry_) out.push_back(linemap_ros::toTransform(odom_base, odom_frame_, base_frame_, stamp));
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
      ps.pose = linemap_ros::toPoseMsg(p);
      path.poses.push_back(ps);
    }
    path_pub_.publish(path);
    slam_->countPublished();
    last_publish_ = ros::WallTime::now().toSec();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool dropped = slam_->counters().dropped > 0;
    const std::string trouble = slam_->trouble();
    if (!trouble.empty())
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, trouble);
    else if (continuation_ && continuation_->state() == SessionContinuation::State::kGaveUp)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, continuation_->summary());
    else
      stat.summary(dropped ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                   dropped ? "scans dropped (no base -> laser tf)" : "ok");
    if (continuation_) stat.add("session " + session_path_, continuation_->summary());
    for (const auto& [key, value] : slam_->diagnostics()) stat.add(key, value);
  }

  std::mutex mutex_;
  std::unique_ptr<LaserSlam> slam_;
  std::unique_ptr<tf2_ros::Buffer> buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
  std::unique_ptr<linemap_ros::TfWaitQueue<sensor_msgs::LaserScan>> waiting_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Publisher path_pub_;
  ros::ServiceServer save_srv_, load_srv_;
  ros::Subscriber initial_sub_;
  LocalizerParams localizer_;  ///< ~localization/*: the search for the robot in a session
  std::size_t search_scans_ = 400;
  std::string merger_;
  std::unique_ptr<SessionContinuation> continuation_;  ///< ~session, ~load_session: null without one
  std::string session_path_, session_map_;
  std::thread merger_loader_;
  std::unique_ptr<linemap_ros::WallDiagnostics> diagnostics_;
  std::string map_frame_, odom_frame_, base_frame_;
  bool use_odometry_ = true;
  double publish_period_ = 0.0, last_publish_ = 0.0;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::SlamNodelet, nodelet::Nodelet)
