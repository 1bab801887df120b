#include "line_map_merging/slam/likelihood_grid.hpp"

#include <algorithm>
#include <limits>

namespace line_map_merging
{
/// The field's cells, by tiles of kTile x kTile, as squared distances [m^2] to the nearest point or join
/// while they are written: a tile starts at the reach (nothing near) when something first writes into it,
/// and the rest stay 0. The field of a building is mostly empty space, which then costs nothing more.
class LikelihoodGrid::NearestDistances
{
 public:
  NearestDistances(std::vector<double>& cells, std::vector<unsigned char>& started, int width, int height,
                   double start)
      : cells_(cells),
        width_(width),
        height_(height),
        tiles_x_((width + kTile - 1) / kTile),
        start_(start),
        started_(started)
  {
    started_.assign(static_cast<std::size_t>(tiles_x_) * ((height + kTile - 1) / kTile), 0);
  }

  /// Row iy of the cells, its cells x0..x1 started.
  double* row(int iy, int x0, int x1)
  {
    const int ty = iy / kTile;
    for (int tx = x0 / kTile; tx <= x1 / kTile; ++tx)
    {
      auto& started = started_[static_cast<std::size_t>(ty) * tiles_x_ + tx];
      if (started) continue;
      started = 1;
      const int cx0 = tx * kTile, cx1 = std::min(width_, cx0 + kTile);
      for (int y = ty * kTile; y < std::min(height_, (ty + 1) * kTile); ++y)
        std::fill(&cells_[static_cast<std::size_t>(y) * width_ + cx0],
                  &cells_[static_cast<std::size_t>(y) * width_] + cx1, start_);
    }
    return &cells_[static_cast<std::size_t>(iy) * width_];
  }

  /// Every cell of every started tile replaced by f(its squared distance).
  template <typename F>
  void convert(F&& f)
  {
    for (std::size_t t = 0; t < started_.size(); ++t)
    {
      if (!started_[t]) continue;
      const int tx = static_cast<int>(t % tiles_x_), ty = static_cast<int>(t / tiles_x_);
      const int cx0 = tx * kTile, cx1 = std::min(width_, cx0 + kTile);
      for (int y = ty * kTile; y < std::min(height_, (ty + 1) * kTile); ++y)
      {
        double* line = &cells_[static_cast<std::size_t>(y) * width_];
        for (int x = cx0; x < cx1; ++x) line[x] = f(line[x]);
      }
    }
  }

