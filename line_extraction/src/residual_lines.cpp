// Lines in the unexplained points of several registered scans (see the header).
#include "line_extraction/residual_lines.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>

#include "line_extraction/bucket_sort.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
ResidualLineParams ResidualLineParams::readOver(const linemap::ParamSet& ps, const std::string& prefix,
                                                const std::string& sources_key) const
{
  ResidualLineParams p = *this;
  p.band_sigmas = positiveParam(ps, prefix + "band_sigmas", p.band_sigmas);
  p.seed_radius = positiveParam(ps, prefix + "seed_radius", p.seed_radius);
  p.max_gap = positiveParam(ps, prefix + "max_gap", p.max_gap);
  p.min_points = intParamAtLeast(ps, prefix + "min_points", p.min_points, 3);
  p.min_sources = intParamAtLeast(ps, prefix + sources_key, p.min_sources, 2);
  p.min_length = nonNegativeParam(ps, prefix + "min_length", p.min_length);
  p.max_rms_sigmas = positiveParam(ps, prefix + "max_rms_sigmas", p.max_rms_sigmas);
  p.max_side_share = nonNegativeParam(ps, prefix + "max_side_share", p.max_side_share);
  p.max_through_share = nonNegativeParam(ps, prefix + "max_through_share", p.max_through_share);
  p.min_fill = nonNegativeParam(ps, prefix + "min_fill", p.min_fill);
  p.fill_bin = positiveParam(ps, prefix + "fill_bin", p.fill_bin);
  p.coarse_beam_fill = ps.getBool(prefix + "coarse_beam_fill", p.coarse_beam_fill);
  return p;
}

namespace
{
std::int64_t cellKey(std::int64_t ix, std::int64_t iy)
{
  return (ix << 32) ^ (iy & 0xffffffffLL);
}

std::int64_t cellIndex(double v, double cell)
{
  return static_cast<std::int64_t>(std::floor(v / cell));
}

/// How many of the n points (xs, ys) lie within their band of `line`. Built for AVX2 too where the
/// processor has it (no FMA: the same distances, four at a time).
__attribute__((target_clones("avx2", "default"))) int countInBand(const double* xs, const double* ys,
                                                                  const double* bands, std::size_t n,
                                                                  const LineNormal& line)
{
  const double nx = line.nx, ny = line.ny, radius = line.radius;
  int count = 0;
  for (std::size_t i = 0; i < n; ++i) count += std::abs(xs[i] * nx + ys[i] * ny - radius) <= bands[i] ? 1 : 0;
  return count;
}
}  // namespace

std::shared_ptr<const ResidualReturns> ResidualReturns::of(std::vector<double> angles,
                                                           std::vector<double> ranges)
{
  auto r = std::make_shared<ResidualReturns>();
  if (angles.size() > 1 && angles.front() > angles.back())  // a negative increment
  {
    std::reverse(angles.begin(), angles.end());
    std::reverse(ranges.begin(), ranges.end());
  }
  r->angles = std::move(angles);
  r->ranges = std::move(ranges);
  for (const double v : r->ranges) r->max_range = std::max(r->max_range, v);
  return r;
}

void ResidualLineFinder::index(std::vector<ResidualPoint>& points, const std::vector<ResidualSource>& sources)
{
  points_ = &points;
  sources_ = &sources;
  max_sigma_ = 0.0;
  max_gap_ = 0.0;
  for (const ResidualPoint& w : points)
  {
    max_sigma_ = std::max(max_sigma_, static_cast<double>(w.sigma));
    max_gap_ = std::max(max_gap_, static_cast<double>(w.gap));
  }
  const double cell = params_.seed_radius;
  auto key = [&](std::uint32_t i)
  { return cellKey(cellIndex(points[i].p.x(), cell), cellIndex(points[i].p.y(), cell)); };
  cell_order_.resize(points.size());
  cell_points_.resize(points.size());
  cell_position_.resize(points.size());
  cells_.clear();
  std::vector<std::pair<std::int64_t, std::uint32_t>> keyed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    keyed[i] = {key(static_cast<std::uint32_t>(i)), static_cast<std::uint32_t>(i)};
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t k = 0; k < keyed.size(); ++k)
  {
    cell_order_[k] = keyed[k].second;
    const ResidualPoint& w = points[keyed[k].second];
    cell_points_[k] = {w.p, params_.band_sigmas * w.sigma, w.source, w.used};
    cell_position_[keyed[k].second] = static_cast<std::uint32_t>(k);
    auto [at, fresh] = cells_.emplace(keyed[k].first, std::make_pair(static_cast<std::uint32_t>(k), 0u));
    at->second.second = static_cast<std::uint32_t>(k) + 1;
  }
}

