// ROS wrapper of the line map mergers: line_segments (+ tf) -> keyframe gate -> merger -> line_map,
// and optimized_trajectory -> map adjustment. All merging logic lives in the ROS-free core.
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/TransformStamped.h>
#include <line_map_msgs/LineMap.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <line_map_msgs/LoadMap.h>
#include <line_map_msgs/ResetMap.h>
#include <line_map_msgs/SaveMap.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <string>
#include <unordered_set>

#include "line_extraction/ros/param_loader.hpp"
#include "line_map_merging/keyframe_gate.hpp"
#include "line_map_merging/merger.hpp"
#include "line_map_merging/trajectory_correction.hpp"

namespace line_map_merging
{
namespace
{
/// Yaw of a quaternion, or nothing when it is not finite or not normalised.
bool yawOf(const geometry_msgs::Quaternion& q, double& yaw)
{
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3) return false;
  yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  return true;
}

bool poseOf(const geometry_msgs::Transform& t, linemap::Pose2& pose)
{
  double yaw = 0.0;
  if (!yawOf(t.rotation, yaw) || !std::isfinite(t.translation.x) || !std::isfinite(t.translation.y))
    return false;
  pose = linemap::Pose2(t.translation.x, t.translation.y, yaw);
  return true;
}

double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

class LineMapMergingNodelet : public nodelet::Nodelet
{
 public:
  ~LineMapMergingNodelet() override
  {
    autosave_timer_.stop();
    if (filter_) filter_->clear();
    // The last changes since the previous autosave (shutdown of the manager, or unload).
    if (merger_)
    {
      std::lock_guard<std::mutex> lock(mutex_);
      autosave();
    }
  }