 private:
  std::vector<double>& cells_;
  int width_, height_, tiles_x_;
  double start_;
  std::vector<unsigned char>& started_;
};

namespace
{
/// Buffers of zeros the fields of this thread gave back (their written tiles zeroed again): a new field
/// takes one instead of allocating and zeroing its whole area, which would cost more than writing it.
struct ZeroBuffers
{
  static constexpr std::size_t kMaxBuffers = 4;
  std::vector<std::vector<double>> free;
  ~ZeroBuffers();
};
thread_local bool zero_buffers_alive = false;
thread_local ZeroBuffers zero_buffers;
ZeroBuffers::~ZeroBuffers()
{
  zero_buffers_alive = false;
}

std::vector<double> takeZeros(std::size_t n)
{
  auto& free = zero_buffers.free;
  zero_buffers_alive = true;
  if (free.empty()) return std::vector<double>(n, 0.0);
  // The smallest that holds n, else the largest (grown: the new part is zeroed as it comes).
  std::size_t pick = 0;
  for (std::size_t i = 1; i < free.size(); ++i)
  {
    const bool holds = free[i].capacity() >= n, picked_holds = free[pick].capacity() >= n;
    if (holds ? (!picked_holds || free[i].capacity() < free[pick].capacity())
              : (!picked_holds && free[i].capacity() > free[pick].capacity()))
      pick = i;
  }
  std::vector<double> zeros = std::move(free[pick]);
  free.erase(free.begin() + static_cast<std::ptrdiff_t>(pick));
  zeros.resize(n, 0.0);  // shrinking leaves zeros beyond the end; growing writes them
  return zeros;
}

void giveBackZeros(std::vector<double>&& zeros)
{
  if (!zero_buffers_alive || zeros.capacity() == 0) return;
  auto& free = zero_buffers.free;
  if (free.size() == ZeroBuffers::kMaxBuffers)
  {
    // Keep the largest: a smaller field fits in them.
    const auto smallest = std::min_element(
        free.begin(), free.end(), [](const auto& a, const auto& b) { return a.capacity() < b.capacity(); });
    if (smallest->capacity() >= zeros.capacity()) return;
    free.erase(smallest);
  }
  free.push_back(std::move(zeros));
}
}  // namespace

LikelihoodGrid::~LikelihoodGrid()
{
  release();
}

LikelihoodGrid& LikelihoodGrid::operator=(LikelihoodGrid&& other) noexcept
{
  if (this != &other)
  {
    release();
    resolution_ = other.resolution_;
    inv_resolution_ = other.inv_resolution_;
    origin_ = other.origin_;
    width_ = other.width_;
    height_ = other.height_;
    cells_ = std::move(other.cells_);
    written_tiles_ = std::move(other.written_tiles_);
    other.cells_.clear();
    other.written_tiles_.clear();
  }
  return *this;
}

void LikelihoodGrid::release() noexcept
{
  if (cells_.empty() || written_tiles_.empty()) return;
  try
  {
    const int tiles_x = (width_ + kTile - 1) / kTile;
    for (std::size_t t = 0; t < written_tiles_.size(); ++t)
    {
      if (!written_tiles_[t]) continue;
      const int x0 = static_cast<int>(t % tiles_x) * kTile, y0 = static_cast<int>(t / tiles_x) * kTile;
      for (int y = y0; y < std::min(height_, y0 + kTile); ++y)
        std::fill_n(cells_.begin() + static_cast<std::ptrdiff_t>(y) * width_ + x0,
                    std::min(kTile, width_ - x0), 0.0);
    }
    written_tiles_.clear();
    giveBackZeros(std::move(cells_));
  }
  catch (...)  // a pool that cannot grow: the buffer is freed as it would have been
  {
  }
  cells_.clear();
}

LikelihoodGrid::LikelihoodGrid(const std::vector<linemap::Vec2>& points, double resolution, double sigma,
                               double margin)
    : LikelihoodGrid(points, {}, resolution, sigma, margin)
{
}

LikelihoodGrid::LikelihoodGrid(const std::vector<linemap::Vec2>& points,
                               const std::vector<linemap::Segment2>& joins, double resolution, double sigma,
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
  const double k = -0.5 / (sigma * sigma);
  margin = std::max(margin, reach + 2.0 * resolution);
  origin_ = {min_x - margin, min_y - margin};
  width_ = static_cast<int>(std::ceil((max_x - min_x + 2.0 * margin) * inv_resolution_)) + 1;
  height_ = static_cast<int>(std::ceil((max_y - min_y + 2.0 * margin) * inv_resolution_)) + 1;
  // Nearest squared distance per cell first, one exp per cell after (far fewer than per point), in the
  // tiles some point or join reaches: the rest of the field is 0.
  const double reach2 = reach * reach;
  cells_ = takeZeros(static_cast<std::size_t>(width_) * height_);
  NearestDistances nearest(cells_, written_tiles_, width_, height_, reach2);
  const int r = static_cast<int>(std::ceil(reach * inv_resolution_));
  std::vector<double> dx2;
  for (const auto& p : points) writeDisc(p, r, dx2, nearest);
  // A join shorter than sigma adds little to its end points' discs (the field sags by under an eighth
  // between them) and most joins are that short: only the longer ones are written.
  for (const auto& s : joins)
    if ((s.end - s.start).squaredNorm() >= sigma * sigma) writeJoin(s, r, reach, nearest);
  nearest.convert([&](double d2) { return d2 >= reach2 ? 0.0 : std::exp(k * d2); });
}

// A point's squared distances along x are the same in every row of its disc: computed once, each row adds
// its own dy^2 (the same sums as per cell). Built for AVX2 too where the processor has it (no FMA: the same
// operations, four at a time).
__attribute__((target_clones("avx2", "default"))) void LikelihoodGrid::writeDisc(
    const linemap::Vec2& p, int r, std::vector<double>& dx2, NearestDistances& nearest) const
{
  const double fx = (p.x() - origin_.x()) * inv_resolution_, fy = (p.y() - origin_.y()) * inv_resolution_;
  const int cx = static_cast<int>(roundHalfAway(fx)), cy = static_cast<int>(roundHalfAway(fy));
  const int x0 = std::max(0, cx - r), x1 = std::min(width_ - 1, cx + r);
  if (x0 > x1) return;
  const int n = x1 - x0 + 1;
  dx2.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    const double dx = (x0 + i - fx) * resolution_;
    dx2[static_cast<std::size_t>(i)] = dx * dx;
  }
  const double* along = dx2.data();
  for (int iy = std::max(0, cy - r); iy <= std::min(height_ - 1, cy + r); ++iy)
  {
    const double dy = (iy - fy) * resolution_, dy2 = dy * dy;
    double* row = nearest.row(iy, x0, x1) + x0;
    for (int i = 0; i < n; ++i) row[i] = std::min(row[i], along[i] + dy2);
  }
}