const ResidualSource* ResidualLineFinder::sourceById(std::uint32_t id) const
{
  if (id < sources_->size() && (*sources_)[id].id == id) return &(*sources_)[id];  // ids are positions
  const auto it = std::lower_bound(sources_->begin(), sources_->end(), id,
                                   [](const ResidualSource& s, std::uint32_t v) { return s.id < v; });
  return it != sources_->end() && it->id == id ? &*it : nullptr;
}

template <class F>
void ResidualLineFinder::forEachNear(const Vec2& origin, const Vec2& dir, double t0, double t1,
                                     double half_width, F&& f, const Stretch* visited) const
{
  // Every cell whose centre lies within half a diagonal of the rectangle.
  const double cell = params_.seed_radius;
  const Vec2 normal(-dir.y(), dir.x());
  struct CellRange
  {
    std::int64_t x0, x1, y0, y1;
  };
  const auto cellRange = [&](double from, double to)
  {
    const Vec2 a = origin + dir * from, b = origin + dir * to;
    const Vec2 lo = a.cwiseMin(b) - Vec2::Constant(half_width + cell);
    const Vec2 hi = a.cwiseMax(b) + Vec2::Constant(half_width + cell);
    return CellRange{cellIndex(lo.x(), cell), cellIndex(hi.x(), cell), cellIndex(lo.y(), cell),
                     cellIndex(hi.y(), cell)};
  };
  const CellRange range = cellRange(t0, t1);
  // Without `visited` an empty range, so the test below never reaches `visited`.
  const CellRange before = visited ? cellRange(visited->t0, visited->t1) : CellRange{1, 0, 1, 0};
  const double reach = half_width + cell * 0.7072;
  for (std::int64_t ix = range.x0; ix <= range.x1; ++ix)
    for (std::int64_t iy = range.y0; iy <= range.y1; ++iy)
    {
      const Vec2 centre((static_cast<double>(ix) + 0.5) * cell, (static_cast<double>(iy) + 0.5) * cell);
      const Vec2 rel = centre - origin;
      const double t = rel.dot(dir);
      if (t < t0 - cell || t > t1 + cell || std::abs(rel.dot(normal)) > reach) continue;
      // The same tests as the earlier call made, so a cell is visited by exactly one of the two.
      if (ix >= before.x0 && ix <= before.x1 && iy >= before.y0 && iy <= before.y1 &&
          t >= visited->t0 - cell && t <= visited->t1 + cell)
        continue;
      const auto cell_at = cells_.find(cellKey(ix, iy));
      if (cell_at == cells_.end()) continue;
      for (std::uint32_t k = cell_at->second.first; k < cell_at->second.second; ++k)
        f(cell_order_[k], cell_points_[k]);
    }
}

bool ResidualLineFinder::grow(std::size_t seed, ResidualLine& line)
{
  std::vector<ResidualPoint>& points = *points_;
  if (points[seed].used) return false;
  const ResidualSource* seed_source = sourceById(points[seed].source);
  if (seed_source == nullptr) return false;
  LineNormal fit_line;
  std::vector<Candidate> run;
  if (!seedLine(seed, fit_line) || !growRun(seed, fit_line, run)) return false;
  if (!acceptRun(run, fit_line, line))
  {
    // A wall seen only through the gaps between things in front of it: its run bridges the hidden
    // stretches (its points' beams are sparse there) and fails the fill test as a whole. Where its points
    // are dense, the piece around the seed is a line of its own.
    if (!keepSeedPiece(seed, fit_line, run) || !acceptRun(run, fit_line, line)) return false;
  }

  // Accepted: the endpoints with the observers on the left.
  const Vec2 observer = seed_source->laser.translation();
  const Vec2 d = line.end - line.start;
  if (Vec2(-d.y(), d.x()).dot(observer - line.start) < 0.0) std::swap(line.start, line.end);
  line.members.clear();
  line.members.reserve(run.size());
  for (const Candidate& c : run)
  {
    points[c.index].used = true;
    cell_points_[cell_position_[c.index]].used = true;
    line.members.push_back(c.index);
  }
  return true;
}

