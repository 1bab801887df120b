#include "line_map_eval/metrics/structure_coverage.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "line_map_eval/metrics/segment_tree.hpp"

namespace line_map_eval
{
using linemap::kPi;
using linemap::Vec2;

namespace
{
constexpr int kMaxIterations = 8;  // the band settles in two to four refits; a cap against cycling
constexpr double kMaxGridCells = 1e8;
constexpr int kHeadingClasses = 8;  // length cells aligned to the nearest of 8 headings (22.5 deg apart)
constexpr double kAcrossShare = 0.25;
// At the smeared scale the RMS is taken over this share of the band's points nearest its line: a wall
// with a row of objects beside it within the band is still thin at its core; clutter filling the band
// is not (a uniform band's core is 0.8 of its width).
constexpr double kSmearCore = 0.8;
// The smeared band is sought once per cell of this share of its half-width (the heaviest voxel's band
// serves the cell): a 2 m band barely moves over a few centimetres.
constexpr double kSmearSeedShare = 1.0;  // across a line, cells of a quarter of the length cell

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
  double heading = 0.0;     ///< of the axis, in [0, pi)
  double half_width = 0.0;  ///< [m] the band's: its points within this of the line are structure
  double reach = 0.0;       ///< [m] 0: fine; else a map segment this close to a foot covers it

  /// Signed distance of `p` from the line, and its foot on it.
  double offset(const Vec2& p) const { return Vec2(-axis.y(), axis.x()).dot(p - point); }
  Vec2 foot(const Vec2& p) const { return p - offset(p) * Vec2(-axis.y(), axis.x()); }
};

/// One scale of the band test (see the header).
struct BandTest
{
  double radius;      ///< [m] neighbourhood
  double half_width;  ///< [m] g
  double max_minor;   ///< [m^2] largest variance across the line
  double min_share;
  double min_length;  ///< [m]
  double min_fill;
  double fill_bin;    ///< [m]
  double min_points;  ///< in the band (the smeared scale)
  bool smeared;       ///< the smeared scale (feet covered within the band's own width)
};

/// The voxel means in a grid of cells of half a radius (compressed rows): the 5 x 5 cells around a
/// voxel's hold its disc in twice its area.
class VoxelGrid
{
 public:
  VoxelGrid(const std::vector<Voxel>& voxels, double radius)
      : voxels_(voxels), radius_(radius), cell_(0.5 * radius)
  {
    double max_x = -std::numeric_limits<double>::infinity(), max_y = max_x;
    for (const Voxel& v : voxels)
    {
      min_x_ = std::min(min_x_, v.mean.x());
      min_y_ = std::min(min_y_, v.mean.y());
      max_x = std::max(max_x, v.mean.x());
      max_y = std::max(max_y, v.mean.y());
    }
    const double gw = std::floor((max_x - min_x_) / cell_) + 1.0,
                 gh = std::floor((max_y - min_y_) / cell_) + 1.0;
    if (gw * gh > kMaxGridCells)
      throw linemap::ParameterError("structure coverage: the cloud spans more than 1e8 cells of " +
                                    std::to_string(cell_) +
                                    " m (parameters eval/structure_radius, "
                                    "eval/structure_smear_radius)");
    width_ = static_cast<std::size_t>(gw);
    height_ = static_cast<std::size_t>(gh);
    start_.assign(width_ * height_ + 1, 0);
    members_.resize(voxels.size());
    for (const Voxel& v : voxels) ++start_[cellOf(v.mean) + 1];
    for (std::size_t c = 0; c + 1 < start_.size(); ++c) start_[c + 1] += start_[c];
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < voxels.size(); ++i)
      members_[fill[cellOf(voxels[i].mean)]++] = static_cast<std::uint32_t>(i);
  }

  /// The voxels whose means lie within the radius of `o`.
  void near(const Vec2& o, std::vector<std::uint32_t>& out) const
  {
    out.clear();
    const auto cx = static_cast<std::size_t>((o.x() - min_x_) / cell_),
               cy = static_cast<std::size_t>((o.y() - min_y_) / cell_);
    for (std::size_t y = cy > 1 ? cy - 2 : 0; y <= std::min(cy + 2, height_ - 1); ++y)
      for (std::size_t x = cx > 1 ? cx - 2 : 0; x <= std::min(cx + 2, width_ - 1); ++x)
        for (std::uint32_t k = start_[y * width_ + x]; k < start_[y * width_ + x + 1]; ++k)
          if ((voxels_[members_[k]].mean - o).squaredNorm() <= radius_ * radius_) out.push_back(members_[k]);
  }

