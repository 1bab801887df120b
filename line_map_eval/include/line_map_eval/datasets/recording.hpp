// A laser recording as the dataset tools produce it (ROS-free): scans with
// odometry, the laser mounting, and optionally corrected keyframe poses.
// carmen_to_bag and simulate_world both fill one and hand it to the bag writer.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "line_extraction/types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
using linemap::Pose2;

/// Beam geometry of a scan.
struct ScanGeometry
{
  double angle_min = 0.0;
  double angle_increment = 0.0;
  std::size_t beam_count = 0;
  double range_min = 0.0;
  double range_max = 0.0;  ///< readings at or beyond this are "no return"
};

/// The extractor's view of one scan of this geometry (no copy: `ranges` must outlive it).
inline line_extraction::ScanInput scanInput(const ScanGeometry& g, const std::vector<float>& ranges)
{
  line_extraction::ScanInput input;
  input.ranges = ranges.data();
  input.count = ranges.size();
  input.angle_min = g.angle_min;
  input.angle_increment = g.angle_increment;
  input.range_min = g.range_min;
  input.range_max = g.range_max;
  return input;
}

struct RecordedScan
{
  double stamp = 0.0;         ///< seconds, strictly increasing over the recording
  std::vector<float> ranges;  ///< beam_count values [m]
  Pose2 odom;                 ///< odometry pose of base_link in odom at `stamp`
  /// This scan's own geometry where it differs from Recording::geometry (sensors that change their
  /// start angle or beam count from scan to scan); empty: the recording's.
  std::optional<ScanGeometry> geometry = std::nullopt;
};

/// A keyframe with its corrected (optimised / true) pose of base_link in map.
struct CorrectedKeyframe
{
  std::size_t scan_index = 0;  ///< index into Recording::scans
  Pose2 pose;
};

struct Recording
{
  ScanGeometry geometry;  ///< of every scan without a geometry of its own
  Pose2 base_to_laser;    ///< static mounting of the laser on base_link
  std::vector<RecordedScan> scans;
  /// Corrected keyframes in scan order (empty when there is no trajectory).
  std::vector<CorrectedKeyframe> keyframes;
  std::string source;  ///< where it came from, for captions and logs

  /// The beam geometry of `scan`, one of this recording's scans.
  const ScanGeometry& geometryOf(const RecordedScan& scan) const
  {
    return scan.geometry ? *scan.geometry : geometry;
  }
};

}  // namespace line_map_eval
