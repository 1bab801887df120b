#include "line_map_merging/slam/chain_edge.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace line_map_merging
{
Eigen::Matrix2d chainEdgeTranslationWeights(const Eigen::Matrix2d& match_weights, double from_heading,
                                            double edge_sigma_xy, double odometry_sigma_xy)
{
  const double floor = std::pow(edge_sigma_xy / odometry_sigma_xy, 2.0);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(match_weights);
  const Eigen::Matrix2d local = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(floor).asDiagonal() *
                                eigen.eigenvectors().transpose();
  // A translation d in the `from` frame is R d in the local frame: d^T (R^T W R) d = (R d)^T W (R d).
  const double c = std::cos(from_heading), s = std::sin(from_heading);
  Eigen::Matrix2d r;
  r << c, -s, s, c;
  return r.transpose() * local * r;
}

}  // namespace line_map_merging