 private:
  std::size_t cellOf(const Vec2& m) const
  {
    const auto cx = static_cast<std::size_t>((m.x() - min_x_) / cell_),
               cy = static_cast<std::size_t>((m.y() - min_y_) / cell_);
    return std::min(cy, height_ - 1) * width_ + std::min(cx, width_ - 1);
  }

  const std::vector<Voxel>& voxels_;
  double radius_, cell_;
  double min_x_ = std::numeric_limits<double>::infinity(), min_y_ = min_x_;
  std::size_t width_ = 0, height_ = 0;
  std::vector<std::uint32_t> start_, members_;
};

/// Variance across the line through `point` along `axis` of the share `core` of the band's points
/// nearest it (by voxel means; each voxel's own scatter included): 1 gives the band's whole variance.
double coreVariance(const std::vector<Voxel>& voxels, const std::vector<std::uint32_t>& band,
                    const Vec2& point, const Vec2& axis, double core)
{
  const Vec2 normal(-axis.y(), axis.x());
  std::vector<std::pair<double, std::uint32_t>> by_offset;
  double total = 0.0;
  for (const std::uint32_t k : band)
  {
    by_offset.emplace_back(std::abs(normal.dot(voxels[k].mean - point)), k);
    total += voxels[k].n;
  }
  // The nearest `core` of the points: the voxels below the offset where their count reaches it.
  std::sort(by_offset.begin(), by_offset.end());
  double n = 0.0, sum = 0.0;
  for (const auto& [offset, k] : by_offset)
  {
    if (n >= core * total) break;
    const Voxel& v = voxels[k];
    // The voxel's scatter across the line: its covariance projected on the normal.
    const double inner = normal.x() * normal.x() * v.sxx + 2.0 * normal.x() * normal.y() * v.sxy +
                         normal.y() * normal.y() * v.syy;
    n += v.n;
    sum += v.n * offset * offset + inner;
  }
  return n > 0.0 ? sum / n : 0.0;
}

/// Whether the band's points fall into two lines side by side with a gap between them (the two faces
/// of a partition, two walls close together) rather than one smear: across the line, in bins of a
/// twenty-fifth of the half-width g (1 cm), each voxel's points spread evenly about its mean with its
/// variance (5 cm voxels would otherwise gather a smear into clusters a voxel apart), a run of at least two
/// bins holding under 1 % of the points where an even spread over the occupied span would put five or more,
/// between two sides holding a tenth of them or more each (a partition's face seen from a room holds far
/// fewer points than its corridor side). A smeared wall spreads continuously across (a sparse one leaves gaps
/// no larger than chance); one segment between two faces would cover both through their feet.
bool twoLines(const std::vector<Voxel>& voxels, const std::vector<std::uint32_t>& band, const Vec2& point,
              const Vec2& axis, double g)
{
  constexpr int kBins = 50, kValley = 2;
  const Vec2 normal(-axis.y(), axis.x());
  std::array<double, kBins> histogram{};
  double total = 0.0;
  const double bin = 2.0 * g / kBins;
  for (const std::uint32_t k : band)
  {
    // A voxel's points, not its mean: 5 cm voxels would otherwise gather a smear into clusters a voxel
    // apart. Each spreads as a normal law with its own mean and variance across the line.
    const Voxel& v = voxels[k];
    const double mean = normal.dot(v.mean - point) + g;
    const double across = (normal.x() * normal.x() * v.sxx + 2.0 * normal.x() * normal.y() * v.sxy +
                           normal.y() * normal.y() * v.syy) /
                          v.n;
    // Spread evenly over +-sqrt(3) of its std (the uniform law of the same variance): cheaper than the
    // normal law's error functions, and as good at filling the gaps between voxel means.
    const double half = std::max(std::sqrt(3.0 * std::max(across, 0.0)), 1e-4);
    const int lo = std::max(0, static_cast<int>(std::floor((mean - half) / bin)));
    const int hi = std::min(kBins - 1, static_cast<int>(std::floor((mean + half) / bin)));
    for (int b = lo; b <= hi; ++b)
    {
      const double overlap = std::min((b + 1) * bin, mean + half) - std::max(b * bin, mean - half);
      if (overlap > 0.0) histogram[static_cast<std::size_t>(b)] += v.n * overlap / (2.0 * half);
    }
    total += v.n;
  }
  int first = 0, last = kBins - 1;
  while (first < last && histogram[first] < 1e-3 * total) ++first;
  while (last > first && histogram[last] < 1e-3 * total) --last;
  const double span = last - first + 1, side = 0.1 * total;
  double below = 0.0;
  for (int b = first; b <= last;)
  {
    int e = b;
    double in_run = 0.0;
    while (e <= last && in_run + histogram[e] < 0.01 * total) in_run += histogram[e++];
    if (e - b >= kValley && total * (e - b) / span >= 5.0 && below >= side && total - below - in_run >= side)
      return true;
    for (const int stop = std::max(e, b + 1); b < stop; ++b) below += histogram[b];
  }
  return false;
}

