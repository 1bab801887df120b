// Fusion conditions and segment fusion of CAE-RLSM (Wen et al., IEEE TIM 2019), shared by
// every merger of this package. All segments are in world (map) coordinates.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

/// How fused segments weigh their members.
enum class FusionWeighting
{
  /// The paper's: every member (update) weighs 1; the line runs through the mean barycentre along
  /// the mean unit heading.
  count,
  /// Total least squares over the members' length: the line minimising the squared distance
  /// integrated along every member, so a 5 m wall seen whole outweighs a 0.6 m glimpse of it.
  length,
};

/// Thresholds of the three fusion conditions, and the weighting of the fusion.
struct FusionParams
{
  FusionWeighting weighting = FusionWeighting::length;
  double max_angle = 4.0 * linemap::kPi / 180.0;  ///< theta_max [rad]
  double max_distance = 0.10;                     ///< d_max [m]
  double min_overlap = -0.10;                     ///< p_min [m]; negative: a gap up to |p_min| still fuses

  /// Reads "fusion/max_angle", "fusion/max_distance", "fusion/min_overlap", "fusion/weighting"
  /// ("length" or "count"); throws
  /// linemap::ParameterError naming the key when a value is malformed or out of range.
  static FusionParams fromParams(const linemap::ParamSet& params);
  void validate() const;
  /// Padding of a map segment's bounding box such that every scan segment meeting the
  /// conditions with it intersects the padded box: d_max + max(0, -p_min).
  double searchPadding() const;
};

/// |normalizeAngle(theta_M - theta_S)|: opposite headings give pi, not 0.
double headingDeviation(const Segment2& map, const Segment2& scan);
/// The larger distance of the scan segment's endpoints to the infinite line of the map segment.
double verticalDistance(const Segment2& map, const Segment2& scan);
/// Length of the overlap between the map segment and the projection of the scan segment onto its
/// line; negative when they are apart (minus the gap).
double horizontalOverlap(const Segment2& map, const Segment2& scan);
/// All three conditions: heading deviation <= max_angle, vertical distance <= max_distance,
/// horizontal overlap >= min_overlap.
bool meetsFusionConditions(const Segment2& map, const Segment2& scan, const FusionParams& params);
/// Whether two map segments are redundant with each other: the conditions hold with either one as
/// the map segment M (they are asymmetric: a short segment beside a long one meets them one way).
bool meetEachOther(const Segment2& a, const Segment2& b, const FusionParams& params);

/// Whether `inner` lies wholly inside the fusion band of `outer`: it faces the same side (heading
/// deviation below 90 deg, so the other face of a wall never qualifies), both its endpoints lie within
/// d_max of outer's line, and both project onto outer itself. Such a segment describes nothing outer
/// does not; its heading, fitted over a shorter baseline, may still differ by more than theta_max
/// (at most asin(2 d_max / its length)).
bool liesWithin(const Segment2& outer, const Segment2& inner, const FusionParams& params);

struct WeightedSegment
{
  Segment2 segment;
  double weight = 1.0;  ///< how many times the segment was updated (original segments: 1)
};

/// Sufficient statistics of a weighted fusion, for both weightings: weight, sum of weighted
/// barycentres and of weighted unit heading vectors (count), and the length-weighted first and
/// second moments of the members seen as uniform mass along their length (length). Adding the
/// moments of a fused group equals adding its members, so a map segment that keeps the moments of
/// its leaves fuses exactly like its leaves would.
struct FusionMoments
{
  double weight = 0.0;
  Vec2 centroid_sum = Vec2::Zero();
  Vec2 direction_sum = Vec2::Zero();
  /// Length-weighted moments, about `reference` (the first member's midpoint) so that squares of
  /// map coordinates do not cost precision: mass = sum w L, first = sum w L (c - ref), second =
  /// sum w L ((c - ref)(c - ref)^T + d d^T / 12) for midpoint c and d = end - start.
  double mass = 0.0;
  Vec2 reference = Vec2::Zero();
  Vec2 first = Vec2::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();

  void add(const Segment2& s, double w = 1.0);
  void add(const FusionMoments& m);
  /// The line's point: the mean barycentre (count) or the centre of mass (length).
  Vec2 centroid(FusionWeighting weighting = FusionWeighting::count) const;
  /// Unit vector of the line: the weighted mean heading (count) or the principal axis of the mass
  /// (length), pointing the way of the members' summed headings (the orientation convention).
  Vec2 direction(FusionWeighting weighting = FusionWeighting::count) const;
};

/// The fused line of `moments` (through the centroid, along the direction) clipped to the
/// farthest projections of the points given to include().
class FusedLine
{
 public:
  explicit FusedLine(const FusionMoments& moments, FusionWeighting weighting = FusionWeighting::count);
  void include(const Vec2& p);
  void include(const Segment2& s)
  {
    include(s.start);
    include(s.end);
  }
  Segment2 segment() const;

 private:
  Vec2 origin_;
  Vec2 direction_;
  double t_min_;
  double t_max_;
};

/// Fusion of weighted segments. count: barycentre = weighted mean of barycentres, heading =
/// weighted mean of the unit heading vectors; length: the total-least-squares line of the members'
/// mass (weight times length). Endpoints = extreme projections of all endpoints onto the fused
/// line. Throws std::invalid_argument for an empty set or a non-positive total weight.
Segment2 fuse(const std::vector<WeightedSegment>& segments,
              FusionWeighting weighting = FusionWeighting::count);

/// Largest coordinate [m] a segment or keyframe position may have (10,000 km). Beyond it the sums
/// of squares that fusion keeps overflow, so such input is refused like non-finite input.
constexpr double kMaxCoordinate = 1e7;

/// True when both endpoints are finite, within kMaxCoordinate and distinct.
bool isValidSegment(const Segment2& s);

}  // namespace line_map_merging
