#include "line_map_eval/metrics/lookup_table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
namespace
{
constexpr double kMaxCells = 1e8;  // 400 MB of floats: beyond that the resolution is a mistake
}

LookupTableParams LookupTableParams::fromParams(const linemap::ParamSet& params)
{
  return linemap::readValidated<LookupTableParams>(
      params, {{"eval/resolution", &LookupTableParams::resolution},
               {"eval/sigma", &LookupTableParams::sigma},
               {"eval/kernel_radius", &LookupTableParams::kernel_radius}});
}

void LookupTableParams::validate() const
{
  if (!(resolution > 0.0) || !std::isfinite(resolution))
    throw linemap::ParameterError("parameter 'eval/resolution' must be a positive number of metres, got " +
                                  std::to_string(resolution));
  if (!(sigma > 0.0) || !std::isfinite(sigma))
    throw linemap::ParameterError("parameter 'eval/sigma' must be a positive number of metres, got " +
                                  std::to_string(sigma));
  if (!(kernel_radius > 0.0) || kernel_radius > 10.0)
    throw linemap::ParameterError("parameter 'eval/kernel_radius' must be in (0, 10] sigmas, got " +
                                  std::to_string(kernel_radius));
  if (kernel_radius * sigma / resolution > 1000.0)
    throw linemap::ParameterError(
        "parameters 'eval/sigma' / 'eval/resolution': kernel of more than 1000 cells");
}

Cell LookupTable::cellOf(const Vec2& p) const
{
  return {static_cast<int>(std::floor(p.x() / params_.resolution)),
          static_cast<int>(std::floor(p.y() / params_.resolution))};
}

Vec2 LookupTable::cellCenter(const Cell& c) const
{
  return {(c.x + 0.5) * params_.resolution, (c.y + 0.5) * params_.resolution};
}

namespace
{
/// The bounding box of the points, which must all be finite.
void boundingBox(const std::vector<Vec2>& points, double& min_x, double& min_y, double& max_x, double& max_y)
{
  min_x = std::numeric_limits<double>::infinity();
  min_y = min_x;
  max_x = -min_x;
  max_y = -min_x;
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const Vec2& p = points[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()))
      throw std::invalid_argument("lookup table: scan point " + std::to_string(i) + " is not finite");
    min_x = std::min(min_x, p.x());
    min_y = std::min(min_y, p.y());
    max_x = std::max(max_x, p.x());
    max_y = std::max(max_y, p.y());
  }
}

/// The kernel on cell offsets (2 r + 1 square, row-major), circularly truncated at radius_m.
std::vector<float> kernelOf(int r, double res, double radius_m, double sigma)
{
  const int k = 2 * r + 1;
  std::vector<float> kernel(static_cast<std::size_t>(k * k), 0.0f);
  const double inv2s2 = 1.0 / (2.0 * sigma * sigma);
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
    {
      const double d2 = (dx * dx + dy * dy) * res * res;
      if (d2 <= radius_m * radius_m * (1.0 + 1e-12))
        kernel[static_cast<std::size_t>((dy + r) * k + dx + r)] = static_cast<float>(std::exp(-d2 * inv2s2));
    }
  return kernel;
}
}  // namespace

LookupTable LookupTable::build(const std::vector<Vec2>& world_points, const LookupTableParams& params)
{
  params.validate();
  LookupTable t;
  t.params_ = params;
  if (world_points.empty()) return t;

  const double res = params.resolution;
  double min_x, min_y, max_x, max_y;
  boundingBox(world_points, min_x, min_y, max_x, max_y);
  // Kernel half-width in cells; the window keeps one spare cell beyond it on each side.
  const double radius_m = params.kernel_radius * params.sigma;
  const int r = static_cast<int>(std::floor(radius_m / res + 1e-9));  // 3 sigma = 3 cells stays 3
  const double wx = std::floor(max_x / res) - std::floor(min_x / res) + 2.0 * r + 3.0;
  const double wy = std::floor(max_y / res) - std::floor(min_y / res) + 2.0 * r + 3.0;
  if (wx * wy > kMaxCells || std::abs(min_x / res) > 1e9 || std::abs(max_x / res) > 1e9 ||
      std::abs(min_y / res) > 1e9 || std::abs(max_y / res) > 1e9)
    throw linemap::ParameterError("parameter 'eval/resolution' (" + std::to_string(res) +
                                  " m) is too fine for " + std::to_string(max_x - min_x) + " x " +
                                  std::to_string(max_y - min_y) + " m of scan points (more than 1e8 cells)");
  t.x0_ = static_cast<int>(std::floor(min_x / res)) - r - 1;
  t.y0_ = static_cast<int>(std::floor(min_y / res)) - r - 1;
  t.width_ = static_cast<int>(wx);
  t.height_ = static_cast<int>(wy);
  t.values_.assign(static_cast<std::size_t>(t.width_) * static_cast<std::size_t>(t.height_), 0.0f);
  t.stamp(t.hitCells(world_points), kernelOf(r, res, radius_m, params.sigma), r);
  return t;
}