/// The mean direction of the fine lines among the band's voxels (doubled angles, weighted by points),
/// turned like `axis`; `axis` itself without any. Two parallel faces tilt the band's own principal axis
/// when they end at different places; their fine lines keep the walls' true direction.
Vec2 fineDirection(const std::vector<VoxelLine>& fine_lines, const std::vector<Voxel>& voxels,
                   const std::vector<std::uint32_t>& band, const Vec2& axis)
{
  double c = 0.0, s = 0.0;
  for (const std::uint32_t k : band)
  {
    if (!fine_lines[k].structure) continue;
    const double a = 2.0 * std::atan2(fine_lines[k].axis.y(), fine_lines[k].axis.x());
    c += voxels[k].n * std::cos(a);
    s += voxels[k].n * std::sin(a);
  }
  if (c == 0.0 && s == 0.0) return axis;
  const double half = 0.5 * std::atan2(s, c);
  const Vec2 d(std::cos(half), std::sin(half));
  return d.dot(axis) < 0.0 ? Vec2(-d) : d;
}

/// The band of the voxel at `o` among the voxels `near` it: the voxels within g of a line, refitted to
/// them and taken again until it settles (a mean shift onto the densest line nearby). Empty when the
/// line loses every voxel.
Fit settleBand(const std::vector<Voxel>& voxels, const std::vector<std::uint32_t>& near, const Vec2& o,
               double g, std::vector<std::uint32_t>& band, std::vector<std::uint32_t>& next)
{
  Fit fit = fitVoxels(voxels, near, o);
  fit.mean = o;
  band.clear();
  for (int it = 0; it < kMaxIterations; ++it)
  {
    const Vec2 normal(-fit.axis.y(), fit.axis.x());
    next.clear();
    for (const std::uint32_t k : near)
      if (std::abs(normal.dot(voxels[k].mean - fit.mean)) <= g) next.push_back(k);
    if (next.empty())
    {
      band.clear();
      break;
    }
    fit = fitVoxels(voxels, next, o);
    const bool settled = next == band;
    band.swap(next);
    if (settled) break;
  }
  return fit;
}

