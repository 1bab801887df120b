// The Gaussian lookup table of the correlation quality metric (ROS-free): every registered
// scan point is rasterised into a grid and smeared with a truncated Gaussian kernel, so
// that each cell holds how likely an obstacle is observed there, in [0, 1].
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/metrics/bresenham.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
using linemap::Vec2;

/// Parameters of the table (keys "eval/resolution", "eval/sigma", "eval/kernel_radius").
struct LookupTableParams
{
  double resolution = 0.05;    ///< cell size [m]
  double sigma = 0.05;         ///< std of the Gaussian kernel [m]
  double kernel_radius = 3.0;  ///< truncation radius in units of sigma

  /// Reads the "eval/..." keys (absent keys keep the defaults above); throws
  /// linemap::ParameterError naming the key for malformed or impossible values.
  static LookupTableParams fromParams(const linemap::ParamSet& params);
  /// Throws linemap::ParameterError naming the offending key.
  void validate() const;
};

/// An axis-aligned grid whose cells are aligned to multiples of `resolution` in the world:
/// global cell (i, j) covers [i*res, (i+1)*res) x [j*res, (j+1)*res). The table stores the
/// window of global cells [x0, x0 + width) x [y0, y0 + height).
class LookupTable
{
 public:
  LookupTable() = default;

  /// Builds the table of world points. Normalisation: every point stamps the kernel
  /// exp(-d^2 / 2 sigma^2), d being the distance between the centres of its cell and of the
  /// stamped cell, truncated at kernel_radius * sigma, and a cell keeps the MAXIMUM of the
  /// stamps it receives (not their sum). So a cell holding a point is exactly 1, a cell at
  /// distance d from the nearest point's cell is exp(-d^2 / 2 sigma^2), every value is in
  /// [0, 1] and dense sampling of a wall does not inflate it. Throws std::invalid_argument
  /// naming the point for a non-finite point, linemap::ParameterError when the grid would
  /// exceed 10^8 cells (naming eval/resolution).
  static LookupTable build(const std::vector<Vec2>& world_points, const LookupTableParams& params);

  const LookupTableParams& params() const { return params_; }
  double resolution() const { return params_.resolution; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// Global index of the first stored column / row.
  int x0() const { return x0_; }
  int y0() const { return y0_; }
  bool empty() const { return values_.empty(); }

  /// Global cell containing a world point (floor of p / resolution).
  Cell cellOf(const Vec2& p) const;
  /// World coordinates of a global cell's centre.
  Vec2 cellCenter(const Cell& c) const;
  /// World coordinates of the lower-left corner of the stored window.
  Vec2 origin() const { return {x0_ * params_.resolution, y0_ * params_.resolution}; }

  /// Value of a global cell; 0 outside the stored window.
  float at(const Cell& c) const
  {
    const int ix = c.x - x0_, iy = c.y - y0_;
    if (ix < 0 || iy < 0 || ix >= width_ || iy >= height_) return 0.0f;
    return values_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(width_) + ix];
  }
  /// Value of the cell containing a world point.
  float valueAt(const Vec2& p) const { return at(cellOf(p)); }
  /// Row-major values, row 0 = lowest y (window-local indices).
  const std::vector<float>& values() const { return values_; }
  /// Number of cells that hold at least one point.
  std::size_t occupiedCells() const { return occupied_; }

 private:
  /// The distinct cells of the points (window-local indices); sets occupied_.
  std::vector<std::size_t> hitCells(const std::vector<Vec2>& world_points);
  /// Raises every cell around the given ones to the kernel (2 r + 1 square) value.
  void stamp(const std::vector<std::size_t>& cells, const std::vector<float>& kernel, int r);

  LookupTableParams params_;
  int x0_ = 0, y0_ = 0, width_ = 0, height_ = 0;
  std::size_t occupied_ = 0;
  std::vector<float> values_;
};

/// Appends the laser-frame points transformed by `laser_pose` (laser in world) to `out`.
void appendWorldPoints(const linemap::Pose2& laser_pose, const std::vector<Vec2>& laser_points,
                       std::vector<Vec2>& out);

/// World points of every corrected keyframe of a recording: laser pose = keyframe pose *
/// base_to_laser; a beam is a point when range_min < range < range_max and finite.
std::vector<Vec2> registeredScanPoints(const Recording& recording);
/// The same for the given keyframes of the recording's scans (e.g. a SLAM run's).
std::vector<Vec2> registeredScanPoints(const Recording& recording,
                                       const std::vector<CorrectedKeyframe>& keyframes);

}  // namespace line_map_eval
