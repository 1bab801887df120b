// Metrics of a line map against the true walls of a simulated world (ROS-free): per wall
// coverage and endpoint error, and the vertex accuracy at the true corners.
#pragma once

#include <cstddef>
#include <vector>

#include "line_extraction/geometry.hpp"
#include "line_extraction/params.hpp"

namespace line_map_eval
{
/// Keys "eval/gt_..." (see config/line_map_eval.yaml).
struct GroundTruthParams
{
  double coverage_tolerance = 0.05;                      ///< a wall sample is covered within this [m]
  double sample_spacing = 0.01;                          ///< distance between wall samples [m]
  double association_angle = 10.0 * linemap::kPi / 180;  ///< map segment vs wall, undirected [rad]
  double association_distance = 0.2;                     ///< map segment midpoint to the wall [m]
  double corner_tolerance = 0.01;                        ///< wall endpoints this close meet [m]
  double corner_min_angle = 20.0 * linemap::kPi / 180;   ///< walls meeting straighter are no corner [rad]
  double vertex_radius = 0.3;                            ///< map endpoints within this of a corner [m]

  static GroundTruthParams fromParams(const linemap::ParamSet& params);
  void validate() const;
};

struct WallScore
{
  double length = 0.0;  ///< [m]
  double coverage =
      0.0;  ///< fraction of the wall's samples within coverage_tolerance of an associated segment
  /// Larger of the two wall endpoints' distances to the nearest endpoint of an associated map
  /// segment [m]; +infinity when no map segment is associated.
  double endpoint_error = 0.0;
  std::size_t associated = 0;  ///< map segments associated with the wall
};

struct CornerScore
{
  linemap::Vec2 corner = linemap::Vec2::Zero();
  double vertex_error = 0.0;  ///< sum of distances from the corner to the map endpoints near it [m]
  std::size_t endpoints = 0;  ///< map endpoints within vertex_radius
};

struct GroundTruthResult
{
  std::vector<WallScore> walls;
  std::vector<CornerScore> corners;
  double coverage = 0.0;             ///< length-weighted mean wall coverage in [0, 1]
  double max_endpoint_error = 0.0;   ///< over the walls with an associated segment [m]
  std::size_t undetected_walls = 0;  ///< walls without any associated map segment
  double mean_vertex_error = 0.0;    ///< mean over the corners with endpoints of their vertex_error [m]
  std::size_t missed_corners = 0;    ///< corners without any map endpoint within vertex_radius
};

/// A map segment is associated with a wall when their undirected heading difference is at
/// most association_angle and its midpoint lies within association_distance of the wall
/// segment. Coverage samples the wall every <= sample_spacing (both ends included) and counts
/// the samples within coverage_tolerance of an associated map segment, so a perpendicular wall's
/// segment ending at a corner does not count as covering it. A corner is a point where the
/// endpoints of two walls lie within corner_tolerance and the walls' undirected headings differ
/// by at least corner_min_angle (collinear continuations are not corners); its position is the
/// mean of those endpoints, and corners closer than corner_tolerance are one. Vertex accuracy
/// (the three-criteria paper's measure): per corner, the sum of the distances from the corner to
/// every map segment endpoint within vertex_radius. Throws std::invalid_argument naming the wall
/// or segment for non-finite coordinates or a zero-length wall.
GroundTruthResult evaluateAgainstGroundTruth(const std::vector<linemap::Segment2>& walls,
                                             const std::vector<linemap::Segment2>& map,
                                             const GroundTruthParams& params);

/// The corners of a set of walls as defined above.
std::vector<linemap::Vec2> findCorners(const std::vector<linemap::Segment2>& walls,
                                       const GroundTruthParams& params);

}  // namespace line_map_eval