 private:
  using SegmentsFilter = tf2_ros::MessageFilter<line_map_msgs::LineSegmentArray>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    method_ = pnh.param<std::string>("method", "cae");
    map_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("map_frame", "map"));
    base_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("base_frame", "base_link"));
    // Keyframe poses in the odometry frame: trajectory corrections are interpolated there, across
    // the jumps of map -> odom (empty: in the map frame).
    odom_frame_ = linemap_ros::stripLeadingSlash(pnh.param<std::string>("odom_frame", "odom"));
    stamp_tolerance_ = pnh.param("stamp_tolerance", 0.01);
    tf_timeout_ = pnh.param("tf_timeout", 0.5);
    publish_labels_ = pnh.param("publish_labels", false);
    marker_width_ = pnh.param("marker_width", 0.03);
    const int queue_size = std::max(1, pnh.param("queue_size", 100));
    autosave_period_ = pnh.param("autosave_period", 0.0);
    autosave_path_ = pnh.param<std::string>("autosave_path", "");
    time_jump_tolerance_ = std::max(0.0, pnh.param("time_jump_tolerance", 1.0));

    const linemap::ParamSet params = linemap_ros::loadParamSet(pnh);
    try
    {
      merger_ = makeMerger(method_, params);
      gate_ = KeyframeGate(KeyframeGateParams::fromParams(params));
    }
    catch (const std::exception& e)
    {
      NODELET_FATAL("line_map_merging: %s", e.what());
      throw;
    }

    tf_buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(120.0));
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);

    map_pub_ = nh.advertise<line_map_msgs::LineMap>("line_map", 1, true);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("line_map_markers", 1, true);
    filter_ = std::make_unique<SegmentsFilter>(*tf_buffer_, map_frame_, queue_size, nh);
    filter_->registerCallback(boost::bind(&LineMapMergingNodelet::onSegments, this, boost::placeholders::_1));
    filter_->registerFailureCallback(boost::bind(&LineMapMergingNodelet::onTfFailure, this,
                                                 boost::placeholders::_1, boost::placeholders::_2));
    segments_sub_ = nh.subscribe<line_map_msgs::LineSegmentArray>(
        "line_segments", queue_size,
        boost::function<void(const ros::MessageEvent<const line_map_msgs::LineSegmentArray>&)>(
            [this](const ros::MessageEvent<const line_map_msgs::LineSegmentArray>& e) { onRawSegments(e); }));
    trajectory_sub_ = nh.subscribe("optimized_trajectory", 2, &LineMapMergingNodelet::onTrajectory, this);
    save_srv_ = pnh.advertiseService("save_map", &LineMapMergingNodelet::onSave, this);
    load_srv_ = pnh.advertiseService("load_map", &LineMapMergingNodelet::onLoad, this);
    reset_srv_ = pnh.advertiseService("reset_map", &LineMapMergingNodelet::onReset, this);

    if (autosave_period_ > 0.0 && !autosave_path_.empty())
    {
      autosave_timer_ = nh.createWallTimer(ros::WallDuration(autosave_period_),
                                           [this](const ros::WallTimerEvent&)
                                           {
                                             std::lock_guard<std::mutex> lock(mutex_);
                                             autosave();
                                           });
      NODELET_INFO("line_map_merging: autosaving to '%s' every %.1f s", autosave_path_.c_str(),
                   autosave_period_);
    }
    else if (autosave_period_ > 0.0 || !autosave_path_.empty())
      NODELET_WARN("line_map_merging: autosave needs both ~autosave_period > 0 and ~autosave_path; off");

    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
    diagnostics_->setHardwareID("none");
    diagnostics_->add("line map merging", this, &LineMapMergingNodelet::produceDiagnostics);
    diag_timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                                     [this](const ros::WallTimerEvent&)
                                     {
                                       std::lock_guard<std::mutex> lock(mutex_);
                                       checkTimeJump(ros::Time());  // the clock also jumps without scans
                                       // update() waits for the next period in ROS time, which never
                                       // comes after the clock jumped back; this timer runs on wall time.
                                       diagnostics_->force_update();
                                     });
    NODELET_INFO("line_map_merging: method '%s' in frame '%s', keyframe gate %.2f m / %.1f deg",
                 method_.c_str(), map_frame_.c_str(), gate_.params().distance,
                 gate_.params().angle * 180.0 / linemap::kPi);
  }

  /// Drops (and counts) segments stamped zero before they reach the tf filter, which would take them
  /// as "latest transform" and pose them wherever the robot is now.
  void onRawSegments(const ros::MessageEvent<const line_map_msgs::LineSegmentArray>& event)
  {
    const auto& msg = event.getConstMessage();
    if (msg->header.stamp.isZero())
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++zero_stamps_;
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: line_segments stamped zero dropped (%zu so far)",
                            zero_stamps_);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      checkTimeJump(msg->header.stamp);
      // A frame that tf has never heard of would wait in the filter until its queue overflows,
      // unreported: drop and count it now (a frame that exists but is not yet connected still waits).
      // The map frame itself needs no tf (its pose is the identity), so tf may never have heard of it.
      const std::string frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
      if (frame.empty() || (frame != map_frame_ && !tf_buffer_->_frameExists(frame)))
      {
        ++dropped_scans_;
        NODELET_WARN_THROTTLE(5.0,
                              "line_map_merging: segments in frame '%s', unknown to tf, dropped (%zu so far)",
                              msg->header.frame_id.c_str(), dropped_scans_);
        return;
      }
    }
    filter_->add(event);  // keeps the receipt time (add(msg) would stamp it with wall time)
  }

  /// Time going backwards (a `rosbag play --loop` restart under use_sim_time): the tf buffer holds
  /// the future of the new time line, which would pose the replayed scans, and the gate reference
  /// is the pose at the end of the previous pass. Both are reset; the map is kept.
  /// Called with mutex_ held.
  void checkTimeJump(const ros::Time& stamp)
  {
    const ros::Time now = ros::Time::now();
    const bool clock_back = !last_now_.isZero() && (last_now_ - now).toSec() > time_jump_tolerance_;
    const bool stamp_back =
        !last_stamp_.isZero() && !stamp.isZero() && (last_stamp_ - stamp).toSec() > time_jump_tolerance_;
    if (clock_back || stamp_back)
    {
      ++time_jumps_;
      NODELET_WARN_THROTTLE(5.0,
                            "line_map_merging: time jumped backwards (%s %.3f -> %.3f); tf buffer cleared, "
                            "keyframe gate reset, map kept (%zu jumps so far)",
                            clock_back ? "clock" : "stamp",
                            clock_back ? last_now_.toSec() : last_stamp_.toSec(),
                            clock_back ? now.toSec() : stamp.toSec(), time_jumps_);
      tf_buffer_->clear();
      gate_.reset();
      last_stamp_ = ros::Time();
    }
    last_now_ = now;
    if (!stamp.isZero()) last_stamp_ = std::max(last_stamp_, stamp);
  }

  /// Saves the map when it changed since the last save. Called with mutex_ held.
  void autosave()
  {
    if (autosave_path_.empty() || autosave_period_ <= 0.0 || saved_revision_ == revision_) return;
    try
    {
      merger_->save(autosave_path_);
      saved_revision_ = revision_;
      ++autosaves_;
    }
    catch (const std::exception& e)
    {
      ++autosave_failures_;
      NODELET_WARN_THROTTLE(30.0, "line_map_merging: autosave failed (%zu so far): %s", autosave_failures_,
                            e.what());
    }
  }

  void onTfFailure(const line_map_msgs::LineSegmentArray::ConstPtr& msg, tf2_ros::FilterFailureReason reason)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++dropped_scans_;
    NODELET_WARN_THROTTLE(5.0,
                          "line_map_merging: dropped segments at %.3f: no transform %s -> %s (reason %d)",
                          msg->header.stamp.toSec(), map_frame_.c_str(), msg->header.frame_id.c_str(),
                          static_cast<int>(reason));
  }

  void onSegments(const ros::MessageEvent<const line_map_msgs::LineSegmentArray>& event)
  {
    const auto& msg = event.getConstMessage();
    std::lock_guard<std::mutex> lock(mutex_);
    if ((ros::Time::now() - event.getReceiptTime()).toSec() > tf_timeout_)
    {
      ++dropped_scans_;
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: segments at %.3f waited more than %.2f s for tf; dropped",
                            msg->header.stamp.toSec(), tf_timeout_);
      return;
    }
    const std::string laser_frame = linemap_ros::stripLeadingSlash(msg->header.frame_id);
    linemap::Pose2 laser, mount;
    try
    {
      if (!poseOf(tf_buffer_->lookupTransform(map_frame_, laser_frame, msg->header.stamp).transform, laser))
      {
        ++dropped_scans_;
        NODELET_WARN_THROTTLE(5.0, "line_map_merging: transform %s -> %s is not a valid pose; scan dropped",
                              map_frame_.c_str(), msg->header.frame_id.c_str());
        return;
      }
    }
    catch (const tf2::TransformException& e)
    {
      ++dropped_scans_;
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: %s", e.what());
      return;
    }
    if (!base_frame_.empty() && base_frame_ != laser_frame)
    {
      try
      {
        if (!poseOf(tf_buffer_->lookupTransform(base_frame_, laser_frame, msg->header.stamp).transform,
                    mount))
          mount = linemap::Pose2();
      }
      catch (const tf2::TransformException& e)
      {
        // Without base -> laser the trajectory is applied to the laser pose directly. A bag without
        // that transform lacks it for good: saying so once is enough.
        NODELET_WARN_ONCE(
                              "line_map_merging: no %s -> %s transform (%s); taking them as the same frame",
                              base_frame_.c_str(), msg->header.frame_id.c_str(), e.what());
      }
    }

    const linemap::Pose2 base = laser * mount.inverse();
    // A scan with the stamp of a keyframe is that keyframe again (a bag replayed with --loop):
    // merging it twice would only add duplicate leaves and make stamp matching ambiguous. The gate
    // moves on from it as from a keyframe, so a replay takes no keyframes in between.
    if (keyframe_stamps_.count(msg->header.stamp.toSec()))
    {
      ++replayed_scans_;
      gate_.setReference(base);
      return;
    }
    scan_gaps_.scan(msg->header.stamp.toSec());
    // Keyframe gate on the robot (base) pose.
    if (!gate_.wouldAccept(base))
    {
      ++gated_scans_;
      return;
    }
    std::optional<linemap::Pose2> odom_laser;
    if (!odom_frame_.empty() && odom_frame_ != map_frame_)
    {
      try
      {
        linemap::Pose2 p;
        if (poseOf(tf_buffer_->lookupTransform(odom_frame_, laser_frame, msg->header.stamp).transform, p))
          odom_laser = p;
      }
      catch (const tf2::TransformException&)
      {
        // No odometry frame: the correction is interpolated in the map frame.
      }
    }

    Keyframe keyframe;
    keyframe.index = next_index_;
    keyframe.stamp = msg->header.stamp.toSec();
    keyframe.pose = laser;
    keyframe.mount = mount;
    keyframe.segments.reserve(msg->segments.size());
    for (const auto& s : msg->segments)
      keyframe.segments.emplace_back(linemap::Vec2(s.start.x, s.start.y), linemap::Vec2(s.end.x, s.end.y));
    const auto t0 = std::chrono::steady_clock::now();
    AddResult result;
    try
    {
      result = merger_->addKeyframe(keyframe);
    }
    catch (const std::exception& e)
    {
      ++dropped_scans_;
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: keyframe rejected: %s", e.what());
      return;
    }
    last_otm_ms_ = msSince(t0);
    if (odom_laser) odom_poses_[keyframe.index] = *odom_laser;
    scan_gaps_.keyframe(keyframe.index);
    ++next_index_;
    keyframe_stamps_.insert(keyframe.stamp);
    ++revision_;
    gate_.accept(base);
    if (result.rejected > 0)
    {
      bad_segments_ += result.rejected;
      NODELET_WARN_THROTTLE(5.0,
                            "line_map_merging: %zu non-finite or zero-length segments skipped (%zu so far)",
                            result.rejected, bad_segments_);
    }
    publish(msg->header.stamp);
  }

  void onTrajectory(const nav_msgs::Path::ConstPtr& path)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (path->poses.empty())
    {
      ++bad_trajectories_;
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: empty optimized_trajectory ignored");
      return;
    }
    if (!path->header.frame_id.empty() && linemap_ros::stripLeadingSlash(path->header.frame_id) != map_frame_)
    {
      ++bad_trajectories_;
      NODELET_WARN_THROTTLE(5.0,
                            "line_map_merging: optimized_trajectory in frame '%s', expected '%s'; ignored",
                            path->header.frame_id.c_str(), map_frame_.c_str());
      return;
    }
    std::vector<KeyframeInfo> keyframes = merger_->keyframes();
    scan_gaps_.fill(keyframes);  // a pose of a scan that did not become a keyframe stays unmatched
    std::sort(keyframes.begin(), keyframes.end(),
              [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.stamp < b.stamp; });
    std::map<std::uint64_t, linemap::Pose2> matched;
    std::size_t unmatched = 0, invalid = 0;
    for (const auto& p : path->poses)
    {
      double yaw = 0.0;
      if (!yawOf(p.pose.orientation, yaw) || !std::isfinite(p.pose.position.x) ||
          !std::isfinite(p.pose.position.y))
      {
        ++invalid;
        continue;
      }
      const auto k = matchByStamp(keyframes, p.header.stamp.toSec(), stamp_tolerance_);
      if (!k)
      {
        ++unmatched;
        continue;
      }
      // The trajectory holds base poses; the merger keeps laser poses.
      matched[keyframes[*k].index] =
          linemap::Pose2(p.pose.position.x, p.pose.position.y, yaw) * keyframes[*k].mount;
    }
    unmatched_poses_ += unmatched;
    bad_poses_ += invalid;
    if (invalid > 0)
      NODELET_WARN_THROTTLE(5.0,
                            "line_map_merging: %zu trajectory poses with a non-normalised quaternion or "
                            "non-finite position ignored",
                            invalid);
    if (unmatched > 0)
      NODELET_INFO_THROTTLE(
          5.0, "line_map_merging: %zu of %zu trajectory poses match no keyframe (tolerance %.3f s)",
          unmatched, path->poses.size(), stamp_tolerance_);
    const auto poses = correctKeyframes(keyframes, matched, odom_poses_);
    if (poses.empty()) return;
    const auto t0 = std::chrono::steady_clock::now();
    try
    {
      const AdjustResult r = merger_->adjust(poses);
      last_gma_ms_ = msSince(t0);
      // The gate measures motion from the last keyframe where it now is.
      const auto last = std::max_element(poses.begin(), poses.end(),
                                         [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const KeyframeInfo& k : keyframes)
        if (k.index == last->first) gate_.setReference(last->second * k.mount.inverse());
      NODELET_DEBUG(
          "line_map_merging: adjusted %zu keyframes (%zu matched) in %.1f ms; %zu leaves split, %zu merged",
          r.moved, matched.size(), last_gma_ms_, r.split, r.merged);
    }
    catch (const std::exception& e)
    {
      NODELET_WARN_THROTTLE(5.0, "line_map_merging: adjustment failed: %s", e.what());
      return;
    }
    ++adjustments_;
    ++revision_;
    publish(path->header.stamp.isZero() ? ros::Time::now() : path->header.stamp);
  }

  bool onSave(line_map_msgs::SaveMap::Request& req, line_map_msgs::SaveMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    try
    {
      merger_->save(req.path);
      res.success = true;
      res.message = "saved " + std::to_string(merger_->segmentCount()) + " segments to " + req.path;
    }
    catch (const std::exception& e)
    {
      res.success = false;
      res.message = e.what();
    }
    return true;
  }

  bool onLoad(line_map_msgs::LoadMap::Request& req, line_map_msgs::LoadMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    try
    {
      merger_->load(req.path);
    }
    catch (const std::exception& e)
    {
      res.success = false;
      res.message = e.what();
      return true;
    }
    next_index_ = 0;
    odom_poses_.clear();
    scan_gaps_.clear();
    keyframe_stamps_.clear();
    for (const KeyframeInfo& k : merger_->keyframes())
    {
      next_index_ = std::max(next_index_, k.index + 1);
      keyframe_stamps_.insert(k.stamp);
    }
    gate_.reset();
    ++revision_;
    res.success = true;
    res.message = "loaded " + std::to_string(merger_->segmentCount()) + " segments, " +
                  std::to_string(merger_->keyframeCount()) + " keyframes from " + req.path;
    publish(ros::Time::now());
    return true;
  }

  bool onReset(line_map_msgs::ResetMap::Request&, line_map_msgs::ResetMap::Response& res)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    merger_->reset();
    ++revision_;
    next_index_ = 0;
    keyframe_stamps_.clear();
    odom_poses_.clear();
    scan_gaps_.clear();
    gate_.reset();
    res.success = true;
    res.message = "map cleared";
    publish(ros::Time::now());
    return true;
  }

  void publish(const ros::Time& stamp)
  {
    const std::vector<MapSegment> map = merger_->map();
    line_map_msgs::LineMap msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = map_frame_;
    msg.segments.resize(map.size());
    for (std::size_t i = 0; i < map.size(); ++i)
    {
      auto& out = msg.segments[i];
      const linemap::Segment2& s = map[i].segment;
      out.id = map[i].id;
      out.merged_count = map[i].merged_count;
      out.segment.start.x = s.start.x();
      out.segment.start.y = s.start.y();
      out.segment.end.x = s.end.x();
      out.segment.end.y = s.end.y();
      const linemap::HessianLine h = linemap::hessianFromPoints(s.start, s.end);
      out.segment.angle = h.angle;
      out.segment.radius = h.radius;
      out.segment.num_points = 0;
    }
    msg.original_segments = static_cast<std::uint32_t>(merger_->leafCount());
    msg.keyframes = static_cast<std::uint32_t>(merger_->keyframeCount());
    map_pub_.publish(msg);
    if (marker_pub_.getNumSubscribers() > 0) publishMarkers(msg);
  }

  void publishMarkers(const line_map_msgs::LineMap& map)
  {
    visualization_msgs::MarkerArray array;
    visualization_msgs::Marker clear;
    clear.header = map.header;
    clear.action = visualization_msgs::Marker::DELETEALL;
    array.markers.push_back(clear);

    auto make = [&](const std::string& ns, int type, float r, float g, float b, double scale)
    {
      visualization_msgs::Marker m;
      m.header = map.header;
      m.ns = ns;
      m.type = type;
      m.action = visualization_msgs::Marker::ADD;
      m.pose.orientation.w = 1.0;
      m.scale.x = scale;
      m.scale.y = scale;
      m.color.r = r;
      m.color.g = g;
      m.color.b = b;
      m.color.a = 1.0;
      return m;
    };
    auto lines = make("segments", visualization_msgs::Marker::LINE_LIST, 0.1f, 0.3f, 1.0f, marker_width_);
    auto starts =
        make("start_points", visualization_msgs::Marker::POINTS, 1.0f, 0.0f, 0.0f, 2.0 * marker_width_);
    auto ends = make("end_points", visualization_msgs::Marker::POINTS, 0.0f, 0.8f, 0.0f, 2.0 * marker_width_);
    for (const auto& s : map.segments)
    {
      lines.points.push_back(s.segment.start);
      lines.points.push_back(s.segment.end);
      starts.points.push_back(s.segment.start);
      ends.points.push_back(s.segment.end);
    }
    if (!lines.points.empty())
    {
      array.markers.push_back(lines);
      array.markers.push_back(starts);
      array.markers.push_back(ends);
    }
    if (publish_labels_)
    {
      for (const auto& s : map.segments)
      {
        auto label = make("labels", visualization_msgs::Marker::TEXT_VIEW_FACING, 1.0f, 1.0f, 1.0f, 0.0);
        label.id = static_cast<int>(s.id % 2147483647u);
        label.scale.z = 0.2;
        label.pose.position.x = 0.5 * (s.segment.start.x + s.segment.end.x);
        label.pose.position.y = 0.5 * (s.segment.start.y + s.segment.end.y);
        label.text = std::to_string(s.id);
        array.markers.push_back(label);
      }
    }
    marker_pub_.publish(array);
  }

  void produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    // Called from the diagnostics timer, which holds mutex_.
    stat.summary(dropped_scans_ > 0 || bad_poses_ > 0 ? diagnostic_msgs::DiagnosticStatus::WARN
                                                      : diagnostic_msgs::DiagnosticStatus::OK,
                 dropped_scans_ > 0 ? "scans dropped (no transform)" : "merging");
    stat.add("method", method_);
    stat.add("keyframes", merger_->keyframeCount());
    stat.add("leaves", merger_->leafCount());
    stat.add("map segments", merger_->segmentCount());
    stat.add("last OTM time [ms]", last_otm_ms_);
    stat.add("last GMA time [ms]", last_gma_ms_);
    stat.add("adjustments", adjustments_);
    stat.add("dropped scans", dropped_scans_);
    stat.add("scans below the keyframe gate", gated_scans_);
    stat.add("bad segments", bad_segments_);
    stat.add("bad trajectory poses", bad_poses_);
    stat.add("unmatched trajectory poses", unmatched_poses_);
    stat.add("ignored trajectories", bad_trajectories_);
    stat.add("zero-stamp segments", zero_stamps_);
    stat.add("replayed scans skipped", replayed_scans_);
    stat.add("time jumps", time_jumps_);
    stat.add("autosaves", autosaves_);
    stat.add("autosave failures", autosave_failures_);
  }

  std::mutex mutex_;
  std::unique_ptr<Merger> merger_;
  std::string method_, map_frame_, base_frame_, odom_frame_;
  std::map<std::uint64_t, linemap::Pose2> odom_poses_;  ///< keyframe index -> laser pose in odom_frame_
  ScanGapTracker scan_gaps_;  ///< time to the scans around each keyframe, for stamp matching
  double stamp_tolerance_ = 0.01, tf_timeout_ = 0.5;
  KeyframeGate gate_;
  bool publish_labels_ = false;
  double marker_width_ = 0.03;

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<SegmentsFilter> filter_;
  ros::Subscriber segments_sub_, trajectory_sub_;
  ros::Publisher map_pub_, marker_pub_;
  ros::ServiceServer save_srv_, load_srv_, reset_srv_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diag_timer_, autosave_timer_;

  // Autosave: revision_ counts map changes, saved_revision_ is the one on disk.
  double autosave_period_ = 0.0;
  std::string autosave_path_;
  std::uint64_t revision_ = 0, saved_revision_ = 0;
  std::size_t autosaves_ = 0, autosave_failures_ = 0;

  // Time jumps: the latest clock reading and segments stamp seen.
  double time_jump_tolerance_ = 1.0;
  ros::Time last_now_, last_stamp_;
  std::size_t time_jumps_ = 0, zero_stamps_ = 0, replayed_scans_ = 0;
  std::unordered_set<double> keyframe_stamps_;  ///< of the merged keyframes, in seconds

  std::uint64_t next_index_ = 0;
  double last_otm_ms_ = 0.0, last_gma_ms_ = 0.0;
  std::size_t dropped_scans_ = 0, gated_scans_ = 0, bad_segments_ = 0, bad_poses_ = 0, unmatched_poses_ = 0,
              bad_trajectories_ = 0, adjustments_ = 0;
};

}  // namespace line_map_merging

PLUGINLIB_EXPORT_CLASS(line_map_merging::LineMapMergingNodelet, nodelet::Nodelet)