__attribute__((target_clones("avx2", "default"))) void LikelihoodGrid::writeJoin(
    const linemap::Segment2& s, int r, double reach, NearestDistances& nearest) const
{
  // In cell units from the join's start a: a cell's offset p projects to t = p.u / |u|^2 along it.
  const double ax = (s.start.x() - origin_.x()) * inv_resolution_,
               ay = (s.start.y() - origin_.y()) * inv_resolution_;
  const double ux = (s.end.x() - s.start.x()) * inv_resolution_,
               uy = (s.end.y() - s.start.y()) * inv_resolution_;
  const double len2 = ux * ux + uy * uy;
  if (!(len2 > 0.0) || !std::isfinite(len2)) return;
  // Cells farther from the line than the reach cannot change (a cell of margin keeps rounding safe).
  const double inv_len2 = 1.0 / len2, band = (reach * inv_resolution_ + 1.0) * std::sqrt(len2);
  const int y0 = std::max(0, static_cast<int>(std::floor(ay + std::min(0.0, uy))) - r);
  const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(ay + std::max(0.0, uy))) + r);
  for (int iy = y0; iy <= y1; ++iy)
  {
    const double py = iy - ay;
    // The row's cells with 0 <= t <= 1 and within reach of the line; the rest are nearer an
    // endpoint, whose disc the points wrote.
    double lo = std::floor(ax + std::min(0.0, ux)) - r, hi = std::ceil(ax + std::max(0.0, ux)) + r;
    if (std::fabs(ux) > 1e-9)
    {
      const double t0 = -py * uy / ux, t1 = (len2 - py * uy) / ux;  // px at t = 0 and t = 1
      lo = std::max(lo, ax + std::min(t0, t1) - 1.0);
      hi = std::min(hi, ax + std::max(t0, t1) + 1.0);
    }
    if (std::fabs(uy) > 1e-9)
    {
      const double c = ax + ux * py / uy, half = std::fabs(band / uy);
      lo = std::max(lo, c - half);
      hi = std::min(hi, c + half);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(lo))),
              x1 = std::min(width_ - 1, static_cast<int>(hi));
    if (x0 > x1) continue;
    double* row = nearest.row(iy, x0, x1);
    for (int ix = x0; ix <= x1; ++ix)
    {
      const double px = ix - ax;
      const double t = (px * ux + py * uy) * inv_len2;
      if (t < 0.0 || t > 1.0) continue;
      const double dx = (px - t * ux) * resolution_, dy = (py - t * uy) * resolution_;
      row[ix] = std::min(row[ix], dx * dx + dy * dy);
    }
  }
}

}  // namespace line_map_merging
