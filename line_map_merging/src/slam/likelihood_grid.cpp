#include "line_map_merging/slam/likelihood_grid.hpp"

#include <algorithm>
#include <limits>

namespace line_map_merging
{
LikelihoodGrid::LikelihoodGrid(const std::vector<linemap::Vec2>& points, double resolution, double sigma,
                               double margin)
    : resolution_(resolution), inv_resolution_(1.0 / resolution)
{
  if (points.empty() || !(resolution > 0.0) || !(sigma > 0.0)) return;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, max_x = -min_x, max_y = -min_x;
  for (const auto& p : points)
  {
    min_x = std::min(min_x, p.x());
    min_y = std::min(min_y, p.y());
    max_x = std::max(max_x, p.x());
    max_y = std::max(max_y, p.y());
  }
  // Beyond 3 sigma the value is below 1.2 %: not worth writing.
  const double reach = 3.0 * sigma;
  margin = std::max(margin, reach + 2.0 * resolution);
  origin_ = {min_x - margin, min_y - margin};
  width_ = static_cast<int>(std::ceil((max_x - min_x + 2.0 * margin) * inv_resolution_)) + 1;
  height_ = static_cast<int>(std::ceil((max_y - min_y + 2.0 * margin) * inv_resolution_)) + 1;
  // Nearest squared distance per cell first, one exp per cell after (far fewer than per point).
  const double reach2 = reach * reach;
  cells_.assign(static_cast<std::size_t>(width_) * height_, reach2);
  const int r = static_cast<int>(std::ceil(reach * inv_resolution_));
  const double k = -0.5 / (sigma * sigma);
  for (const auto& p : points)
  {
    const double fx = (p.x() - origin_.x()) * inv_resolution_, fy = (p.y() - origin_.y()) * inv_resolution_;
    const int cx = static_cast<int>(std::lround(fx)), cy = static_cast<int>(std::lround(fy));
    for (int iy = std::max(0, cy - r); iy <= std::min(height_ - 1, cy + r); ++iy)
    {
      const double dy = (iy - fy) * resolution_;
      double* row = &cells_[static_cast<std::size_t>(iy) * width_];
      for (int ix = std::max(0, cx - r); ix <= std::min(width_ - 1, cx + r); ++ix)
      {
        const double dx = (ix - fx) * resolution_;
        row[ix] = std::min(row[ix], dx * dx + dy * dy);
      }
    }
  }
  for (double& c : cells_) c = c >= reach2 ? 0.0 : std::exp(k * c);
}

}  // namespace line_map_merging