bool ResidualLineFinder::seedLine(std::size_t seed, LineNormal& best) const
{
  const std::vector<ResidualPoint>& points = *points_;
  const ResidualPoint& s = points[seed];
  const double radius = params_.seed_radius;
  // Unused neighbours of the seed, their coordinates and bands side by side: each line hypothesis below
  // reads them all.
  std::vector<std::uint32_t> near;
  std::vector<double> xs, ys, bands;
  const std::int64_t cx = cellIndex(s.p.x(), radius), cy = cellIndex(s.p.y(), radius);
  for (std::int64_t dx = -1; dx <= 1; ++dx)
    for (std::int64_t dy = -1; dy <= 1; ++dy)
    {
      const auto cell_at = cells_.find(cellKey(cx + dx, cy + dy));
      if (cell_at == cells_.end()) continue;
      for (std::uint32_t k = cell_at->second.first; k < cell_at->second.second; ++k)
      {
        const CellPoint& w = cell_points_[k];
        if (w.used || !((w.p - s.p).squaredNorm() <= radius * radius)) continue;
        near.push_back(cell_order_[k]);
        xs.push_back(w.p.x());
        ys.push_back(w.p.y());
        bands.push_back(w.band);
      }
    }
  const std::size_t n = near.size();
  if (n < 3) return false;

  // The line through the seed and one neighbour that holds the most neighbours in its band.
  int best_count = 0;
  const std::size_t stride = std::max<std::size_t>(1, n / 48);
  for (std::size_t a = 0; a < n; a += stride)
  {
    const Vec2 d = points[near[a]].p - s.p;
    const double len = d.norm();
    if (len < 2.0 * s.sigma) continue;
    LineNormal h;
    h.nx = -d.y() / len;
    h.ny = d.x() / len;
    h.radius = h.nx * s.p.x() + h.ny * s.p.y();
    const int count = countInBand(xs.data(), ys.data(), bands.data(), n, h);
    if (count > best_count)
    {
      best_count = count;
      best = h;
    }
  }
  return best_count >= 3;
}

bool ResidualLineFinder::alongThenIndex(const Candidate& a, const Candidate& b)
{
  return a.along < b.along || (a.along == b.along && a.index < b.index);
}

void ResidualLineFinder::sortAlong(std::vector<Candidate>& band, std::vector<Candidate>& scratch)
{
  bucketSortByKey(
      band, scratch, [](const Candidate& c) { return c.along; }, alongThenIndex);
}

bool ResidualLineFinder::growRun(std::size_t seed, LineNormal& fit_line, std::vector<Candidate>& run) const
{
  // Collect the band's unused points on the seed's side, keep the contiguous run through the
  // seed, refit; twice.
  // Any stretch at which the run ends inside gives the same run (points collected beyond it lie
  // farther than a gap from its ends), so the refit pass starts at the stretch the first one reached.
  double stretch = 4.0 * params_.seed_radius + bridge();
  for (int pass = 0; pass < 2; ++pass)
  {
    if (!runAlong(seed, fit_line, stretch, run)) return false;
    LineSums sums;
    for (const Candidate& c : run) sums.add((*points_)[c.index].p);
    if (!fitNormal(sums, fit_line)) return false;
  }
  return true;
}

double ResidualLineFinder::bridge() const
{
  return std::max(params_.max_gap, max_gap_) + 1e-9;
}

