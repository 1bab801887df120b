// Total-least-squares line fitting with incremental sums (implemented in src/line_fit.cpp).
#pragma once

#include <Eigen/Core>

#include "line_extraction/types.hpp"

namespace line_extraction
{
/// Running sums of points so that adding or removing one point is O(1).
struct LineSums
{
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;

  void add(const Vec2& p)
  {
    n += 1.0;
    sx += p.x();
    sy += p.y();
    sxx += p.x() * p.x();
    syy += p.y() * p.y();
    sxy += p.x() * p.y();
  }
  void remove(const Vec2& p)
  {
    n -= 1.0;
    sx -= p.x();
    sy -= p.y();
    sxx -= p.x() * p.x();
    syy -= p.y() * p.y();
    sxy -= p.x() * p.y();
  }
  void clear() { *this = LineSums(); }
};

/// A fitted infinite line in Hessian form with the covariance of (radius, angle).
struct LineFit
{
  double angle = 0.0;   ///< x cos(angle) + y sin(angle) = radius
  double radius = 0.0;  ///< >= 0
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< of (radius, angle)
  double sum_squared_residuals = 0.0;
  bool valid = false;  ///< false for fewer than 2 points or all points coincident

  /// Signed distance of p from the line.
  double signedDistance(const Vec2& p) const
  {
    return p.x() * std::cos(angle) + p.y() * std::sin(angle) - radius;
  }
};

/// Total-least-squares fit of the points summarised by `sums`. The covariance
/// follows from isotropic point noise with standard deviation `range_sigma` [m].
LineFit fitLine(const LineSums& sums, double range_sigma);

/// Builds a Segment from a fit and its member points: endpoints are the first
/// and last member projected onto the line; appends `members` to out.point_indices.
void appendSegment(const PreparedScan& scan, const LineFit& fit, const int* members, int count,
                   ExtractionResult& out);

}  // namespace line_extraction
