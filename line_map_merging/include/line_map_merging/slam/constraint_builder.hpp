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
#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// Where to look for closures of one keyframe.
struct LoopSearch
{
  double radius = 0.0;  ///< [m] the window grown with the path since the last closure
  double angle = 0.0;   ///< [rad]
  /// The older keyframes to match it against: nearest first within their window, at most
  /// loop_candidates, no two within one submap's span.
  std::vector<std::size_t> candidates;
  /// Each candidate's window: `radius` and `angle`, widened by the suspect chain edges between it and
  /// the keyframe that no closure spans yet (capped at loop/max_radius and loop/max_angle).
  std::vector<double> radii, angles;
};

/// One attempted closure of keyframe `to` against the submap around keyframe `from`.
struct LoopMatch
{
  std::size_t from = 0, to = 0;
  /// The refined match: `to`'s pose in `from`'s frame; nothing when the submap had too few points or
  /// the search found nothing. An ambiguous one is the coarse search's best, not refined: the loop gate
  /// refuses it before its score.
  std::optional<MatchResult> match;
  double ambiguity = 0.0;  ///< best coarse score away from the peak / the peak's (0: not checked)
  TranslationShape shape;  ///< of the match (matchShape)
  /// The closure edge from -> to, its information so shaped; its measurement is the match's pose held to
  /// the estimate along the directions the match leaves open (heldToEstimate). The loop gate judges the
  /// match as found (`match->pose`): a slide shows there as a disagreement with the graph.
  PoseGraphEdge edge;
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
  /// A closure of a keyframe at path `path` went into `graph`: the window shrinks back from there, and the
  /// suspect edges a closure now spans are forgotten (a kept closure stays in the graph).
  void closureAccepted(double path, const PoseGraph& graph)
  {
    path_at_closure_ = path;
    suspects_ = openSuspects(graph);
  }
  /// The chain edge into keyframe `to` may hide a slip of this size (its match disagreed with the
  /// odometry far beyond their usual disagreement): until a closure spans it, the windows of closures
  /// across it cover where the slip may have put the keyframe.
  void suspectEdge(std::size_t to, double shift, double turn) { suspects_.push_back({to, shift, turn}); }

 private:
  struct SuspectEdge
  {
    std::size_t to = 0;
    double shift = 0.0, turn = 0.0;
  };
  /// The candidates and their windows (LoopSearch), `open` the suspect edges no closure spans.
  void chooseCandidates(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph, std::size_t k,
                        const std::vector<SuspectEdge>& open, LoopSearch& search) const;
  /// How much the `open` suspect edges between keyframes j and k widen their window: (shift, turn).
  static std::pair<double, double> slipAllowance(const PoseGraph& graph, const std::vector<SuspectEdge>& open,
                                                 std::size_t j, std::size_t k);
  /// The suspect edges no loop closure in the graph spans.
  std::vector<SuspectEdge> openSuspects(const PoseGraph& graph) const;
  /// The submap of keyframe `current`'s match against `candidate`: the candidate and its neighbours (not
  /// the recent ones) in the candidate's frame by their optimised poses, the points within reach of the
  /// scan somewhere in the search window around `guess`.
  /// The keyframes of `candidate`'s submap: its neighbours over loop_submap_path each side, but none so
  /// recent for `current` that they are part of the chain being checked.
  std::vector<std::size_t> submapOf(const std::vector<SlamKeyframe>& keyframes, std::size_t candidate,
                                    std::size_t current) const;
  /// The current keyframe's points (its frame) that, placed at `guess` in the candidate's frame, lie in some
  /// submap keyframe's view cone, widened by the search `radius` in range (submap_view.hpp).
  std::vector<linemap::Vec2> pointsInSubmapView(const std::vector<SlamKeyframe>& keyframes,
                                                const PoseGraph& graph, std::size_t candidate,
                                                std::size_t current, const linemap::Pose2& guess,
                                                double radius) const;
  std::vector<linemap::Vec2> submapPoints(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                          std::size_t candidate, std::size_t current,
                                          const linemap::Pose2& guess, double radius) const;
  /// A submap match: the refined one (an ambiguous one unrefined), its ambiguity (best coarse score away
  /// from the peak / the peak's), the coarse best and where it lay on the window's border (borderDirection),
  /// and the match's shape.
  struct Found
  {
    MatchResult match;
    double ambiguity = 0.0;
    linemap::Vec2 coarse_best = linemap::Vec2::Zero();  ///< the coarse search's best translation
    linemap::Vec2 border = linemap::Vec2::Zero();
    TranslationShape shape;
    /// On the border along a direction the match determines (half its weight or more).
    bool onDeterminedBorder() const;
  };
  std::optional<Found> matchLoop(const std::vector<SlamKeyframe>& keyframes, const PoseGraph& graph,
                                 std::size_t candidate, std::size_t current, const linemap::Pose2& guess,
                                 double radius, double angle, bool slide) const;
  /// A submap's points and their fields: the coarse one for the search, the fine one built when a match is
  /// first refined.
  struct Fields
  {
    std::vector<linemap::Vec2> points;
    LikelihoodGrid coarse;
    mutable std::optional<LikelihoodGrid> fine;
  };
  /// The coarse search of `wide` around `centre`, its best few refined unless ambiguous; rivals also among
  /// the translations of an `earlier` search, and the spread of this one's scores into `spread_out`; with
  /// `slide`, a match ambiguous only along a line is made where the line passes `centre` (alongRidge).
  std::optional<Found> searchAround(const Fields& fields, const std::vector<linemap::Vec2>& scan,
                                    const linemap::Pose2& centre, const SearchWindow& wide,
                                    const TranslationScores* earlier, TranslationScores* spread_out,
                                    bool slide) const;

  /// The best pose of the fine search one coarse cell and angular step around `start` (the fine field built
  /// when first needed), refined held towards `prior` (without one, towards that best).
  std::optional<MatchResult> refinedAround(const Fields& fields, const std::vector<linemap::Vec2>& scan,
                                           const linemap::Pose2& start,
                                           const std::optional<linemap::Pose2>& prior) const;
  /// A match ambiguous along one line through its `best` and nowhere across it (loop/ridge_closures):
  /// matched again where the line passes `estimate`, shaped to count only across the line (nothing when the
  /// line's good scores do not reach that far, or rivals lie across it).
  std::optional<Found> alongRidge(const Fields& fields, const std::vector<linemap::Vec2>& scan,
                                  const linemap::Pose2& estimate, const MatchResult& best,
                                  const TranslationScores& spread) const;

  LaserSlamParams params_;
  double path_at_closure_ = 0.0;  ///< [m] front-end path of the last accepted closure's keyframe
  std::vector<SuspectEdge> suspects_;
};

}  // namespace line_map_merging
