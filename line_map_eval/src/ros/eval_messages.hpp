// Message conversions of the evaluator nodelet (header-only, ROS side): segments and trajectories
// in, MapQuality (every field of MapMetrics that the message carries) and the lookup table out.
#pragma once

#include <geometry_msgs/Transform.h>
#include <line_map_msgs/LineMap.h>
#include <line_map_msgs/LineSegmentArray.h>
#include <line_map_msgs/MapQuality.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <tf2/utils.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "line_map_eval/online/map_evaluator.hpp"

namespace line_map_eval
{
/// The laser poses of a trajectory of base poses (`mount`: base -> laser); a pose with a zero or
/// non-finite quaternion gets a non-finite heading (counted and skipped by the core).
inline std::vector<std::pair<double, linemap::Pose2>> toLaserPoses(const nav_msgs::Path& path,
                                                                   const linemap::Pose2& mount)
{
  std::vector<std::pair<double, linemap::Pose2>> poses;
  poses.reserve(path.poses.size());
  for (const auto& p : path.poses)
  {
    const auto& q = p.pose.orientation;
    const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    const double yaw = std::isfinite(norm) && norm > 1e-9 ? tf2::getYaw(q) : NAN;
    poses.emplace_back(p.header.stamp.toSec(),
                       linemap::Pose2(p.pose.position.x, p.pose.position.y, yaw) * mount);
  }
  return poses;
}

inline line_map_msgs::MapQuality toMessage(const MapMetrics& m, const std::string& frame,
                                           const ros::Time& stamp)
{
  line_map_msgs::MapQuality q;
  q.header.stamp = stamp;
  q.header.frame_id = frame;
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
  q.structure_coverage = m.structure_coverage.fraction() * 100.0;
  q.unmapped_structure_length = m.structure_coverage.unmapped_length;
  q.crossing_pairs = static_cast<uint32_t>(m.crossing_pairs.size());
  return q;
}

/// The lookup table as an occupancy grid (0-100).
inline nav_msgs::OccupancyGrid toGrid(const LookupTable& table, const std::string& frame,
                                      const ros::Time& stamp)
{
  nav_msgs::OccupancyGrid grid;
  grid.header.stamp = grid.info.map_load_time = stamp;
  grid.header.frame_id = frame;
  grid.info.resolution = static_cast<float>(table.resolution());
  grid.info.width = static_cast<uint32_t>(table.width());
  grid.info.height = static_cast<uint32_t>(table.height());
  grid.info.origin.position.x = table.origin().x();
  grid.info.origin.position.y = table.origin().y();
  grid.info.origin.orientation.w = 1.0;
  grid.data.resize(table.values().size());
  for (std::size_t i = 0; i < grid.data.size(); ++i)
    grid.data[i] = static_cast<int8_t>(std::lround(100.0 * table.values()[i]));
  return grid;
}

}  // namespace line_map_eval
