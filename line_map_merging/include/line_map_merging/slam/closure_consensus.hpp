// Loop closures judged against each other, not only against the chain (ROS-free). A front-end slip
// makes the chain's estimate wrong by more than its covariance admits, so the chi-square gate refuses
// every true closure across the slip and the error is locked in. Two closures that are both true
// agree with each other whatever the chain did between them, up to the little the chain adds over the
// short stretches that join their ends: the cycle closure a, the graph from a's newer keyframe to
// b's, closure b backwards and the graph back to a's older keyframe is the identity within its
// propagated covariance (pairwise consistency, as in Olson's single-cluster spectral graph
// partitioning and Mangelson et al.'s pairwise consistent measurement sets). A group of such closures
// from different keyframes outvotes the chain; a false match rarely repeats itself consistently.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "line_map_merging/slam/pose_graph.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// A relative pose with the first-order covariance of its parameters (x, y in its `from` frame,
/// heading), the convention of relativeCovariance and edgeCovariance.
struct UncertainPose
{
  linemap::Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

/// a then b (b's `from` frame is a's `to` frame), the two independent.
UncertainPose compose(const UncertainPose& a, const UncertainPose& b);
/// The same relative pose the other way round.
UncertainPose inverse(const UncertainPose& a);

/// Two closures judged together: the chi-square (3 degrees of freedom) of their cycle (see
/// pairwiseDisagreement), and of the larger of their corrections of the graph (a closure's measurement
/// against the graph's estimate) in the cycle's metric: how well the cycle could tell that correction
/// from none. Their agreement is evidence only when this exceeds the gate.
struct PairwiseCheck
{
  double disagreement = 0.0;
  double larger_correction = 0.0;
};
PairwiseCheck checkPair(const PoseGraph& graph, const PoseGraphEdge& a, const PoseGraphEdge& b);

/// Chi-square (3 degrees of freedom) of the cycle a, graph a.to -> b.to, b backwards, graph b.from ->
/// a.from, in the metric of its propagated covariance (the closures' own plus relativeCovariance of
/// the two graph stretches). Infinite when the graph joins neither pair of ends.
double pairwiseDisagreement(const PoseGraph& graph, const PoseGraphEdge& a, const PoseGraphEdge& b);

/// The largest set of `closures` holding `newest` whose members are pairwise within `gate`
/// (pairwiseDisagreement) by a cycle tight enough to tell their corrections from none (checkPair),
/// grown greedily from the closures most consistent with `newest`; indices
/// into `closures`, `newest` first.
std::vector<std::size_t> consistentGroup(const PoseGraph& graph, const std::vector<PoseGraphEdge>& closures,
                                         std::size_t newest, double gate);

/// How many different `to` keyframes the closures `group` (indices into `closures`) have.
std::size_t distinctKeyframes(const std::vector<PoseGraphEdge>& closures,
                              const std::vector<std::size_t>& group);

}  // namespace line_map_merging
