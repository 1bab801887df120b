// Message conversions of the merging nodelet (header-only, ROS side): poses from tf and
// nav_msgs/Path, the map as line_map_msgs/LineMap, its RViz markers and its occupancy grid, errors as
// service answers.
#pragma once

#include <geometry_msgs/Quaternion.h>
#include <line_map_msgs/LineMap.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "line_map_merging/map/occupancy_grid.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/online/concurrent_mapper.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "linemap_ros/message_conversions.hpp"
#include "linemap_ros/param_loader.hpp"

namespace line_map_merging
{
/// The nodes of a trajectory (base poses in the map frame `map_frame`; an empty frame is taken as
/// it), or nothing for a trajectory in another frame; `bad` counts the poses skipped.
inline std::optional<std::vector<std::pair<double, linemap::Pose2>>> toNodes(const nav_msgs::Path& path,
                                                                             const std::string& map_frame,
                                                                             std::size_t& bad)
{
  const std::string frame = linemap_ros::stripLeadingSlash(path.header.frame_id);
  if (!frame.empty() && frame != map_frame) return std::nullopt;
  std::vector<std::pair<double, linemap::Pose2>> nodes;
  nodes.reserve(path.poses.size());
  for (const auto& p : path.poses)
    if (const auto pose = linemap_ros::toPose2(p.pose.position.x, p.pose.position.y, p.pose.orientation))
      nodes.emplace_back(p.header.stamp.toSec(), *pose);
  bad = path.poses.size() - nodes.size();
  return nodes;
}

/// A scan's beams for the map-level lines.
inline std::shared_ptr<const KeyframeScan> toKeyframeScan(const sensor_msgs::LaserScan& msg)
{
  return makeKeyframeScan(msg, msg.ranges);
}

/// A segment set with its poses from tf at its stamp: the laser in `map` (nothing without a valid
/// transform), in `odom` (unless empty or `map`) and base -> laser (identity when tf has none or
/// `base` is empty; `mount_found` says which).
inline std::optional<StampedScan> toStampedScan(const tf2_ros::Buffer& tf,
                                                const line_map_msgs::LineSegmentArray& msg,
                                                const std::string& frame, const std::string& map,
                                                const std::string& base, const std::string& odom,
                                                bool& mount_found)
{
  StampedScan scan;
  scan.stamp = msg.header.stamp.toSec();
  const auto laser = linemap_ros::lookupPose(tf, map, frame, msg.header.stamp);
  if (!laser) return std::nullopt;
  scan.laser = *laser;
  const auto mount =
      base.empty() ? linemap::Pose2() : linemap_ros::lookupPose(tf, base, frame, msg.header.stamp);
  mount_found = mount.has_value();
  scan.mount = mount.value_or(linemap::Pose2());
  if (!odom.empty() && odom != map) scan.odom = linemap_ros::lookupPose(tf, odom, frame, msg.header.stamp);
  scan.segments = linemap_ros::toSegments(msg);
  return scan;
}

/// A map service's response from the core's answer.
template <class Response>
bool answer(Response& res, const MapCommandAnswer& answer)
{
  res.success = answer.success;
  res.message = answer.message;
  return true;
}

inline line_map_msgs::LineMap toLineMap(const Merger& merger, const std::string& frame,
                                        const ros::Time& stamp)
{
  const std::vector<MapSegment> map = merger.map();
  line_map_msgs::LineMap msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame;
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
  }
  msg.original_segments = static_cast<std::uint32_t>(merger.leafCount());
  msg.keyframes = static_cast<std::uint32_t>(merger.keyframeCount());
  return msg;
}

/// Lines, start points red, end points green, optionally id labels; the first marker clears the old ones.
inline visualization_msgs::MarkerArray toMarkers(const line_map_msgs::LineMap& map, double width, bool labels)
{
  using visualization_msgs::Marker;
  auto make = [&](const std::string& ns, int type, float r, float g, float b, double scale)
  {
    Marker m;
    m.header = map.header;
    m.ns = ns;
    m.type = type;
    m.action = Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = scale;
    m.color.r = r;
    m.color.g = g;
    m.color.b = b;
    m.color.a = 1.0;
    return m;
  };
  visualization_msgs::MarkerArray array;
  Marker clear;
  clear.header = map.header;
  clear.action = Marker::DELETEALL;
  array.markers.push_back(clear);
  auto lines = make("segments", Marker::LINE_LIST, 0.1f, 0.3f, 1.0f, width);
  auto starts = make("start_points", Marker::POINTS, 1.0f, 0.0f, 0.0f, 2.0 * width);
  auto ends = make("end_points", Marker::POINTS, 0.0f, 0.8f, 0.0f, 2.0 * width);
  for (const auto& s : map.segments)
  {
    lines.points.push_back(s.segment.start);
    lines.points.push_back(s.segment.end);
    starts.points.push_back(s.segment.start);
    ends.points.push_back(s.segment.end);
  }
  if (!lines.points.empty()) array.markers.insert(array.markers.end(), {lines, starts, ends});
  for (const auto& s : map.segments)
  {
    if (!labels) break;
    auto label = make("labels", Marker::TEXT_VIEW_FACING, 1.0f, 1.0f, 1.0f, 0.0);
    label.id = static_cast<int>(s.id % 2147483647u);
    label.scale.z = 0.2;
    label.pose.position.x = 0.5 * (s.segment.start.x + s.segment.end.x);
    label.pose.position.y = 0.5 * (s.segment.start.y + s.segment.end.y);
    label.text = std::to_string(s.id);
    array.markers.push_back(label);
  }
  return array;
}

inline nav_msgs::OccupancyGrid toGridMessage(const OccupancyGrid& grid, const std::string& frame,
                                             const ros::Time& stamp)
{
  nav_msgs::OccupancyGrid msg;
  msg.header.frame_id = frame;
  msg.header.stamp = stamp;
  msg.info.map_load_time = stamp;
  msg.info.resolution = static_cast<float>(grid.resolution);
  msg.info.width = static_cast<std::uint32_t>(grid.width);
  msg.info.height = static_cast<std::uint32_t>(grid.height);
  msg.info.origin.position.x = grid.origin.x();
  msg.info.origin.position.y = grid.origin.y();
  msg.info.origin.orientation.w = 1.0;
  msg.data = grid.cells;  // both row-major from the origin corner, -1 / 0 / 100
  return msg;
}

/// A grid's stamp: its newest keyframe's (ros::Time throws for one out of range); the newest input's
/// exact one when it is that keyframe's (the double lost the nanoseconds), or stands in for an empty map.
inline ros::Time gridStamp(double newest_keyframe, const ros::Time& newest_input)
{
  const bool same = std::abs(newest_keyframe - newest_input.toSec()) < 1e-6;
  return std::isfinite(newest_keyframe) && !same ? ros::Time(newest_keyframe) : newest_input;
}

}  // namespace line_map_merging
