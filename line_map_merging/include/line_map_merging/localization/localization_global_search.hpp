// Global localization in a line map (ROS-free): an exhaustive search over every position of the map's
// bounding box and every heading, on a coarse, wide likelihood field sampled from the segments (a
// scan's score there falls off slowly with the pose error, so a coarse grid of candidate poses cannot
// step over the true one), keeping the best well-separated candidates; each is then searched again
// in its neighbourhood on a fine field (scan_matcher's correlative search). What is returned are
// hypotheses: one scan rarely tells the rooms of a building apart, the localizer decides among them
// as the robot moves.
#pragma once

#include <cstddef>
#include <vector>

#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct GlobalSearchParams
{
  double coarse_resolution = 0.25;    ///< [m] coarse field and candidate positions
  double coarse_sigma = 0.25;         ///< [m]
  double coarse_angular_step = 0.05;  ///< [rad]
  double fine_resolution = 0.05;      ///< [m]
  double fine_sigma = 0.05;           ///< [m]
  double fine_angular_step = 0.01;    ///< [rad]
  std::size_t max_points = 60;        ///< scan points of the coarse stage (evenly subsampled)
  std::size_t candidates = 30;        ///< hypotheses returned at most
  double separation = 0.75;           ///< [m] candidates nearer than this and separation_angle are one
  double separation_angle = 0.35;     ///< [rad]
  double sample_spacing = 0.02;       ///< [m] points sampled along the segments for the fields
};

class LocalizationGlobalSearch
{
 public:
  LocalizationGlobalSearch() = default;
  LocalizationGlobalSearch(const std::vector<linemap::Segment2>& segments, const GlobalSearchParams& params);

  /// Candidate poses of the frame `points` are given in, best (fine score) first; empty for an empty
  /// map or scan.
  std::vector<MatchResult> search(const std::vector<linemap::Vec2>& points) const;

  const LikelihoodGrid& fineField() const { return fine_; }
  const GlobalSearchParams& params() const { return params_; }

 private:
  GlobalSearchParams params_;
  LikelihoodGrid coarse_, fine_;
};

/// Points every `spacing` along each segment (both end points included).
std::vector<linemap::Vec2> sampleSegments(const std::vector<linemap::Segment2>& segments, double spacing);

}  // namespace line_map_merging
