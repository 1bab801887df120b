#include "line_map_eval/datasets/bag_reader.hpp"

#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace line_map_eval
{
namespace
{
double yawOf(const geometry_msgs::Quaternion& q)
{
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

Pose2 fromTransform(const geometry_msgs::Transform& t)
{
  return {t.translation.x, t.translation.y, yawOf(t.rotation)};
}

Pose2 fromPose(const geometry_msgs::Pose& p)
{
  return {p.position.x, p.position.y, yawOf(p.orientation)};
}

std::string stripSlash(const std::string& frame)
{
  return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame;
}

/// Pose at time t from samples sorted by time; exact stamps return the sample itself.
bool sampleAt(const std::vector<std::pair<double, Pose2>>& samples, double t, Pose2& out)
{
  const auto it =
      std::lower_bound(samples.begin(), samples.end(), t,
                       [](const std::pair<double, Pose2>& s, double time) { return s.first < time; });
  if (it != samples.end() && it->first == t)
  {
    out = it->second;
    return true;
  }
  if (it == samples.begin() || it == samples.end()) return false;
  const auto& a = *(it - 1);
  const auto& b = *it;
  out = linemap::interpolate(a.second, b.second, (t - a.first) / (b.first - a.first));
  return true;
}

/// The frames readBag looks for, without leading slashes.
struct Frames
{
  std::string odom, base, map;
};

/// Appends one LaserScan to the recording; the first scan sets the recording's geometry.
void readScan(const rosbag::MessageInstance& m, const std::string& path, BagContents& out,
              bool& have_geometry)
{
  Recording& rec = out.recording;
  const auto scan = m.instantiate<sensor_msgs::LaserScan>();
  if (!scan) throw std::runtime_error(path + ": " + m.getTopic() + " does not hold sensor_msgs/LaserScan");
  ScanGeometry g;
  g.angle_min = scan->angle_min;
  g.angle_increment = scan->angle_increment;
  g.beam_count = scan->ranges.size();
  g.range_min = scan->range_min;
  g.range_max = scan->range_max;
  RecordedScan s;
  if (!have_geometry)
  {
    rec.geometry = g;
    out.scan_frame = stripSlash(scan->header.frame_id);
    have_geometry = true;
  }
  else if (g.angle_min != rec.geometry.angle_min || g.angle_increment != rec.geometry.angle_increment ||
           g.beam_count != rec.geometry.beam_count || g.range_min != rec.geometry.range_min ||
           g.range_max != rec.geometry.range_max)
  {
    s.geometry = g;  // this scan's own (sensors that change start angle or beam count)
  }
  s.stamp = scan->header.stamp.toSec();
  s.ranges = scan->ranges;
  rec.scans.push_back(std::move(s));
}

/// Sorts the transforms of one /tf or /tf_static message into odom->base, map->odom and base->child.
void readTf(const rosbag::MessageInstance& m, const std::string& path, const Frames& frames, BagContents& out,
            std::map<std::string, Pose2>& base_to)
{
  const std::string& topic = m.getTopic();
  const auto tf = m.instantiate<tf2_msgs::TFMessage>();
  if (!tf) throw std::runtime_error(path + ": " + topic + " does not hold tf2_msgs/TFMessage");
  for (const auto& t : tf->transforms)
  {
    const std::string parent = stripSlash(t.header.frame_id), child = stripSlash(t.child_frame_id);
    const double stamp = t.header.stamp.toSec();
    if (topic == "/tf_static") ++out.static_transforms;
    if (parent == frames.odom && child == frames.base)
      out.odom_to_base.emplace_back(stamp, fromTransform(t.transform));
    else if (parent == frames.map && child == frames.odom)
      out.map_to_odom.emplace_back(stamp, fromTransform(t.transform));
    else if (parent == frames.base)
      base_to[child] = fromTransform(t.transform);
  }
}

void readTrajectory(const rosbag::MessageInstance& m, const std::string& path, BagContents& out)
{
  const auto p = m.instantiate<nav_msgs::Path>();
  if (!p) throw std::runtime_error(path + ": " + m.getTopic() + " does not hold nav_msgs/Path");
  TrajectoryEmission e;
  e.stamp = p->header.stamp.toSec();
  for (const auto& pose : p->poses) e.poses.emplace_back(pose.header.stamp.toSec(), fromPose(pose.pose));
  out.trajectory.push_back(std::move(e));
}

/// Reads every scan, transform and trajectory message of the bag in bag order.
void readMessages(const std::string& path, const BagWriterOptions& options, const Frames& frames,
                  BagContents& out, std::map<std::string, Pose2>& base_to)
{
  try
  {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Read);
    rosbag::View view(
        bag, rosbag::TopicQuery({options.scan_topic, "/tf", "/tf_static", options.trajectory_topic}));
    bool have_geometry = false;
    for (const rosbag::MessageInstance& m : view)
    {
      const std::string& topic = m.getTopic();
      if (topic == options.scan_topic)
        readScan(m, path, out, have_geometry);
      else if (topic == "/tf" || topic == "/tf_static")
        readTf(m, path, frames, out, base_to);
      else if (topic == options.trajectory_topic)
        readTrajectory(m, path, out);
    }
    bag.close();
  }
  catch (const rosbag::BagException& e)
  {
    throw std::runtime_error(path + ": " + e.what());
  }
}

/// Gives every scan its odometry pose, interpolated between the odom->base transforms around it.
void stampOdometry(const std::string& path, const Frames& frames, BagContents& out)
{
  Recording& rec = out.recording;
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
  {
    if (!sampleAt(out.odom_to_base, rec.scans[i].stamp, rec.scans[i].odom))
      throw std::runtime_error(path + ": no " + frames.odom + " -> " + frames.base +
                               " transform around scan " + std::to_string(i) + " (stamp " +
                               std::to_string(rec.scans[i].stamp) + ")");
  }
}

/// Keyframes: the poses of the last emission, each matched to the scan with the same stamp.
void matchKeyframes(const std::string& path, BagContents& out)
{
  Recording& rec = out.recording;
  std::size_t next = 0;
  for (const auto& [stamp, pose] : out.trajectory.back().poses)
  {
    while (next < rec.scans.size() && rec.scans[next].stamp < stamp) ++next;
    if (next == rec.scans.size() || rec.scans[next].stamp != stamp)
      throw std::runtime_error(
          path + ": trajectory pose stamped " + std::to_string(stamp) +
          " matches no scan stamp (poses must be stamped with their scans' stamps, in order)");
    rec.keyframes.push_back({next, pose});
    ++next;
  }
}
}  // namespace

BagContents readBag(const std::string& path, const BagWriterOptions& options)
{
  BagContents out;
  Recording& rec = out.recording;
  rec.source = path;
  const Frames frames{stripSlash(options.odom_frame), stripSlash(options.base_frame),
                      stripSlash(options.map_frame)};
  std::map<std::string, Pose2> base_to;  // base->child static transforms
  readMessages(path, options, frames, out, base_to);

  if (rec.scans.empty())
    throw std::runtime_error(path + ": no sensor_msgs/LaserScan on " + options.scan_topic);
  const auto by_time = [](const std::pair<double, Pose2>& a, const std::pair<double, Pose2>& b)
  { return a.first < b.first; };
  std::stable_sort(out.odom_to_base.begin(), out.odom_to_base.end(), by_time);
  std::stable_sort(out.map_to_odom.begin(), out.map_to_odom.end(), by_time);

  const auto mount = base_to.find(out.scan_frame);
  out.odometry = !out.odom_to_base.empty();
  if (out.scan_frame == frames.base || (!out.odometry && out.static_transforms == 0 && base_to.empty()))
    rec.base_to_laser = Pose2();
  else if (mount != base_to.end())
    rec.base_to_laser = mount->second;
  else
    throw std::runtime_error(path + ": no transform " + frames.base + " -> " + out.scan_frame +
                             " on /tf_static or /tf");

  if (out.odometry) stampOdometry(path, frames, out);
  if (!out.trajectory.empty()) matchKeyframes(path, out);
  return out;
}

}  // namespace line_map_eval
