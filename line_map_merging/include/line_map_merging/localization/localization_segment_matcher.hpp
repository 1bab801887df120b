// Scan-to-line-map matching for localization (ROS-free): every scan point is paired with the nearest
// map segment (point-to-segment distance, through a grid of segment lists) and the pose is solved by
// iteratively reweighted Gauss-Newton under a Cauchy loss, whose influence falls again with the
// distance, so points of what the map lacks (furniture, people, a moved wall) count little, held towards a
// motion prior where the segments leave a direction free (a corridor along its axis). The segments themselves
// are matched, not a grid made from them: the result is as precise as the map's lines, at any range.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// A uniform grid over the map whose cells list the segments passing through them. A nearest-segment query
/// searches rings of cells around the point, nearest first, and stops once no unsearched cell can hold a
/// nearer segment (or one within `reach`): a map of overlapping keyframe scans has many hundreds of segments
/// within reach of a point, and only those near it are measured.
class LocalizationSegmentIndex
{
 public:
  LocalizationSegmentIndex() = default;
  LocalizationSegmentIndex(std::vector<linemap::Segment2> segments, double cell_size, double reach);

  /// The segment nearest to `p` within reach, and the point of it nearest to `p`. With a `sensor`,
  /// segments whose free (left) side faces away from it are skipped: the laser sees a wall's face from
  /// its free side, never the back of the other face of the same wall.
  struct Nearest
  {
    std::size_t segment = 0;
    linemap::Vec2 closest = linemap::Vec2::Zero();
    double distance = 0.0;
  };
  std::optional<Nearest> nearest(const linemap::Vec2& p, const linemap::Vec2* sensor = nullptr) const;

  const std::vector<linemap::Segment2>& segments() const { return segments_; }
  bool empty() const { return segments_.empty(); }
  double reach() const { return reach_; }
  /// Bounding box of the segments.
  const linemap::Vec2& lower() const { return lower_; }
  const linemap::Vec2& upper() const { return upper_; }

 private:
  std::vector<linemap::Segment2> segments_;
  double cell_size_ = 0.5, reach_ = 0.5;
  linemap::Vec2 origin_ = linemap::Vec2::Zero(), lower_ = linemap::Vec2::Zero(),
                upper_ = linemap::Vec2::Zero();
  int width_ = 0, height_ = 0;
  /// A segment as a cell lists it: its start, direction (end - start) and squared length, stored in the
  /// cell's run, so that a query reads one contiguous block (a map of overlapping keyframe scans lists many
  /// hundreds of segments in a cell).
  struct Candidate
  {
    double ax, ay, dx, dy, length2;
    std::size_t segment;
  };
  std::vector<std::uint32_t> cell_start_;  ///< CSR layout: cell i lists candidates_[start[i], start[i+1])
  std::vector<Candidate> candidates_;
};

struct SegmentMatchParams
{
  double max_distance = 0.3;  ///< [m] points farther from every segment take no part
  /// [m] the same in a second solve from the first one's pose: once the pose is near, what lies this
  /// far from the map (a shelf before a wall) is left out altogether rather than merely down-weighted.
  double refine_distance = 0.1;
  double loss_scale = 0.05;      ///< [m] Cauchy scale: a residual of this size weighs half
  double point_sigma = 0.03;     ///< [m] range noise + map error of one point, scales the information
  double inlier_distance = 0.1;  ///< [m] a point this near a segment is an inlier
  int max_iterations = 15;
  bool check_free_side = true;  ///< see LocalizationSegmentIndex::nearest
};

/// A Gaussian prior on the pose (the odometry prediction).
struct PosePrior
{
  linemap::Pose2 mean;
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  ///< in (x, y, theta)
};

struct SegmentMatch
{
  linemap::Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();    ///< inverse of the full Hessian (scan + prior)
  Eigen::Matrix3d scan_information = Eigen::Matrix3d::Zero();  ///< the scan's part alone
  double score = 0.0;         ///< mean of exp(-d^2 / 2 sigma^2) over all points, d capped at max_distance
  double inlier_share = 0.0;  ///< points within inlier_distance / all points
  std::size_t inliers = 0;
  int iterations = 0;
  bool valid = false;  ///< false: no point found a segment (the pose is the initial one)
};

/// Gauss-Newton from `initial` on the points (in the frame whose pose is sought; the sensor at
/// `sensor_offset` in that frame), with the prior's residuals added when given.
SegmentMatch matchToSegments(const LocalizationSegmentIndex& index, const std::vector<linemap::Vec2>& points,
                             const linemap::Pose2& initial, const std::optional<PosePrior>& prior,
                             const SegmentMatchParams& params,
                             const linemap::Vec2& sensor_offset = linemap::Vec2::Zero());

/// Score and inlier share of `points` at `pose` without optimising.
SegmentMatch evaluateOnSegments(const LocalizationSegmentIndex& index,
                                const std::vector<linemap::Vec2>& points, const linemap::Pose2& pose,
                                const SegmentMatchParams& params,
                                const linemap::Vec2& sensor_offset = linemap::Vec2::Zero());

}  // namespace line_map_merging
