// A smoothed occupancy likelihood field for scan matching (ROS-free): every cell holds
// exp(-d^2 / 2 sigma^2) of the distance d from its centre to the nearest map point or surface
// segment, so a scan point's score falls off smoothly with its distance to the map. The correlative search
// reads it at the nearest cell; the refinement reads it bicubically interpolated (as Ceres interpolates),
// which needs the smooth field (a binary grid has no gradient).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// std::lround's result (halves away from zero) without its library call: the field's lookups round
/// every scan point, and the call costs more than the lookup.
inline long roundHalfAway(double v)
{
  if (!(std::fabs(v) < 4.0e18)) return std::lround(v);  // out of long's range, or NaN: as lround does
  const long toward_zero = static_cast<long>(v);
  const double fraction = v - static_cast<double>(toward_zero);  // exact for every |v| < 2^63
  return toward_zero + (fraction >= 0.5 ? 1 : 0) - (fraction <= -0.5 ? 1 : 0);
}

class LikelihoodGrid
{
 public:
  LikelihoodGrid() = default;
  LikelihoodGrid(const LikelihoodGrid&) = default;
  LikelihoodGrid& operator=(const LikelihoodGrid&) = default;
  LikelihoodGrid(LikelihoodGrid&&) noexcept = default;
  LikelihoodGrid& operator=(LikelihoodGrid&& other) noexcept;
  /// Gives its cells, zeroed where it wrote them, to the next field this thread builds.
  ~LikelihoodGrid();
  /// Field of `points` at `resolution` [m] with spread `sigma` [m]; the grid covers the points'
  /// bounding box plus `margin` [m] (so a scan overhanging the map still reads zero, not garbage).
  LikelihoodGrid(const std::vector<linemap::Vec2>& points, double resolution, double sigma, double margin);
  /// The same with `joins`, segments between points (of `points`) on one surface: the distance is to
  /// the nearest point or join (joins shorter than sigma are left to their end points).
  LikelihoodGrid(const std::vector<linemap::Vec2>& points, const std::vector<linemap::Segment2>& joins,
                 double resolution, double sigma, double margin);

  bool empty() const { return cells_.empty(); }
  double resolution() const { return resolution_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// Centre of cell (0, 0).
  const linemap::Vec2& origin() const { return origin_; }
  /// Row-major (row = y index) cell values in [0, 1].
  const std::vector<double>& cells() const { return cells_; }

  /// The field bicubically interpolated at row r, column c (cell units from the origin; the border cells
  /// repeat outwards), with its derivatives by r and c where asked for: bit for bit what Ceres'
  /// BiCubicInterpolator over a Grid2D of cells() gives, without the column derivatives it computes for a
  /// value alone. The scoring passes read the field far more often than the solver.
  double interpolate(double r, double c, double* dfdr = nullptr, double* dfdc = nullptr) const
  {
    const int row = static_cast<int>(std::floor(r)), col = static_cast<int>(std::floor(c));
    const double x = c - col;
    double f[4], df[4];
    if (row >= 1 && col >= 1 && row + 2 < height_ && col + 2 < width_)
    {
      const double* line = cells_.data() + static_cast<std::size_t>(row - 1) * width_ + (col - 1);
      for (int i = 0; i < 4; ++i, line += width_)
        f[i] = hermite(line[0], line[1], line[2], line[3], x, dfdc ? &df[i] : nullptr);
    }
    else  // the border cells repeat outwards
    {
      int cols[4];
      for (int j = 0; j < 4; ++j) cols[j] = std::min(std::max(0, col - 1 + j), width_ - 1);
      for (int i = 0; i < 4; ++i)
      {
        const double* line =
            cells_.data() +
            static_cast<std::size_t>(std::min(std::max(0, row - 1 + i), height_ - 1)) * width_;
        f[i] =
            hermite(line[cols[0]], line[cols[1]], line[cols[2]], line[cols[3]], x, dfdc ? &df[i] : nullptr);
      }
    }
    const double value = hermite(f[0], f[1], f[2], f[3], r - row, dfdr);
    if (dfdc) *dfdc = hermite(df[0], df[1], df[2], df[3], r - row, nullptr);
    return value;
  }

  /// Value of the cell containing p; 0 outside the grid.
  double nearest(double x, double y) const
  {
    const long ix = roundHalfAway((x - origin_.x()) * inv_resolution_);
    const long iy = roundHalfAway((y - origin_.y()) * inv_resolution_);
    if (ix < 0 || iy < 0 || ix >= width_ || iy >= height_) return 0.0;
    return cells_[static_cast<std::size_t>(iy) * width_ + ix];
  }

 private:
  class NearestDistances;
  void release() noexcept;
  /// Lowers the cells within r cells of point p to their squared distance [m^2] to it (dx2: scratch).
  void writeDisc(const linemap::Vec2& p, int r, std::vector<double>& dx2, NearestDistances& nearest) const;
  /// Lowers the cells within r cells and `reach` [m] of the join `s`, and nearer its inside than its ends,
  /// to their squared distance [m^2] to it.
  void writeJoin(const linemap::Segment2& s, int r, double reach, NearestDistances& nearest) const;

  static constexpr int kTile = 8;  ///< cells are written by tiles of kTile x kTile

  /// One cubic Hermite (Catmull-Rom) spline at x in [0, 1] between p1 and p2, in the operations and the
  /// order of Ceres' CubicHermiteSpline: the value, and its derivative where asked for.
  static double hermite(double p0, double p1, double p2, double p3, double x, double* dfdx)
  {
    const double a = 0.5 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3);
    const double b = 0.5 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3);
    const double c = 0.5 * (-p0 + p2);
    if (dfdx) *dfdx = c + x * (2.0 * b + 3.0 * a * x);
    return p1 + x * (c + x * (b + x * a));
  }

  double resolution_ = 0.05, inv_resolution_ = 20.0;
  linemap::Vec2 origin_ = linemap::Vec2::Zero();
  int width_ = 0, height_ = 0;
  std::vector<double> cells_;
  std::vector<unsigned char> written_tiles_;  // per tile (row-major), whether the constructor wrote it
};

}  // namespace line_map_merging
