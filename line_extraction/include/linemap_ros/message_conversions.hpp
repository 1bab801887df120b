// ROS side (not part of the ROS-free core): conversions between ROS messages and the core's planar
// geometry, written once for every nodelet and tool.
#pragma once

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/TransformStamped.h>
#include <line_map_msgs/LineMap.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <ros/time.h>
#include <tf2_ros/buffer.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "linemap/geometry.hpp"

namespace linemap_ros
{
/// The planar pose of a position and quaternion (its rotation about z), or nothing when the
/// quaternion is not normalised or the position is not finite.
inline std::optional<linemap::Pose2> toPose2(double x, double y, const geometry_msgs::Quaternion& q)
{
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3 || !std::isfinite(x) || !std::isfinite(y))
    return std::nullopt;
  return linemap::Pose2(x, y, std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z)));
}

/// The planar pose `p` as a pose message (z = 0, rotation about z).
inline geometry_msgs::Pose toPoseMsg(const linemap::Pose2& p)
{
  geometry_msgs::Pose m;
  m.position.x = p.x;
  m.position.y = p.y;
  m.orientation.z = std::sin(0.5 * p.theta);
  m.orientation.w = std::cos(0.5 * p.theta);
  return m;
}

/// The planar pose `p` of `child` in `parent` as a stamped transform (z = 0, rotation about z).
inline geometry_msgs::TransformStamped toTransform(const linemap::Pose2& p, const std::string& parent,
                                                   const std::string& child, const ros::Time& stamp)
{
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  const geometry_msgs::Pose m = toPoseMsg(p);
  t.transform.translation.x = m.position.x;
  t.transform.translation.y = m.position.y;
  t.transform.rotation = m.orientation;
  return t;
}

/// The pose of `frame` in `target` at `stamp` from tf (identity for the same frame: the map frame may
/// be unknown to tf), or nothing when tf has none or it is not a valid planar pose.
inline std::optional<linemap::Pose2> lookupPose(const tf2_ros::Buffer& tf, const std::string& target,
                                                const std::string& frame, const ros::Time& stamp)
{
  if (target == frame) return linemap::Pose2();
  try
  {
    const auto t = tf.lookupTransform(target, frame, stamp).transform;
    return toPose2(t.translation.x, t.translation.y, t.rotation);
  }
  catch (const tf2::TransformException&)
  {
    return std::nullopt;
  }
}

/// The segments of a segment set, in its frame.
inline std::vector<linemap::Segment2> toSegments(const line_map_msgs::LineSegmentArray& msg)
{
  std::vector<linemap::Segment2> out;
  out.reserve(msg.segments.size());
  for (const auto& s : msg.segments)
    out.emplace_back(linemap::Vec2(s.start.x, s.start.y), linemap::Vec2(s.end.x, s.end.y));
  return out;
}

/// The segments of a line map, in its frame.
inline std::vector<linemap::Segment2> toSegments(const line_map_msgs::LineMap& map)
{
  std::vector<linemap::Segment2> out;
  out.reserve(map.segments.size());
  for (const auto& s : map.segments)
    out.emplace_back(linemap::Vec2(s.segment.start.x, s.segment.start.y),
                     linemap::Vec2(s.segment.end.x, s.segment.end.y));
  return out;
}
}  // namespace linemap_ros