std::vector<std::size_t> LookupTable::hitCells(const std::vector<Vec2>& world_points)
{
  // Hits first: a wall sampled every centimetre puts many points into one cell, and
  // stamping each distinct cell once is what keeps the table fast.
  const std::size_t w = static_cast<std::size_t>(width_);
  std::vector<std::uint8_t> hit(values_.size(), 0);
  std::vector<std::size_t> cells;
  cells.reserve(world_points.size() / 4 + 16);
  for (const Vec2& p : world_points)
  {
    const Cell c = cellOf(p);
    const std::size_t idx = static_cast<std::size_t>(c.y - y0_) * w + static_cast<std::size_t>(c.x - x0_);
    if (!hit[idx])
    {
      hit[idx] = 1;
      cells.push_back(idx);
    }
  }
  occupied_ = cells.size();
  return cells;
}

void LookupTable::stamp(const std::vector<std::size_t>& cells, const std::vector<float>& kernel, int r)
{
  const std::size_t w = static_cast<std::size_t>(width_);
  const int k = 2 * r + 1;
  for (const std::size_t idx : cells)
  {
    const std::size_t cy = idx / w, cx = idx % w;  // r + 1 <= cx < width - r - 1: no bounds checks
    for (int dy = -r; dy <= r; ++dy)
    {
      float* row = &values_[(cy + dy) * w + cx - r];
      const float* krow = &kernel[static_cast<std::size_t>((dy + r) * k)];
      for (int i = 0; i < k; ++i) row[i] = std::max(row[i], krow[i]);
    }
  }
}

void appendWorldPoints(const linemap::Pose2& laser_pose, const std::vector<Vec2>& laser_points,
                       std::vector<Vec2>& out)
{
  const double c = std::cos(laser_pose.theta), s = std::sin(laser_pose.theta);
  // No exact reserve here: called once per scan, it would defeat the vector's geometric growth.
  for (const Vec2& p : laser_points)
    out.emplace_back(c * p.x() - s * p.y() + laser_pose.x, s * p.x() + c * p.y() + laser_pose.y);
}

std::vector<Vec2> registeredScanPoints(const Recording& recording)
{
  return registeredScanPoints(recording, recording.keyframes);
}

std::vector<Vec2> registeredScanPoints(const Recording& recording,
                                       const std::vector<CorrectedKeyframe>& keyframes)
{
  std::vector<Vec2> out;
  out.reserve(keyframes.size() * recording.geometry.beam_count);
  std::vector<Vec2> local;
  for (const CorrectedKeyframe& kf : keyframes)
  {
    if (kf.scan_index >= recording.scans.size())
      throw std::invalid_argument("recording '" + recording.source + "': keyframe scan_index " +
                                  std::to_string(kf.scan_index) + " beyond " +
                                  std::to_string(recording.scans.size()) + " scans");
    const RecordedScan& scan = recording.scans[kf.scan_index];
    const ScanGeometry& g = recording.geometryOf(scan);
    local.clear();
    for (std::size_t i = 0; i < scan.ranges.size(); ++i)
    {
      const double range = scan.ranges[i];
      if (!std::isfinite(range) || range <= g.range_min || range >= g.range_max) continue;
      const double a = g.angle_min + static_cast<double>(i) * g.angle_increment;
      local.emplace_back(range * std::cos(a), range * std::sin(a));
    }
    appendWorldPoints(kf.pose * recording.base_to_laser, local, out);
  }
  return out;
}

}  // namespace line_map_eval
