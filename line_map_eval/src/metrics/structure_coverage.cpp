#include "line_map_eval/metrics/structure_coverage.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace line_map_eval
{
using linemap::kPi;
using linemap::Vec2;

namespace
{
constexpr int kMaxIterations = 8;  // the band settles in two to four refits; a cap against cycling
constexpr double kMaxGridCells = 1e8;
constexpr int kHeadingClasses = 8;     // length cells aligned to the nearest of 8 headings (22.5 deg apart)
constexpr double kAcrossShare = 0.25;  // across a line, cells of a quarter of the length cell

void require(bool ok, const char* key, const std::string& what, double value)
{
  if (!ok)
    throw linemap::ParameterError(std::string("parameter '") + key + "' must be " + what + ", got " +
                                  std::to_string(value));
}

/// Key of an integer cell (x, y), ordered by x then y.
std::int64_t cellKey(std::int64_t x, std::int64_t y)
{
  return (x << 32) + (y + (std::int64_t(1) << 31));
}

std::int64_t floorIndex(double v, double size)
{
  const double f = std::floor(v / size);
  if (!(std::abs(f) < 2e9)) throw std::invalid_argument("structure coverage: coordinate out of range");
  return static_cast<std::int64_t>(f);
}

struct Voxel
{
  std::size_t begin = 0, end = 0;  ///< range in the sorted point order
  double n = 0.0;
  Vec2 mean = Vec2::Zero();
  double sxx = 0.0, sxy = 0.0, syy = 0.0;  ///< scatter about the mean
};

/// Count, mean and covariance of the points of several voxels, accumulated about a local origin.
struct Fit
{
  double n = 0.0;
  Vec2 mean = Vec2::Zero();
  Vec2 axis = Vec2::UnitX();  ///< principal direction
  double minor = 0.0;         ///< variance across it (smaller eigenvalue)
};

template <typename Indices>
Fit fitVoxels(const std::vector<Voxel>& voxels, const Indices& indices, const Vec2& origin)
{
  double n = 0.0, s1x = 0.0, s1y = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (const auto i : indices)
  {
    const Voxel& v = voxels[i];
    const Vec2 d = v.mean - origin;
    n += v.n;
    s1x += v.n * d.x();
    s1y += v.n * d.y();
    sxx += v.sxx + v.n * d.x() * d.x();
    sxy += v.sxy + v.n * d.x() * d.y();
    syy += v.syy + v.n * d.y() * d.y();
  }
  Fit f;
  if (n <= 0.0) return f;
  f.n = n;
  const double mx = s1x / n, my = s1y / n;
  const double a = sxx / n - mx * mx, b = sxy / n - mx * my, c = syy / n - my * my;
  f.mean = origin + Vec2(mx, my);
  const double theta = 0.5 * std::atan2(2.0 * b, a - c);
  f.axis = Vec2(std::cos(theta), std::sin(theta));
  f.minor = std::max(0.0, 0.5 * (a + c) - std::hypot(0.5 * (a - c), b));
  return f;
}

/// The line of a structure voxel.
struct VoxelLine
{
  bool structure = false;
  Vec2 point = Vec2::Zero();
  Vec2 axis = Vec2::UnitX();
  double heading = 0.0;  ///< of the axis, in [0, pi)
};

}  // namespace

StructureParams StructureParams::fromParams(const linemap::ParamSet& params)
{
  StructureParams p;
  p.radius = params.getDouble("eval/structure_radius", p.radius);
  p.min_length = params.getDouble("eval/structure_min_length", p.min_length);
  p.band_sigmas = params.getDouble("eval/structure_band_sigmas", p.band_sigmas);
  p.max_rms_sigmas = params.getDouble("eval/structure_max_rms_sigmas", p.max_rms_sigmas);
  p.min_share = params.getDouble("eval/structure_min_share", p.min_share);
  p.min_fill = params.getDouble("eval/structure_min_fill", p.min_fill);
  p.voxel = params.getDouble("eval/structure_voxel", p.voxel);
  p.length_cell = params.getDouble("eval/structure_length_cell", p.length_cell);
  p.validate();
  return p;
}

void StructureParams::validate() const
{
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  require(positive(radius), "eval/structure_radius", "a positive number of metres", radius);
  require(min_length >= 0.0 && min_length <= 2.0 * radius, "eval/structure_min_length",
          "in [0, 2 * eval/structure_radius] metres", min_length);
  require(positive(band_sigmas), "eval/structure_band_sigmas", "positive", band_sigmas);
  require(positive(max_rms_sigmas), "eval/structure_max_rms_sigmas", "positive", max_rms_sigmas);
  require(min_share >= 0.0 && min_share <= 1.0, "eval/structure_min_share", "in [0, 1]", min_share);
  require(min_fill >= 0.0 && min_fill <= 1.0, "eval/structure_min_fill", "in [0, 1]", min_fill);
  require(positive(voxel) && voxel <= radius, "eval/structure_voxel",
          "a positive number of metres, at most eval/structure_radius", voxel);
  require(positive(length_cell), "eval/structure_length_cell", "a positive number of metres", length_cell);
}

StructurePoints classifyStructure(const std::vector<Vec2>& points, double sigma,
                                  const StructureParams& params)
{
  params.validate();
  require(sigma > 0.0 && std::isfinite(sigma), "eval/sigma", "a positive number of metres", sigma);
  StructurePoints out;
  out.points = points.size();
  if (points.empty()) return out;

  // Voxels: the points sorted by voxel key, one run per voxel.
  const double h = params.voxel;
  std::vector<std::pair<std::int64_t, std::size_t>> order(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const Vec2& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument("structure coverage: scan point " + std::to_string(i) + " is not finite");
    order[i] = {cellKey(floorIndex(p.x(), h), floorIndex(p.y(), h)), i};
  }
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<Voxel> voxels;
  for (std::size_t b = 0; b < order.size();)
  {
    std::size_t e = b;
    Voxel v;
    v.begin = b;
    for (; e < order.size() && order[e].first == order[b].first; ++e) v.mean += points[order[e].second];
    v.end = e;
    v.n = static_cast<double>(e - b);
    v.mean /= v.n;
    for (std::size_t k = b; k < e; ++k)
    {
      const Vec2 d = points[order[k].second] - v.mean;
      v.sxx += d.x() * d.x();
      v.sxy += d.x() * d.y();
      v.syy += d.y() * d.y();
    }
    voxels.push_back(v);
    b = e;
  }

  // Neighbourhood grid of the voxel means, cells of half a radius (compressed rows): the 5 x 5 cells
  // around a voxel's hold its disc in twice its area (3 x 3 cells of one radius: 2.9 times).
  const double r = params.radius, cell = 0.5 * r;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, max_x = -min_x, max_y = -min_x;
  for (const Voxel& v : voxels)
  {
    min_x = std::min(min_x, v.mean.x());
    min_y = std::min(min_y, v.mean.y());
    max_x = std::max(max_x, v.mean.x());
    max_y = std::max(max_y, v.mean.y());
  }
  const double gw = std::floor((max_x - min_x) / cell) + 1.0, gh = std::floor((max_y - min_y) / cell) + 1.0;
  if (gw * gh > kMaxGridCells)
    throw linemap::ParameterError(
        "parameter 'eval/structure_radius': the cloud spans more than 1e8 cells of " + std::to_string(cell) +
        " m");
  const auto width = static_cast<std::size_t>(gw), height = static_cast<std::size_t>(gh);
  const auto cellOf = [&](const Vec2& m)
  {
    return std::make_pair(static_cast<std::size_t>((m.x() - min_x) / cell),
                          static_cast<std::size_t>((m.y() - min_y) / cell));
  };
  std::vector<std::uint32_t> start(width * height + 1, 0), members(voxels.size());
  for (const Voxel& v : voxels)
  {
    const auto [cx, cy] = cellOf(v.mean);
    ++start[std::min(cy, height - 1) * width + std::min(cx, width - 1) + 1];
  }
  for (std::size_t c = 0; c + 1 < start.size(); ++c) start[c + 1] += start[c];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < voxels.size(); ++i)
    {
      const auto [cx, cy] = cellOf(voxels[i].mean);
      members[fill[std::min(cy, height - 1) * width + std::min(cx, width - 1)]++] =
          static_cast<std::uint32_t>(i);
    }
  }

  // Each voxel's band (see the header): independent of the others, so in parallel.
  const double g = params.band_sigmas * sigma;
  const double max_minor = std::pow(params.max_rms_sigmas * sigma, 2);
  std::vector<VoxelLine> lines(voxels.size());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, voxels.size(), 256),
      [&](const tbb::blocked_range<std::size_t>& range)
      {
        std::vector<std::uint32_t> near, band, next;
        std::vector<std::int64_t> bins;
        for (std::size_t i = range.begin(); i != range.end(); ++i)
        {
          const Vec2& o = voxels[i].mean;
          const auto [cx, cy] = cellOf(o);
          near.clear();
          for (std::size_t y = cy > 1 ? cy - 2 : 0; y <= std::min(cy + 2, height - 1); ++y)
            for (std::size_t x = cx > 1 ? cx - 2 : 0; x <= std::min(cx + 2, width - 1); ++x)
              for (std::uint32_t k = start[y * width + x]; k < start[y * width + x + 1]; ++k)
                if ((voxels[members[k]].mean - o).squaredNorm() <= r * r) near.push_back(members[k]);
          Fit fit = fitVoxels(voxels, near, o);
          Vec2 point = o, axis = fit.axis;
          band.clear();
          for (int it = 0; it < kMaxIterations; ++it)
          {
            const Vec2 normal(-axis.y(), axis.x());
            next.clear();
            for (const std::uint32_t k : near)
              if (std::abs(normal.dot(voxels[k].mean - point)) <= g) next.push_back(k);
            if (next.empty())
            {
              band.clear();
              break;
            }
            fit = fitVoxels(voxels, next, o);
            point = fit.mean;
            axis = fit.axis;
            const bool settled = next == band;
            band.swap(next);
            if (settled) break;
          }
          if (band.empty()) continue;
          if (fit.minor > max_minor) continue;
          if (static_cast<double>(band.size()) < params.min_share * static_cast<double>(near.size()))
            continue;
          double lo = std::numeric_limits<double>::infinity(), hi = -lo;
          for (const std::uint32_t k : band)
          {
            const double t = axis.dot(voxels[k].mean - point);
            lo = std::min(lo, t);
            hi = std::max(hi, t);
          }
          if (hi - lo < params.min_length) continue;
          // Continuity: a wall fills its line, a row of chair legs does not.
          bins.clear();
          for (const std::uint32_t k : band)
            bins.push_back(
                static_cast<std::int64_t>(std::floor((axis.dot(voxels[k].mean - point) - lo) / h)));
          std::sort(bins.begin(), bins.end());
          const auto filled = std::unique(bins.begin(), bins.end()) - bins.begin();
          if (static_cast<double>(filled) < params.min_fill * std::floor((hi - lo) / h + 1.0)) continue;
          double heading = std::atan2(axis.y(), axis.x());
          if (heading < 0.0) heading += kPi;
          lines[i] = {true, point, axis, heading < kPi ? heading : 0.0};
        }
      });

  // The points of structure voxels within the band of their voxel's line, in index order.
  std::vector<std::uint32_t> voxel_of(points.size());
  out.indices.reserve(points.size());
  out.feet.reserve(points.size());
  out.headings.reserve(points.size());
  for (std::size_t i = 0; i < voxels.size(); ++i)
    for (std::size_t k = voxels[i].begin; k < voxels[i].end; ++k)
      voxel_of[order[k].second] = static_cast<std::uint32_t>(i);
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const VoxelLine& l = lines[voxel_of[i]];
    if (!l.structure) continue;
    const Vec2 normal(-l.axis.y(), l.axis.x());
    const double d = normal.dot(points[i] - l.point);
    if (std::abs(d) > g) continue;
    out.indices.push_back(i);
    out.feet.push_back(points[i] - d * normal);
    out.headings.push_back(l.heading);
  }
  out.runs = structureRuns(out.feet, out.headings, params.length_cell);
  out.length = out.runs.length();
  return out;
}