/// Whether a settled band (line through fit.mean along fit.axis) passes `test` (see the header): the
/// cheap tests first.
bool bandPasses(const std::vector<Voxel>& voxels, const std::vector<std::uint32_t>& band, std::size_t near,
                const Fit& fit, const BandTest& test, const std::vector<VoxelLine>* fine_lines,
                std::vector<std::int64_t>& bins)
{
  if (band.empty()) return false;
  if (static_cast<double>(band.size()) < test.min_share * static_cast<double>(near)) return false;
  const Vec2 &point = fit.mean, &axis = fit.axis;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const std::uint32_t k : band)
  {
    const double t = axis.dot(voxels[k].mean - point);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  if (hi - lo < test.min_length) return false;
  // Continuity: a wall fills its line, a row of chair legs does not.
  bins.clear();
  for (const std::uint32_t k : band)
    bins.push_back(
        static_cast<std::int64_t>(std::floor((axis.dot(voxels[k].mean - point) - lo) / test.fill_bin)));
  std::sort(bins.begin(), bins.end());
  const auto filled = std::unique(bins.begin(), bins.end()) - bins.begin();
  const double bin_count = std::floor((hi - lo) / test.fill_bin + 1.0);
  double expected = bin_count;
  if (test.smeared)
  {
    // The bins n points spread evenly at random along the line would fill: a wall seen sparsely from
    // afar fills about that many; posts seen by many scans pile their points into few.
    double n = 0.0;
    for (const std::uint32_t k : band) n += voxels[k].n;
    if (n < test.min_points) return false;
    expected = bin_count * (1.0 - std::exp(-n / bin_count));
  }
  if (static_cast<double>(filled) < test.min_fill * expected) return false;
  if (test.smeared ? coreVariance(voxels, band, point, axis, kSmearCore) > test.max_minor
                   : fit.minor > test.max_minor)
    return false;
  return !(fine_lines &&
           twoLines(voxels, band, point, fineDirection(*fine_lines, voxels, band, axis), test.half_width));
}

/// The band test of `test` for every voxel, or for the voxels `only` (in parallel: each voxel's band
/// is independent of the others'); `fine_lines` at the smeared scale.
void classifyVoxels(const std::vector<Voxel>& voxels, const BandTest& test, std::vector<VoxelLine>& lines,
                    const std::vector<VoxelLine>* fine_lines = nullptr,
                    const std::vector<std::uint32_t>* only = nullptr)
{
  const VoxelGrid grid(voxels, test.radius);
  const double g = test.half_width;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, only ? only->size() : voxels.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<std::uint32_t> near, band, next;
                      std::vector<std::int64_t> bins;
                      for (std::size_t r = range.begin(); r != range.end(); ++r)
                      {
                        const std::size_t i = only ? (*only)[r] : r;
                        grid.near(voxels[i].mean, near);
                        const Fit fit = settleBand(voxels, near, voxels[i].mean, g, band, next);
                        if (!bandPasses(voxels, band, near.size(), fit, test, fine_lines, bins)) continue;
                        double heading = std::atan2(fit.axis.y(), fit.axis.x());
                        if (heading < 0.0) heading += kPi;
                        // A smeared band's points lie about its line like a uniform band sqrt(3) RMS
                        // wide each way.
                        const double reach = test.smeared ? std::min(g, std::sqrt(3.0 * fit.minor)) : 0.0;
                        lines[i] = {true, fit.mean, fit.axis, heading < kPi ? heading : 0.0, g, reach};
                      }
                    });
}

/// The points' voxels (cells of `size`): `order` gets the points' (voxel key, index) sorted, each
/// voxel a run [begin, end) of it. Throws std::invalid_argument naming a non-finite point.
std::vector<Voxel> buildVoxels(const std::vector<Vec2>& points, double size,
                               std::vector<std::pair<std::int64_t, std::size_t>>& order)
{
  order.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const Vec2& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument("structure coverage: scan point " + std::to_string(i) + " is not finite");
    order[i] = {cellKey(floorIndex(p.x(), size), floorIndex(p.y(), size)), i};
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
  return voxels;
}

/// Every voxel's line at the smeared scale (`fine_lines`: the fine scale's). The band is sought for the
/// heaviest voxel of each seed cell and serves every voxel of that cell.
std::vector<VoxelLine> smearedLines(const std::vector<Voxel>& voxels, const StructureParams& params,
                                    const std::vector<VoxelLine>& fine_lines)
{
  const BandTest smeared{params.smear_radius,
                         params.smear_band,
                         params.smear_max_rms * params.smear_max_rms,
                         params.smear_min_share,
                         params.smear_min_length,
                         params.smear_min_fill,
                         params.smear_fill_bin,
                         static_cast<double>(params.smear_min_points),
                         true};
  const double seed_cell = kSmearSeedShare * params.smear_band;
  std::vector<std::pair<std::int64_t, std::uint32_t>> cell_of(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i)
    cell_of[i] = {
        cellKey(floorIndex(voxels[i].mean.x(), seed_cell), floorIndex(voxels[i].mean.y(), seed_cell)),
        static_cast<std::uint32_t>(i)};
  tbb::parallel_sort(cell_of.begin(), cell_of.end());
  std::vector<std::uint32_t> seeds, seed_of(voxels.size());
  for (std::size_t b = 0; b < cell_of.size();)
  {
    std::size_t e = b, heaviest = b;
    for (; e < cell_of.size() && cell_of[e].first == cell_of[b].first; ++e)
      if (voxels[cell_of[e].second].n > voxels[cell_of[heaviest].second].n) heaviest = e;
    for (std::size_t k = b; k < e; ++k) seed_of[cell_of[k].second] = cell_of[heaviest].second;
    seeds.push_back(cell_of[heaviest].second);
    b = e;
  }
  std::vector<VoxelLine> lines(voxels.size());
  classifyVoxels(voxels, smeared, lines, &fine_lines, &seeds);
  for (std::size_t i = 0; i < voxels.size(); ++i) lines[i] = lines[seed_of[i]];
  return lines;
}

}  // namespace

