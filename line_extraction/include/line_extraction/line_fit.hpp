// Total-least-squares line fitting with incremental sums (implemented in src/line_fit.cpp).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

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

  LineSums& operator+=(const LineSums& o)
  {
    n += o.n;
    sx += o.sx;
    sy += o.sy;
    sxx += o.sxx;
    syy += o.syy;
    sxy += o.sxy;
    return *this;
  }
  LineSums& operator-=(const LineSums& o)
  {
    n -= o.n;
    sx -= o.sx;
    sy -= o.sy;
    sxx -= o.sxx;
    syy -= o.syy;
    sxy -= o.sxy;
    return *this;
  }
};

inline LineSums operator-(LineSums a, const LineSums& b)
{
  return a -= b;
}
inline LineSums operator+(LineSums a, const LineSums& b)
{
  return a += b;
}

/// A fitted infinite line in Hessian form with the covariance of (radius, angle).
struct LineFit
{
  double angle = 0.0;                                    ///< x cos(angle) + y sin(angle) = radius
  double radius = 0.0;                                   ///< >= 0
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< of (radius, angle)
  double sum_squared_residuals = 0.0;
  bool valid = false;            ///< false for fewer than 2 points or all points coincident
  Vec2 normal = Vec2(1.0, 0.0);  ///< (cos angle, sin angle), kept to spare callers the trigonometry

  /// Signed distance of p from the line.
  double signedDistance(const Vec2& p) const { return p.dot(normal) - radius; }
};

/// Total-least-squares fit of the points summarised by `sums`. The covariance
/// follows from isotropic point noise with standard deviation `range_sigma` [m].
LineFit fitLine(const LineSums& sums, double range_sigma);

/// The noise scale of a segment whose first and last members are points `first` and `last`: the
/// mean of theirs (the range noise is linear in range). The fit's covariance, computed for
/// sigma_0, is multiplied by its square.
inline double membersNoiseScale(const PreparedScan& scan, int first, int last)
{
  return 0.5 * (scan.tolerance(first, 1.0) + scan.tolerance(last, 1.0));
}

/// Builds a Segment from a fit and its member points: endpoints are the first
/// and last member projected onto the line; appends `members` to out.point_indices.
/// The covariance is scaled by membersNoiseScale squared.
void appendSegment(const PreparedScan& scan, const LineFit& fit, const int* members, int count,
                   ExtractionResult& out);

/// Same for the contiguous members [members.begin, members.end).
void appendSegment(const PreparedScan& scan, const LineFit& fit, PointRange members, ExtractionResult& out);

/// Sums of the points [begin, end) of scan.
LineSums sumRange(const PreparedScan& scan, int begin, int end);

/// A fitted line as unit normal and radius, for hot loops that need distances only.
struct LineNormal
{
  double nx = 1.0, ny = 0.0, radius = 0.0;
  double signedDistance(const Vec2& p) const { return p.x() * nx + p.y() * ny - radius; }
  double distance(const Vec2& p) const { return std::abs(signedDistance(p)); }
};

/// The total-least-squares line of `sums` without trigonometric calls or covariance
/// (same line as fitLine); false for fewer than 2 points or coincident points.
bool fitNormal(const LineSums& sums, LineNormal& out);

/// Cumulative sums over a scan: the sums of any contiguous range in O(1).
class PrefixSums
{
 public:
  /// Prepares sums of the points [range.begin, range.end); keeps capacity between calls.
  void build(const PreparedScan& scan, PointRange range);
  /// Sums of the points [begin, end), begin/end inside the built range.
  LineSums sums(int begin, int end) const { return cum_[end - offset_] - cum_[begin - offset_]; }

 private:
  std::vector<LineSums> cum_;
  int offset_ = 0;
};

/// Resolves the shared points of consecutive contiguous segments (in scan order):
/// when segment k+1 starts before segment k ends, each contested point goes to the
/// line it is nearer to, splitting where the two distances cross. Touching segments
/// (k+1 starts where k ends) contest the two points at the junction. Segments left with
/// fewer than 2 points get size 0 (callers skip them). `prefix`, when given, must
/// cover the segments and saves summing their points again.
void resolveOverlaps(const PreparedScan& scan, std::vector<PointRange>& segments,
                     const PrefixSums* prefix = nullptr);

}  // namespace line_extraction