namespace
{
/// A structure foot's cell: heading class, column along it and cell across it.
struct Keyed
{
  int heading_class;
  std::int64_t along, across;
  std::uint32_t index;
  bool operator<(const Keyed& o) const
  {
    return std::tie(heading_class, along, across, index) <
           std::tie(o.heading_class, o.along, o.across, o.index);
  }
};

/// A run of adjacent occupied cells across, in one column.
struct Run
{
  int heading_class;
  std::int64_t along, low, high;
};

/// The feet's cells, sorted by heading class, column, then across.
std::vector<Keyed> keyedFeet(const std::vector<Vec2>& feet, const std::vector<double>& headings, double cell,
                             double step)
{
  const double across = kAcrossShare * cell;
  std::vector<Keyed> keyed(feet.size());
  for (std::size_t i = 0; i < feet.size(); ++i)
  {
    if (!feet[i].allFinite() || !std::isfinite(headings[i]))
      throw std::invalid_argument("structure length: point " + std::to_string(i) + " is not finite");
    const int c = static_cast<int>(((std::lround(headings[i] / step) % kHeadingClasses) + kHeadingClasses) %
                                   kHeadingClasses);
    const Vec2 u(std::cos(c * step), std::sin(c * step));
    keyed[i] = {c, floorIndex(u.dot(feet[i]), cell),
                floorIndex(u.x() * feet[i].y() - u.y() * feet[i].x(), across), static_cast<std::uint32_t>(i)};
  }
  tbb::parallel_sort(keyed.begin(), keyed.end());
  return keyed;
}

/// Runs: adjacent occupied cells across, in one column along the heading class; sets out.run_of and
/// out.width.
std::vector<Run> findRuns(const std::vector<Keyed>& keyed, const std::vector<double>& headings, double cell,
                          double step, StructureRuns& out)
{
  out.run_of.resize(keyed.size());
  std::vector<Run> runs;
  for (std::size_t b = 0; b < keyed.size();)
  {
    std::size_t e = b + 1;
    while (e < keyed.size() && keyed[e].heading_class == keyed[b].heading_class &&
           keyed[e].along == keyed[b].along && keyed[e].across - keyed[e - 1].across <= 1)
      ++e;
    double sin_sum = 0.0, cos_sum = 0.0;
    for (std::size_t k = b; k < e; ++k)
    {
      const double offset = headings[keyed[k].index] - keyed[b].heading_class * step;
      sin_sum += std::sin(2.0 * offset);
      cos_sum += std::cos(2.0 * offset);
      out.run_of[keyed[k].index] = static_cast<std::uint32_t>(runs.size());
    }
    runs.push_back({keyed[b].heading_class, keyed[b].along, keyed[b].across, keyed[e - 1].across});
    out.width.push_back(cell / std::cos(0.5 * std::atan2(sin_sum, cos_sum)));
    b = e;
  }
  return runs;
}

/// Each run's runs in the column before (same class) touching it across; runs are sorted by class,
/// column, then across.
void linkColumns(const std::vector<Run>& runs, StructureRuns& out)
{
  out.before_start.push_back(0);
  std::size_t previous_begin = 0, previous_end = 0;
  for (std::size_t r = 0; r < runs.size();)
  {
    std::size_t column_end = r;
    while (column_end < runs.size() && runs[column_end].heading_class == runs[r].heading_class &&
           runs[column_end].along == runs[r].along)
      ++column_end;
    const bool adjacent = previous_end > previous_begin &&
                          runs[previous_begin].heading_class == runs[r].heading_class &&
                          runs[previous_begin].along + 1 == runs[r].along;
    for (std::size_t k = r; k < column_end; ++k)
    {
      for (std::size_t q = previous_begin; adjacent && q < previous_end; ++q)
        if (runs[q].low <= runs[k].high + 1 && runs[k].low <= runs[q].high + 1)
          out.before.push_back(static_cast<std::uint32_t>(q));
      out.before_start.push_back(static_cast<std::uint32_t>(out.before.size()));
    }
    previous_begin = r;
    previous_end = column_end;
    r = column_end;
  }
}
}  // namespace