StructureParams StructureParams::fromParams(const linemap::ParamSet& params)
{
  return linemap::readValidated<StructureParams>(
      params, {{"eval/structure_radius", &StructureParams::radius},
               {"eval/structure_min_length", &StructureParams::min_length},
               {"eval/structure_band_sigmas", &StructureParams::band_sigmas},
               {"eval/structure_max_rms_sigmas", &StructureParams::max_rms_sigmas},
               {"eval/structure_min_share", &StructureParams::min_share},
               {"eval/structure_min_fill", &StructureParams::min_fill},
               {"eval/structure_voxel", &StructureParams::voxel},
               {"eval/structure_length_cell", &StructureParams::length_cell},
               {"eval/structure_smear_band", &StructureParams::smear_band},
               {"eval/structure_smear_radius", &StructureParams::smear_radius},
               {"eval/structure_smear_max_rms", &StructureParams::smear_max_rms},
               {"eval/structure_smear_min_share", &StructureParams::smear_min_share},
               {"eval/structure_smear_min_length", &StructureParams::smear_min_length},
               {"eval/structure_smear_min_fill", &StructureParams::smear_min_fill},
               {"eval/structure_smear_fill_bin", &StructureParams::smear_fill_bin},
               {"eval/structure_smear_min_points", &StructureParams::smear_min_points}});
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
  require(smear_band >= 0.0 && std::isfinite(smear_band), "eval/structure_smear_band",
          "a number of metres >= 0 (0: no smeared scale)", smear_band);
  if (smear_band == 0.0) return;
  require(positive(smear_radius) && smear_radius >= voxel, "eval/structure_smear_radius",
          "a positive number of metres, at least eval/structure_voxel", smear_radius);
  require(positive(smear_max_rms), "eval/structure_smear_max_rms", "a positive number of metres",
          smear_max_rms);
  require(smear_min_share >= 0.0 && smear_min_share <= 1.0, "eval/structure_smear_min_share", "in [0, 1]",
          smear_min_share);
  require(smear_min_length >= 0.0 && smear_min_length <= 2.0 * smear_radius,
          "eval/structure_smear_min_length", "in [0, 2 * eval/structure_smear_radius] metres",
          smear_min_length);
  require(smear_min_fill >= 0.0 && smear_min_fill <= 1.0, "eval/structure_smear_min_fill", "in [0, 1]",
          smear_min_fill);
  require(positive(smear_fill_bin), "eval/structure_smear_fill_bin", "a positive number of metres",
          smear_fill_bin);
  require(smear_min_points >= 2, "eval/structure_smear_min_points", "at least 2", smear_min_points);
}

