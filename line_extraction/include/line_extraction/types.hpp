// Core data types of the line extraction library (ROS-free).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_extraction
{
using linemap::Vec2;

/// A laser scan as any source gives it (sensor_msgs/LaserScan, CARMEN, simulator).
/// Beam i has angle angle_min + i * angle_increment. Nothing is owned.
struct ScanInput
{
  const float* ranges = nullptr;
  std::size_t count = 0;
  double angle_min = 0.0;
  double angle_increment = 0.0;
  double range_min = 0.0;
  double range_max = 0.0;
  /// Optional intensities; when intensity_count > 0 it must equal count.
  const float* intensities = nullptr;
  std::size_t intensity_count = 0;
};

/// The ScanInput of a message with sensor_msgs/LaserScan's fields, pointing into it (a template, so
/// that the core needs no ROS).
template <class LaserScan>
ScanInput scanInputOf(const LaserScan& msg)
{
  ScanInput scan;
  scan.ranges = msg.ranges.data();
  scan.count = msg.ranges.size();
  scan.angle_min = msg.angle_min;
  scan.angle_increment = msg.angle_increment;
  scan.range_min = msg.range_min;
  scan.range_max = msg.range_max;
  scan.intensities = msg.intensities.data();
  scan.intensity_count = msg.intensities.size();
  return scan;
}

/// The valid points of one scan, in beam order, in the laser frame.
/// Filled by Preprocessor; buffers keep their capacity between scans.
struct PreparedScan
{
  std::vector<Vec2> points;
  std::vector<double> ranges;    ///< range of each point [m]
  std::vector<double> angles;    ///< beam angle of each point [rad]
  std::vector<int> beam_index;   ///< index of each point in ScanInput::ranges
  double angle_increment = 0.0;  ///< of the source scan (for beam prediction)
  /// True when the beams cover the full circle, so the last point neighbours the first.
  bool full_circle = false;
  /// Per point: sigma(r) / sigma_0 of the sensor model (SensorModel::annotate); a distance
  /// tolerance set for the base noise is multiplied by it. Empty: 1 everywhere.
  std::vector<double> noise_scale;
  /// Per point i > 0: the squared distance the pair (i-1, i) may span on one surface when their
  /// beams are neighbours; 0 where the model adds nothing. Empty: 0 everywhere.
  std::vector<double> gap2;

  /// The tolerance `base` at point i.
  double tolerance(int i, double base) const
  {
    return noise_scale.empty() ? base : base * noise_scale[static_cast<std::size_t>(i)];
  }
  /// The squared gap the pair (i-1, i) may span: the larger of `fixed2` and the model's.
  double maxGap2(int i, double fixed2) const
  {
    return gap2.empty() ? fixed2 : std::max(fixed2, gap2[static_cast<std::size_t>(i)]);
  }
  /// Whether points i-1 and i are farther apart than the gap allows.
  bool gapBefore(int i, double fixed2) const
  {
    return (points[static_cast<std::size_t>(i)] - points[static_cast<std::size_t>(i) - 1]).squaredNorm() >
           maxGap2(i, fixed2);
  }

  std::size_t size() const { return points.size(); }
  void clear()
  {
    points.clear();
    ranges.clear();
    angles.clear();
    beam_index.clear();
    noise_scale.clear();
    gap2.clear();
  }
};

/// A contiguous range [begin, end) of PreparedScan points (a breakpoint cluster).
struct PointRange
{
  int begin = 0;
  int end = 0;
  int size() const { return end - begin; }
};

/// An extracted segment, in the laser frame.
struct Segment
{
  /// The extreme member points projected onto the line; LineExtractor orders them so that the
  /// sensor lies left of start -> end (orientFreeSideLeft), whatever the algorithm's order.
  Vec2 start = Vec2::Zero();
  Vec2 end = Vec2::Zero();
  double angle = 0.0;   ///< Hessian form: x cos(angle) + y sin(angle) = radius
  double radius = 0.0;  ///< >= 0
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< of (radius, angle)
  int num_points = 0;
  /// Member point indices (into PreparedScan) are
  /// ExtractionResult::point_indices[index_begin, index_end), in scan order.
  int index_begin = 0;
  int index_end = 0;

  double length() const { return (end - start).norm(); }
};

/// Output of an extractor. Reused between scans so the hot path does not allocate.
struct ExtractionResult
{
  std::vector<Segment> segments;
  std::vector<int> point_indices;

  void clear()
  {
    segments.clear();
    point_indices.clear();
  }
};

}  // namespace line_extraction
