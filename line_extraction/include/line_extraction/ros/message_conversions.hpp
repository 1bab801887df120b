// ROS side (not part of the ROS-free core): conversions between the suite's messages and the core's
// geometry that more than one nodelet needs.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <ros/time.h>

#include <cmath>
#include <string>
#include <vector>

#include "line_extraction/geometry.hpp"

namespace linemap_ros
{
/// The planar pose `p` of `child` in `parent` as a stamped transform (z = 0, rotation about z).
inline geometry_msgs::TransformStamped toTransform(const linemap::Pose2& p, const std::string& parent,
                                                   const std::string& child, const ros::Time& stamp)
{
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = p.x;
  t.transform.translation.y = p.y;
  t.transform.rotation.z = std::sin(0.5 * p.theta);
  t.transform.rotation.w = std::cos(0.5 * p.theta);
  return t;
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
}  // namespace linemap_ros