StructurePoints classifyStructure(const std::vector<Vec2>& points, double sigma,
                                  const StructureParams& params)
{
  params.validate();
  require(sigma > 0.0 && std::isfinite(sigma), "eval/sigma", "a positive number of metres", sigma);
  StructurePoints out;
  out.points = points.size();
  if (points.empty()) return out;

  std::vector<std::pair<std::int64_t, std::size_t>> order;
  const std::vector<Voxel> voxels = buildVoxels(points, params.voxel, order);
  // Each voxel's band (see the header): independent of the others, so in parallel.
  std::vector<VoxelLine> lines(voxels.size());
  const BandTest fine{params.radius,
                      params.band_sigmas * sigma,
                      std::pow(params.max_rms_sigmas * sigma, 2),
                      params.min_share,
                      params.min_length,
                      params.min_fill,
                      params.voxel,
                      0.0,
                      false};
  classifyVoxels(voxels, fine, lines);
  const std::vector<VoxelLine> smeared_lines =
      params.smear_band > 0.0 ? smearedLines(voxels, params, lines) : std::vector<VoxelLine>(voxels.size());

  // The points of structure voxels within the band of their voxel's line, in index order.
  std::vector<std::uint32_t> voxel_of(points.size());
  for (std::size_t i = 0; i < voxels.size(); ++i)
    for (std::size_t k = voxels[i].begin; k < voxels[i].end; ++k)
      voxel_of[order[k].second] = static_cast<std::uint32_t>(i);
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    // On fine structure within its band, else on smeared structure within its band; the smeared
    // line (when there is one) also tells whether a map segment covers the point.
    const VoxelLine& fine_line = lines[voxel_of[i]];
    const VoxelLine& smeared_line = smeared_lines[voxel_of[i]];
    const bool on_fine = fine_line.structure && std::abs(fine_line.offset(points[i])) <= fine_line.half_width;
    const bool on_smeared =
        smeared_line.structure && std::abs(smeared_line.offset(points[i])) <= smeared_line.half_width;
    if (!on_fine && !on_smeared) continue;
    const VoxelLine& l = on_fine ? fine_line : smeared_line;
    out.indices.push_back(i);
    out.feet.push_back(l.foot(points[i]));
    out.headings.push_back(l.heading);
    out.fine.push_back(on_fine ? 1 : 0);
    out.smeared_feet.push_back(on_smeared ? smeared_line.foot(points[i]) : points[i]);
    out.reach.push_back(on_smeared ? static_cast<float>(smeared_line.reach) : 0.0F);
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

StructureCoverage computeStructureCoverage(const StructurePoints& structure, const PointCoverage& coverage,
                                           const std::vector<linemap::Segment2>& map, double radius)
{
  if (structure.points != coverage.points)
    throw std::invalid_argument("structure coverage: structure of " + std::to_string(structure.points) +
                                " points, point coverage of " + std::to_string(coverage.points));
  StructureCoverage c;
  c.points = structure.indices.size();
  c.length = structure.length;
  std::vector<std::uint8_t> uncovered(structure.indices.size(), 0);
  // Covered: a fine point within the point-coverage radius of a segment, or a point of a smeared band
  // whose foot on the band's line lies within the band's reach of one (the map's line of a wall whose
  // registered points smear lies inside their band, not on every one of them).
  float widest = 0.0F;
  for (const float reach : structure.reach) widest = std::max(widest, reach);
  const SegmentTree tree = segmentTree(map, std::max<double>(widest, radius), "structure coverage");
  const auto smearCovered = [&](std::size_t k)
  {
    if (k >= structure.reach.size() || !(structure.reach[k] > 0.0F)) return false;
    const Vec2& p = structure.smeared_feet[k];
    const double reach = std::max<double>(structure.reach[k], radius);
    for (auto it = tree.qbegin(boost::geometry::index::intersects(SegmentPoint(p.x(), p.y())));
         it != tree.qend(); ++it)
      if (linemap::distanceToSegment(p, map[it->second].start, map[it->second].end) <= reach) return true;
    return false;
  };
  // Both index lists ascend: one merge pass.
  auto u = coverage.uncovered.begin();
  for (std::size_t k = 0; k < structure.indices.size(); ++k)
  {
    const std::size_t i = structure.indices[k];
    while (u != coverage.uncovered.end() && *u < i) ++u;
    const bool point_covered = !(u != coverage.uncovered.end() && *u == i);
    const bool fine = k < structure.fine.size() ? structure.fine[k] != 0 : true;
    if ((fine && point_covered) || smearCovered(k)) continue;
    c.uncovered.push_back(i);
    uncovered[k] = 1;
  }
  c.covered = c.points - c.uncovered.size();
  c.unmapped_length = c.uncovered.empty() ? 0.0 : structure.runs.length(uncovered);
  return c;
}

}  // namespace line_map_eval
