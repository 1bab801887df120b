// The translation shape of a matched chain edge (ROS-free): what the front end's match of the new
// keyframe determined, carried into the edge from the previous keyframe. Apart from LaserSlam so that
// the frame change can be tested at any heading.
#pragma once

#include <Eigen/Core>

namespace line_map_merging
{
/// The translation_weights of the chain edge from the previous keyframe, whose heading in the local
/// frame is `from_heading`: `match_weights` (the match's shape in the local frame, symmetric, eigenvalues
/// in [0, 1]) with every eigenvalue raised to (edge_sigma_xy / odometry_sigma_xy)^2, so that along a
/// direction the match left to the odometry the edge is as loose as an odometry edge; then expressed in
/// the previous keyframe's frame, where the edge's measurement is: R^T W R, R the rotation by
/// `from_heading`.
Eigen::Matrix2d chainEdgeTranslationWeights(const Eigen::Matrix2d& match_weights, double from_heading,
                                            double edge_sigma_xy, double odometry_sigma_xy);

}  // namespace line_map_merging