StructureRuns structureRuns(const std::vector<Vec2>& feet, const std::vector<double>& headings, double cell)
{
  if (feet.size() != headings.size())
    throw std::invalid_argument("structure length: " + std::to_string(feet.size()) + " feet but " +
                                std::to_string(headings.size()) + " headings");
  if (!(cell > 0.0) || !std::isfinite(cell))
    throw std::invalid_argument("structure length: cell size " + std::to_string(cell) + " must be positive");
  const double step = kPi / kHeadingClasses;
  const std::vector<Keyed> keyed = keyedFeet(feet, headings, cell, step);
  StructureRuns out;
  const std::vector<Run> runs = findRuns(keyed, headings, cell, step, out);
  linkColumns(runs, out);
  return out;
}

double StructureRuns::length(const std::vector<std::uint8_t>& uncovered) const
{
  if (!uncovered.empty() && uncovered.size() != run_of.size())
    throw std::invalid_argument("structure length: " + std::to_string(uncovered.size()) + " flags for " +
                                std::to_string(run_of.size()) + " feet");
  std::vector<std::uint32_t> open(width.size(), 0), total(width.size(), 0);
  for (std::size_t i = 0; i < run_of.size(); ++i)
  {
    ++total[run_of[i]];
    if (uncovered.empty() || uncovered[i]) ++open[run_of[i]];
  }
  const auto counted = [&](std::size_t r) { return 2 * open[r] > total[r]; };
  double length = 0.0;
  for (std::size_t r = 0; r < width.size(); ++r)
  {
    if (!counted(r)) continue;
    // The first run of a chain adds nothing: a piece touches one column more than its length spans.
    bool continues = false;
    for (std::uint32_t k = before_start[r]; k < before_start[r + 1] && !continues; ++k)
      continues = counted(before[k]);
    if (continues) length += width[r];
  }
  return length;
}