bool ResidualLineFinder::runAlong(std::size_t seed, const LineNormal& fit_line, double& stretch,
                                  std::vector<Candidate>& run) const
{
  // The band is searched over a stretch of the line that doubles until the run ends inside it by more
  // than any gap could bridge.
  const std::vector<ResidualPoint>& points = *points_;
  const auto observer_side = [&](std::uint32_t source_id)
  {
    const ResidualSource* src = sourceById(source_id);
    return src != nullptr && fit_line.signedDistance(src->laser.translation()) > 0.0 ? 1 : -1;
  };
  const double half_width = params_.band_sigmas * max_sigma_;
  const int side = observer_side(points[seed].source);
  const Vec2 dir(-fit_line.ny, fit_line.nx);
  const Vec2 foot = Vec2(fit_line.nx, fit_line.ny) * fit_line.radius;
  const double t_seed = dir.dot(points[seed].p - foot);
  // A cell's points come mostly from one keyframe: its side of the line is looked up once per run of them.
  std::uint32_t last_source = std::numeric_limits<std::uint32_t>::max();
  int last_side = 0;
  // A longer stretch adds the points of the cells the shorter one did not visit to its sorted band.
  std::vector<Candidate> band, fresh, scratch;
  std::optional<Stretch> visited;
  for (;; stretch *= 2.0)
  {
    fresh.clear();
    forEachNear(
        foot, dir, t_seed - stretch, t_seed + stretch, half_width,
        [&](std::uint32_t j, const CellPoint& w)
        {
          if (w.used || fit_line.distance(w.p) > w.band) return;
          if (w.source != last_source)
          {
            last_source = w.source;
            last_side = observer_side(w.source);
          }
          if (last_side != side) return;
          fresh.push_back({j, dir.dot(w.p - foot)});
        },
        visited ? &*visited : nullptr);
    sortAlong(fresh, scratch);
    scratch.resize(band.size() + fresh.size());
    std::merge(band.begin(), band.end(), fresh.begin(), fresh.end(), scratch.begin(), alongThenIndex);
    band.swap(scratch);
    visited = Stretch{t_seed - stretch, t_seed + stretch};
    if (!runThrough(seed, band, run)) return false;
    if (run.front().along - (t_seed - stretch) > bridge() && (t_seed + stretch) - run.back().along > bridge())
      return true;
  }
}

bool ResidualLineFinder::runThrough(std::size_t seed, const std::vector<Candidate>& band,
                                    std::vector<Candidate>& run) const
{
  const std::vector<ResidualPoint>& points = *points_;
  const auto at =
      std::find_if(band.begin(), band.end(), [seed](const Candidate& c) { return c.index == seed; });
  if (at == band.end()) return false;
  std::size_t lo = static_cast<std::size_t>(at - band.begin()), hi = lo;
  const auto joined = [&](std::size_t a, std::size_t b)
  {
    const double allowed = std::max({params_.max_gap, static_cast<double>(points[band[a].index].gap),
                                     static_cast<double>(points[band[b].index].gap)});
    return band[b].along - band[a].along <= allowed;
  };
  while (lo > 0 && joined(lo - 1, lo)) --lo;
  while (hi + 1 < band.size() && joined(hi, hi + 1)) ++hi;
  run.assign(band.begin() + static_cast<std::ptrdiff_t>(lo),
             band.begin() + static_cast<std::ptrdiff_t>(hi) + 1);
  return true;
}

bool ResidualLineFinder::acceptRun(const std::vector<Candidate>& run, const LineNormal& fit_line,
                                   ResidualLine& line) const
{
  // Support, extent, fit and the absence of clutter beside it.
  const std::vector<ResidualPoint>& points = *points_;
  const double band_k = params_.band_sigmas;
  if (static_cast<int>(run.size()) < params_.min_points) return false;
  std::unordered_set<std::uint32_t> sources;
  double sigma_sum = 0.0, squares = 0.0;
  for (const Candidate& c : run)
  {
    const ResidualPoint& w = points[c.index];
    sources.insert(w.source);
    sigma_sum += w.sigma;
    const double d = fit_line.signedDistance(w.p);
    squares += d * d;
  }
  if (static_cast<int>(sources.size()) < params_.min_sources) return false;
  const double n = static_cast<double>(run.size());
  const double sigma = sigma_sum / n;
  if (std::sqrt(squares / n) > params_.max_rms_sigmas * sigma) return false;
  const Vec2 dir(-fit_line.ny, fit_line.nx);
  const Vec2 foot = Vec2(fit_line.nx, fit_line.ny) * fit_line.radius;
  double t0 = dir.dot(points[run.front().index].p - foot), t1 = t0;
  for (const Candidate& c : run)
  {
    const double t = dir.dot(points[c.index].p - foot);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
  }
  if (t1 - t0 < params_.min_length) return false;
  if (params_.min_fill > 0.0 && filledShare(run, fit_line, t0, t1) < params_.min_fill) return false;
  if (curved(run, fit_line, t0, t1, sigma)) return false;
  // Beside the band: between one and two bands off the line, away from the ends (where a
  // corner's other wall starts).
  const double margin = 2.0 * band_k * sigma;
  std::size_t beside = 0;
  if (t1 - t0 > 2.0 * margin)
    forEachNear(foot, dir, t0 + margin, t1 - margin, 2.0 * band_k * max_sigma_,
                [&](std::uint32_t, const CellPoint& w)
                {
                  const double t = dir.dot(w.p - foot);
                  if (t < t0 + margin || t > t1 - margin) return;
                  const double d = fit_line.distance(w.p);
                  if (d > w.band && d <= 2.0 * w.band) ++beside;
                });
  if (static_cast<double>(beside) > params_.max_side_share * n) return false;

  line.start = foot + dir * t0;
  line.end = foot + dir * t1;
  line.sigma = sigma;
  return !seenThrough(line.start, line.end, band_k * sigma);
}

