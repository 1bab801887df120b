// The laser SLAM's loop-closure search (ROS-free): a keyframe is matched against submaps around older
// keyframes near its estimate (a candidate and its neighbours, by their optimised poses), within a
// window that grows with the path travelled since the last accepted closure; coarse correlative search,
// the best few refined on the fine field, and how ambiguous the match is. Reads the keyframes and the
// graph, changes neither: whether a match goes into the graph is ClosureGate's decision.
#pragma once

#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "line_map_merging/slam/laser_slam_params.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// Where to look for closures of one keyframe.
struct LoopSearch
{
  double radius = 0.0;  ///< [m]
  double angle = 0.0;   ///< [rad]
  /// The older keyframes to match it against: nearest first within `radius`, at most loop_candidates,
  /// no two within one submap's span.
  std::vector<std::size_t> candidates;
};

/// One attempted closure of keyframe `to` against the submap around keyframe `from`.
struct LoopMatch
{
  std::size_t from = 0, to = 0;
  /// The refined match: `to`'s pose in `from`'s frame; nothing when the submap had too few points or
  /// the search found nothing.
  std::optional<MatchResult> match;
  double ambiguity = 0.0;  ///< best coarse score away from the peak / the peak's (0: not checked)
  TranslationShape shape;  ///< of the match (matchShape)
  PoseGraphEdge edge;      ///< the closure edge from -> to it measures, its information so shaped
};

class ConstraintBuilder
{
 public:
  explicit ConstraintBuilder(const LaserSlamParams& params = {}) : params_(params) {}

  /// The search for keyframe k (the newest): its window, grown with the path since the last accepted
  /// closure, and the candidates by the graph's estimate.
  LoopSearch search(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph, std::size_t k) const;
  /// Keyframe k matched against the submap around candidate j, from the graph's current estimate (an
  /// attempt, counted).
  LoopMatch match(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph, std::size_t j,
                  std::size_t k, const LoopSearch& search, SlamCounters& counters) const;
  /// A closure of a keyframe at path `path` was accepted: the window shrinks back from there.
  void closureAccepted(double path) { path_at_closure_ = path; }

 private:
  std::vector<std::size_t> loopCandidates(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                          std::size_t k, double radius) const;
  /// The refined match and its ambiguity (best coarse score away from the peak / the peak's).
  std::optional<std::pair<MatchResult, double>> matchLoop(const std::vector<SlamKeyframe>& keyframes,
                                                          const PoseGraph& graph, std::size_t candidate,
                                                          std::size_t current, const linemap::Pose2& guess,
                                                          double radius, double angle) const;

  LaserSlamParams params_;
  double path_at_closure_ = 0.0;  ///< [m] front-end path of the last accepted closure's keyframe
};

}  // namespace line_map_merging