double structureLength(const std::vector<Vec2>& feet, const std::vector<double>& headings, double cell,
                       const std::vector<std::uint8_t>& uncovered)
{
  return structureRuns(feet, headings, cell).length(uncovered);
}

StructureCoverage computeStructureCoverage(const StructurePoints& structure, const PointCoverage& coverage)
{
  if (structure.points != coverage.points)
    throw std::invalid_argument("structure coverage: structure of " + std::to_string(structure.points) +
                                " points, point coverage of " + std::to_string(coverage.points));
  StructureCoverage c;
  c.points = structure.indices.size();
  c.length = structure.length;
  std::vector<std::uint8_t> uncovered(structure.indices.size(), 0);
  // Both index lists ascend: one merge pass.
  auto u = coverage.uncovered.begin();
  for (std::size_t k = 0; k < structure.indices.size(); ++k)
  {
    const std::size_t i = structure.indices[k];
    while (u != coverage.uncovered.end() && *u < i) ++u;
    if (u != coverage.uncovered.end() && *u == i)
    {
      c.uncovered.push_back(i);
      uncovered[k] = 1;
    }
  }
  c.covered = c.points - c.uncovered.size();
  c.unmapped_length = c.uncovered.empty() ? 0.0 : structure.runs.length(uncovered);
  return c;
}

}  // namespace line_map_eval