double ResidualLineFinder::filledShare(const std::vector<Candidate>& run, const LineNormal& line, double t0,
                                       double t1) const
{
  const std::vector<ResidualPoint>& points = *points_;
  const Vec2 dir(-line.ny, line.nx);
  const Vec2 foot = Vec2(line.nx, line.ny) * line.radius;
  const auto bins = static_cast<std::size_t>(std::ceil((t1 - t0) / params_.fill_bin));
  std::vector<char> filled(std::max<std::size_t>(bins, 1), 0);
  const auto bin_of = [&](double t)
  { return std::min(filled.size() - 1, static_cast<std::size_t>(std::max(0.0, t - t0) / params_.fill_bin)); };
  struct Near
  {
    std::uint32_t source;
    std::int32_t beam;
    double along;
    float gap;
    bool operator<(const Near& o) const { return source < o.source || (source == o.source && beam < o.beam); }
  };
  std::vector<Near> near_line;
  for (const Candidate& c : run)
  {
    const ResidualPoint& w = points[c.index];
    if (line.distance(w.p) > params_.fill_bin) continue;
    const double t = dir.dot(w.p - foot);
    filled[bin_of(t)] = 1;
    if (params_.coarse_beam_fill && w.beam >= 0) near_line.push_back({w.source, w.beam, t, w.gap});
  }
  std::sort(near_line.begin(), near_line.end());
  for (std::size_t i = 1; i < near_line.size(); ++i)
  {
    const Near &a = near_line[i - 1], &b = near_line[i];
    if (a.source != b.source || b.beam - a.beam != 1) continue;
    const double apart = std::abs(b.along - a.along);
    if (apart <= params_.max_gap || apart > std::max(a.gap, b.gap)) continue;
    for (std::size_t k = bin_of(std::min(a.along, b.along)); k <= bin_of(std::max(a.along, b.along)); ++k)
      filled[k] = 1;
  }
  return static_cast<double>(std::count(filled.begin(), filled.end(), 1)) /
         static_cast<double>(filled.size());
}

bool ResidualLineFinder::keepSeedPiece(std::size_t seed, LineNormal& fit_line,
                                       std::vector<Candidate>& run) const
{
  if (!(params_.min_fill > 0.0) || run.empty()) return false;
  const std::vector<ResidualPoint>& points = *points_;
  const Vec2 dir(-fit_line.ny, fit_line.nx);
  const Vec2 foot = Vec2(fit_line.nx, fit_line.ny) * fit_line.radius;
  double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
  std::vector<double> along;  // where the points that fill bins lie along the line
  double sigma_sum = 0.0;
  for (const Candidate& c : run)
  {
    const double t = dir.dot(points[c.index].p - foot);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
    sigma_sum += points[c.index].sigma;
    if (fit_line.distance(points[c.index].p) <= params_.fill_bin) along.push_back(t);
  }
  if (filledShare(run, fit_line, t0, t1) >= params_.min_fill) return false;  // it failed for another reason
  // A curved wall's points leave the line along the run: its chords are the curvature test's matter.
  if (curved(run, fit_line, t0, t1, sigma_sum / static_cast<double>(run.size()))) return false;
  std::sort(along.begin(), along.end());
  // The piece: between the empty stretches longer than max_gap nearest the seed on either side.
  const double t_seed = dir.dot(points[seed].p - foot);
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < along.size(); ++i)
  {
    const double a = along[i - 1], b = along[i];
    if (b - a <= params_.max_gap) continue;
    if (b <= t_seed)
      lo = b;
    else if (a >= t_seed)
    {
      hi = a;
      break;
    }
    else
      return false;  // the seed lies in an empty stretch
  }
  if (!std::isfinite(lo) && !std::isfinite(hi)) return false;  // no empty stretch to cut at
  std::vector<Candidate> piece;
  LineSums sums;
  for (const Candidate& c : run)
  {
    const double t = dir.dot(points[c.index].p - foot);
    if (t < lo || t > hi) continue;
    piece.push_back(c);
    sums.add(points[c.index].p);
  }
  if (static_cast<int>(piece.size()) < params_.min_points || !fitNormal(sums, fit_line)) return false;
  run.swap(piece);
  return true;
}

