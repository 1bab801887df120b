#include "line_map_merging/slam/likelihood_grid.hpp"

#include <algorithm>
#include <limits>

namespace line_map_merging
{
namespace
{
std::vector<linemap::Segment2> asSegments(const std::vector<linemap::Vec2>& points)
{
  std::vector<linemap::Segment2> out;
  out.reserve(points.size());
  for (const auto& p : points) out.emplace_back(p, p);
  return out;
}
}  // namespace

LikelihoodGrid::LikelihoodGrid(const std::vector<linemap::Vec2>& points, double resolution, double sigma,
                               double margin)
    : LikelihoodGrid(asSegments(points), resolution, sigma, margin)
{
}

LikelihoodGrid::LikelihoodGrid(const std::vector<linemap::Segment2>& surfaces, double resolution,
                               double sigma, double margin)
    : resolution_(resolution), inv_resolution_(1.0 / resolution)
{
  if (surfaces.empty() || !(resolution > 0.0) || !(sigma > 0.0)) return;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, max_x = -min_x, max_y = -min_x;
  for (const auto& s : surfaces)
    for (const auto& p : {s.start, s.end})
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
  // Nearest squared distance per cell first, one exp per cell after (far fewer than per segment).
  const double reach2 = reach * reach;
  cells_.assign(static_cast<std::size_t>(width_) * height_, reach2);
  const int r = static_cast<int>(std::ceil(reach * inv_resolution_));
  const double k = -0.5 / (sigma * sigma);
  for (const auto& s : surfaces) writeSquaredDistances(s, r);
  for (double& c : cells_) c = c >= reach2 ? 0.0 : std::exp(k * c);
}

void LikelihoodGrid::writeSquaredDistances(const linemap::Segment2& s, int r)
{
  // In cell units, relative to the segment's start: the distance of a cell to the segment.
  const double ax = (s.start.x() - origin_.x()) * inv_resolution_,
               ay = (s.start.y() - origin_.y()) * inv_resolution_;
  const double bx = (s.end.x() - origin_.x()) * inv_resolution_,
               by = (s.end.y() - origin_.y()) * inv_resolution_;
  const double ux = bx - ax, uy = by - ay, len2 = ux * ux + uy * uy;
  const int x0 = static_cast<int>(std::lround(std::min(ax, bx))) - r;
  const int x1 = static_cast<int>(std::lround(std::max(ax, bx))) + r;
  const int y0 = static_cast<int>(std::lround(std::min(ay, by))) - r;
  const int y1 = static_cast<int>(std::lround(std::max(ay, by))) + r;
  const double len = std::sqrt(len2);
  for (int iy = std::max(0, y0); iy <= std::min(height_ - 1, y1); ++iy)
  {
    double* row = &cells_[static_cast<std::size_t>(iy) * width_];
    int from = std::max(0, x0), to = std::min(width_ - 1, x1);
    if (std::fabs(uy) > 1e-6 * len)
    {
      // Only the row's cells within reach of the segment's line (a long oblique segment's
      // bounding box is mostly far from it).
      const double c = ax + ux * (iy - ay) / uy, half = std::fabs((r + 1) * len / uy);
      from = std::max(from, static_cast<int>(std::floor(c - half)));
      to = std::min(to, static_cast<int>(std::ceil(c + half)));
    }
    for (int ix = from; ix <= to; ++ix)
    {
      double px = ix - ax, py = iy - ay;
      if (len2 > 0.0)
      {
        const double t = std::clamp((px * ux + py * uy) / len2, 0.0, 1.0);
        px -= t * ux;
        py -= t * uy;
      }
      const double dx = px * resolution_, dy = py * resolution_;
      row[ix] = std::min(row[ix], dx * dx + dy * dy);
    }
  }
}

}  // namespace line_map_merging
