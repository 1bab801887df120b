// The laser SLAM's acceptance of loop closures (ROS-free): a matched closure (ConstraintBuilder) goes
// into the pose graph only when it scores well, is unambiguous and is consistent with the graph
// (chi-square gate on relativeCovariance); one the estimate already meets is added without optimising,
// one far off waits for a corroborating second closure when asked to (loop_corroborate_*), and one the
// optimised graph still misses is removed again. A closure refused as inconsistent is not forgotten: when
// enough of the recent ones agree with each other (closure_consensus.hpp) they outvote the chain. Records
// every attempt's outcome and counts them. Not thread-safe: the caller serialises the calls.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "line_map_merging/slam/constraint_builder.hpp"
#include "line_map_merging/slam/laser_slam_params.hpp"
#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// What became of a closure in the graph.
struct ClosureVerdict
{
  bool accepted = false;   ///< in the graph
  bool optimized = false;  ///< and the graph was optimised with it (its poses changed)
};

class ClosureGate
{
 public:
  explicit ClosureGate(const LaserSlamParams& params = {});

  /// Decides on `match` (of keyframes already in `graph`): adds its edge (and a corroborated pending
  /// closure's) and optimises, or leaves the graph as it was. Records the attempt, counts into `counters`.
  ClosureVerdict consider(const LoopMatch& match, PoseGraph& graph, SlamCounters& counters);
  /// The front end's typical match score (LocalTrajectoryBuilder::runScore): what the closures' score
  /// floor is relative to (LaserSlamParams::loopMinScore).
  void setFrontEndScore(double score) { front_end_score_ = score; }
  /// Every closure attempt that got as far as a match, in order.
  const std::vector<ClosureAttempt>& attempts() const { return attempts_; }

 private:
  /// The match's score and ambiguity: false (the refusal counted and recorded) when it goes no further.
  bool passesScreening(const LoopMatch& match, std::size_t attempt, SlamCounters& counters);
  /// Whether closure edge e (not yet in the graph) disagrees with the estimate by no more than the
  /// consistency gate allows, in the metric of its covariance plus the estimate's (relativeCovariance).
  bool consistentWithGraph(const PoseGraph& graph, const PoseGraphEdge& e) const;
  /// A closure (edge `added[0]`, `relative` pose of k from j) that disagrees with the estimate by
  /// `size` and `theta_error`: sets its loss, adds a corroborating pending closure to `added`, or
  /// leaves it pending (removed from the graph; false).
  bool admitDisagreeing(PoseGraph& graph, std::size_t j, std::size_t k, const PoseGraphEdge& e,
                        const linemap::Pose2& relative, double size, double theta_error,
                        std::vector<std::size_t>& added, SlamCounters& counters);
  /// Whether the pending closure implies the same correction of keyframe k as one putting it at
  /// `implied`.
  bool corroborates(const PoseGraph& graph, std::size_t k, const linemap::Pose2& implied) const;
  /// Keeps the closure just refused as inconsistent among the recent ones; when loop_consensus of them
  /// agree with each other, adds them all and optimises (kept or removed as optimizeKeeping decides).
  ClosureVerdict outvoteChain(const LoopMatch& match, std::size_t attempt, PoseGraph& graph,
                              SlamCounters& counters);
  /// Of the mutually agreeing refused closures `agreeing` (indices into `edges`), those whose older keyframes
  /// lie more than two submap spans from every one kept before them.
  std::vector<std::size_t> independentVotes(const std::vector<PoseGraphEdge>& edges,
                                            const std::vector<std::size_t>& agreeing) const;
  /// The Cauchy scale of a closure that disagrees with the estimate by `size` (in its own metric): wide
  /// enough to apply the correction it is for (loop_scale_by_disagreement), never below loop_loss_scale.
  double disagreementScale(double size) const;
  /// Optimises the graph with the closure edges `added`; when the optimised graph misses one of them
  /// by more than loop_max_error_*, removes them and restores the poses. Whether they stayed.
  bool optimizeKeeping(PoseGraph& graph, std::vector<std::size_t> added, SlamCounters& counters) const;

  LaserSlamParams params_;
  double front_end_score_ = 0.0;
  double consistency_gate_;  ///< chi-square quantile of loop_consistency_probability (infinite: off)
  struct PendingClosure
  {
    PoseGraphEdge edge;
    linemap::Pose2 implied;  ///< where the closure puts its keyframe
    std::size_t to;
    std::size_t attempt;  ///< its entry in attempts_
  };
  std::optional<PendingClosure> pending_;
  /// The newest loop_consensus_waiting closures refused as inconsistent, oldest first.
  struct RefusedClosure
  {
    PoseGraphEdge edge;
    std::size_t attempt;  ///< its entry in attempts_
    bool degenerate;      ///< its match left a direction open
  };
  std::vector<RefusedClosure> refused_;
  std::vector<ClosureAttempt> attempts_;
};

}  // namespace line_map_merging