bool ResidualLineFinder::curved(const std::vector<Candidate>& run, const LineNormal& line, double t0,
                                double t1, double sigma) const
{
  // Residuals against the position along the line, u in [-1, 1]: d = a + b u + c u^2. A chord of
  // a curved wall has a significant c (its sagitta); a straight wall's c is noise.
  const std::vector<ResidualPoint>& points = *points_;
  const Vec2 dir(-line.ny, line.nx);
  const Vec2 foot = Vec2(line.nx, line.ny) * line.radius;
  const double mid = 0.5 * (t0 + t1), half = std::max(0.5 * (t1 - t0), 1e-9);
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Candidate& c : run)
  {
    const Vec2& p = points[c.index].p;
    const double u = (dir.dot(p - foot) - mid) / half;
    const Eigen::Vector3d row(1.0, u, u * u);
    normal += row * row.transpose();
    rhs += row * line.signedDistance(p);
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(normal);
  if (!lu.isInvertible()) return false;
  const double c = lu.solve(rhs)(2);
  const double c_std = sigma * std::sqrt(std::max(0.0, lu.inverse()(2, 2)));
  return std::abs(c) > 3.0 * c_std && std::abs(c) > 0.5 * sigma;
}

bool ResidualLineFinder::seenThrough(const Vec2& a, const Vec2& b, double band) const
{
  // Only the interior counts: near an end, a beam grazing past a corner is no contradiction. Of each
  // scan only the beams between the directions of the two ends can meet the line.
  const double length = (b - a).norm();
  const double margin = std::min(0.25 * length, 2.0 * band);
  std::size_t on = 0, through = 0;
  for (const ResidualSource& src : *sources_)
  {
    if (!src.returns || src.returns->angles.empty() ||
        linemap::distanceToSegment(src.laser.translation(), a, b) > src.returns->max_range + band)
      continue;
    const std::vector<double>& angles = src.returns->angles;
    const std::vector<double>& ranges = src.returns->ranges;
    const linemap::Pose2 to_laser = src.laser.inverse();
    const Vec2 la = to_laser.apply(a), lb = to_laser.apply(b);
    const Vec2 d = lb - la;
    double from = std::atan2(la.y(), la.x()), to = std::atan2(lb.y(), lb.x());
    if (from > to) std::swap(from, to);
    // The segment subtends less than half a turn from a laser not on it: a wider interval wraps.
    if (to - from > linemap::kPi)
    {
      const double wrapped = from + 2.0 * linemap::kPi;
      from = to;
      to = wrapped;
    }
    // The scan's angles may follow another convention than atan2's: the interval a turn either way too.
    for (int turn = -1; turn <= 1; ++turn)
    {
      const double shift = 2.0 * linemap::kPi * turn;
      const auto first = std::lower_bound(angles.begin(), angles.end(), from + shift);
      const auto last = std::upper_bound(first, angles.end(), to + shift);
      for (auto it = first; it != last; ++it)
      {
        const std::size_t i = static_cast<std::size_t>(it - angles.begin());
        const Vec2 u(std::cos(*it), std::sin(*it));
        // Ray u * s meets la + d * t where s u - t d = la.
        const double det = d.x() * u.y() - d.y() * u.x();
        if (std::abs(det) < 1e-12) continue;
        const double t = (u.x() * la.y() - u.y() * la.x()) / det;
        const double s = (d.x() * la.y() - d.y() * la.x()) / det;
        if (s <= 0.0 || t * length < margin || (1.0 - t) * length < margin) continue;
        if (ranges[i] > s + band)
          ++through;
        else if (ranges[i] >= s - band)
          ++on;
      }
    }
  }
  return static_cast<double>(through) > params_.max_through_share * static_cast<double>(on);
}

}  // namespace line_extraction
