// Writes a Recording as a rosbag (implemented in src/ros/bag_writer.cpp; links rosbag).
#pragma once

#include <cstddef>
#include <string>

#include "line_map_eval/datasets/recording.hpp"

namespace line_map_eval
{
struct BagWriterOptions
{
  std::string scan_topic = "/scan";
  std::string trajectory_topic = "/optimized_trajectory";
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string laser_frame = "laser";
  /// Emit the trajectory (and update map->odom) every this many keyframes and at the end.
  std::size_t trajectory_every = 50;
  bool progress = true;  ///< progress bar on stderr
  /// Chunk compression: "none", "lz4" or "bz2".
  std::string compression = "none";
};

/// What writeBag wrote.
struct BagWriteSummary
{
  std::size_t scans = 0;
  std::size_t keyframes = 0;
  std::size_t trajectory_emissions = 0;  ///< nav_msgs/Path messages
  double duration = 0.0;                 ///< last minus first scan stamp [s]
  double scan_time = 0.0;                ///< median scan period written as LaserScan::scan_time [s]
};

/// Writes sensor_msgs/LaserScan on scan_topic, tf odom->base_link per scan, a
/// static base->laser on /tf_static and, when the recording has keyframes,
/// nav_msgs/Path on trajectory_topic plus tf map->odom (identity before the
/// first emission, corrected * odometry^-1 at the latest keyframe after).
/// Every message is stamped (and stored at) its scan's stamp; per scan the order is
/// /tf, scan_topic, then the trajectory when one is emitted at that keyframe.
/// Stamps must be positive and strictly increasing.
/// Throws std::runtime_error naming the file on failure.
void writeBag(const Recording& recording, const std::string& path, const BagWriterOptions& options,
              BagWriteSummary* summary = nullptr);

}  // namespace line_map_eval
