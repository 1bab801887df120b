// Reads a bag written by writeBag (or recorded from a live system with the same
// topics and frames) back into a Recording plus the trajectory emissions.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/online/online_drive.hpp"

namespace line_map_eval
{
struct BagContents
{
  /// Scans with odometry (odom->base_link at each scan stamp), base->laser from tf_static,
  /// and keyframes from the last trajectory emission (poses whose stamps equal a scan stamp).
  Recording recording;
  std::vector<TrajectoryEmission> trajectory;  ///< every Path message (TrajectoryEmission), in bag order
  std::vector<std::pair<double, Pose2>> map_to_odom;   ///< every map->odom sample on /tf
  std::vector<std::pair<double, Pose2>> odom_to_base;  ///< every odom->base_link sample on /tf
  std::size_t static_transforms = 0;                   ///< transforms seen on /tf_static
  std::string scan_frame;                              ///< frame_id of the scans
  /// False for a bag of scans alone (no odom -> base_link on /tf): every scan's odometry is then the
  /// identity, and without any transform at all the laser is taken to sit at base_link.
  bool odometry = true;
};

/// Topics and frame names are those of BagWriterOptions (the writer's defaults unless changed).
/// A scan whose geometry differs from the first one's keeps its own; the odometry at a scan stamp
/// is the odom->base_link sample with that exact stamp, or the interpolation of the two around it.
/// Throws std::runtime_error naming the file on failure (missing topic, a gap in the tf, ...).
BagContents readBag(const std::string& path, const BagWriterOptions& options = {});

}  // namespace line_map_eval
