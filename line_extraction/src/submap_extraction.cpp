// Lines in the unexplained points of the last few metres of scans (see the header).
#include "line_extraction/submap_extraction.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
SubmapParams SubmapParams::fromParams(const linemap::ParamSet& ps)
{
  SubmapParams p;
  p.enabled = ps.getBool("submap/enabled", p.enabled);
  p.scan_distance = nonNegativeParam(ps, "submap/scan_distance", p.scan_distance);
  p.scan_angle = nonNegativeParam(ps, "submap/scan_angle", p.scan_angle);
  p.window_distance = positiveParam(ps, "submap/window_distance", p.window_distance);
  p.window_scans = intParamAtLeast(ps, "submap/window_scans", p.window_scans, 2);
  p.band_sigmas = positiveParam(ps, "submap/band_sigmas", p.band_sigmas);
  p.seed_radius = positiveParam(ps, "submap/seed_radius", p.seed_radius);
  p.max_gap = positiveParam(ps, "submap/max_gap", p.max_gap);
  p.min_points = intParamAtLeast(ps, "submap/min_points", p.min_points, 3);
  p.min_scans = intParamAtLeast(ps, "submap/min_scans", p.min_scans, 2);
  p.min_length = nonNegativeParam(ps, "submap/min_length", p.min_length);
  p.max_rms_sigmas = positiveParam(ps, "submap/max_rms_sigmas", p.max_rms_sigmas);
  p.max_side_share = nonNegativeParam(ps, "submap/max_side_share", p.max_side_share);
  p.max_through_share = nonNegativeParam(ps, "submap/max_through_share", p.max_through_share);
  return p;
}

namespace
{
std::int64_t cellKey(std::int64_t ix, std::int64_t iy)
{
  return (ix << 32) ^ (iy & 0xffffffffLL);
}
}  // namespace

SubmapExtractor::SubmapExtractor(const SubmapParams& params, const SensorModel& sensor)
    : params_(params), sensor_(sensor)
{
}

std::size_t SubmapExtractor::appendTo(const PreparedScan& scan, ExtractionResult& result,
                                      const Pose2& laser_pose)
{
  const std::vector<Segment>& found = update(scan, result, laser_pose);
  result.segments.insert(result.segments.end(), found.begin(), found.end());
  return found.size();
}

void SubmapExtractor::observeStamp(std::uint64_t stamp_ns)
{
  if (stamp_ns < last_stamp_ns_) reset();
  last_stamp_ns_ = stamp_ns;
}

void SubmapExtractor::reset()
{
  scans_.clear();
  points_.clear();
  pending_.clear();
  output_.clear();
  has_last_ = false;
  path_ = 0.0;
}

bool SubmapExtractor::admits(const Pose2& laser) const
{
  if (!has_last_) return true;
  const double moved = (laser.translation() - last_admitted_.translation()).norm();
  const double turned = std::abs(linemap::normalizeAngle(laser.theta - last_admitted_.theta));
  return moved >= params_.scan_distance || turned >= params_.scan_angle;
}

const std::vector<Segment>& SubmapExtractor::update(const PreparedScan& scan,
                                                    const ExtractionResult& extracted,
                                                    const Pose2& laser_pose)
{
  output_.clear();
  if (!params_.enabled) return output_;
  if (admits(laser_pose))
  {
    if (has_last_) path_ += (laser_pose.translation() - last_admitted_.translation()).norm();
    last_admitted_ = laser_pose;
    has_last_ = true;
    const std::size_t before = points_.size();
    addResiduals(scan, extracted, laser_pose);
    const std::size_t added = points_.size() - before;
    dropOldScans();  // erases a prefix of points_: the new ones stay the last `added`
    pending_.clear();
    buildGrid();
    findLines(points_.size() - added);
  }
  emit(laser_pose);
  return output_;
}

void SubmapExtractor::addResiduals(const PreparedScan& scan, const ExtractionResult& extracted,
                                   const Pose2& laser)
{
  std::vector<char> explained(scan.size(), 0);
  for (const Segment& s : extracted.segments)
    for (int k = s.index_begin; k < s.index_end; ++k)
      explained[static_cast<std::size_t>(extracted.point_indices[static_cast<std::size_t>(k)])] = 1;
  const std::uint32_t id = next_scan_id_++;
  scans_.push_back({id, laser, path_, scan.angles, scan.ranges});
  for (std::size_t i = 0; i < scan.size(); ++i)
  {
    if (explained[i]) continue;
    WindowPoint w;
    w.p = laser.apply(scan.points[i]);
    w.sigma = static_cast<float>(sensor_.sigma(scan.ranges[i]));
    // The gap to either neighbour on one surface; the model's is 0 where it adds nothing.
    double gap2 = scan.gap2.empty() ? 0.0 : scan.gap2[i];
    if (!scan.gap2.empty() && i + 1 < scan.size()) gap2 = std::max(gap2, scan.gap2[i + 1]);
    w.gap = static_cast<float>(std::sqrt(gap2));
    w.scan = id;
    points_.push_back(w);
  }
}

void SubmapExtractor::dropOldScans()
{
  std::size_t drop = 0;
  while (scans_.size() - drop > 1 && (static_cast<int>(scans_.size() - drop) > params_.window_scans ||
                                      path_ - scans_[drop].path > params_.window_distance))
    ++drop;
  if (drop == 0) return;
  const std::uint32_t oldest_kept = scans_[drop].id;
  scans_.erase(scans_.begin(), scans_.begin() + static_cast<std::ptrdiff_t>(drop));
  // Points are in scan order, so the dropped ones are a prefix.
  const auto keep = std::find_if(points_.begin(), points_.end(),
                                 [oldest_kept](const WindowPoint& w) { return w.scan >= oldest_kept; });
  points_.erase(points_.begin(), keep);
}

void SubmapExtractor::buildGrid()
{
  const double cell = params_.seed_radius;
  cell_order_.resize(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i) cell_order_[i] = static_cast<std::uint32_t>(i);
  auto key = [&](std::uint32_t i)
  {
    return cellKey(static_cast<std::int64_t>(std::floor(points_[i].p.x() / cell)),
                   static_cast<std::int64_t>(std::floor(points_[i].p.y() / cell)));
  };
  std::sort(cell_order_.begin(), cell_order_.end(),
            [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  cell_keys_.resize(points_.size());
  for (std::size_t k = 0; k < cell_order_.size(); ++k) cell_keys_[k] = key(cell_order_[k]);
}

const SubmapExtractor::WindowScan* SubmapExtractor::scanById(std::uint32_t id) const
{
  const auto it = std::lower_bound(scans_.begin(), scans_.end(), id,
                                   [](const WindowScan& s, std::uint32_t v) { return s.id < v; });
  return it != scans_.end() && it->id == id ? &*it : nullptr;
}

void SubmapExtractor::findLines(std::size_t first_new)
{
  for (std::size_t seed = first_new; seed < points_.size(); ++seed)
  {
    if (points_[seed].used) continue;
    FoundLine line;
    if (grow(seed, line))
    {
      pending_.push_back(std::move(line));
      ++lines_found_;
    }
  }
}

bool SubmapExtractor::grow(std::size_t seed, FoundLine& line)
{
  // Seen from the seed's side (its scan's laser).
  const WindowScan* seed_scan = scanById(points_[seed].scan);
  if (seed_scan == nullptr) return false;
  LineNormal fit_line;
  std::vector<Candidate> run;
  if (!seedLine(seed, fit_line) || !growRun(seed, fit_line, run) || !acceptRun(run, fit_line, line))
    return false;

  // Accepted: the endpoints with the observers on the left.
  const Vec2 observer = seed_scan->laser.translation();
  const Vec2 d = line.end - line.start;
  if (Vec2(-d.y(), d.x()).dot(observer - line.start) < 0.0) std::swap(line.start, line.end);
  line.members.reserve(run.size());
  for (const Candidate& c : run)
  {
    points_[c.index].used = true;
    line.members.push_back(points_[c.index].p);
  }
  return true;
}

bool SubmapExtractor::seedLine(std::size_t seed, LineNormal& best) const
{
  const WindowPoint& s = points_[seed];
  const double radius = params_.seed_radius;
  // Unused neighbours of the seed.
  std::vector<std::uint32_t> near;
  const std::int64_t cx = static_cast<std::int64_t>(std::floor(s.p.x() / radius));
  const std::int64_t cy = static_cast<std::int64_t>(std::floor(s.p.y() / radius));
  for (std::int64_t dx = -1; dx <= 1; ++dx)
    for (std::int64_t dy = -1; dy <= 1; ++dy)
    {
      const std::int64_t k = cellKey(cx + dx, cy + dy);
      const auto range = std::equal_range(cell_keys_.begin(), cell_keys_.end(), k);
      for (auto it = range.first; it != range.second; ++it)
      {
        const std::uint32_t j = cell_order_[static_cast<std::size_t>(it - cell_keys_.begin())];
        if (!points_[j].used && (points_[j].p - s.p).squaredNorm() <= radius * radius) near.push_back(j);
      }
    }
  if (static_cast<int>(near.size()) < 3) return false;

  // The line through the seed and one neighbour that holds the most neighbours in its band.
  int best_count = 0;
  const std::size_t stride = std::max<std::size_t>(1, near.size() / 48);
  for (std::size_t a = 0; a < near.size(); a += stride)
  {
    const Vec2 d = points_[near[a]].p - s.p;
    const double len = d.norm();
    if (len < 2.0 * s.sigma) continue;
    LineNormal h;
    h.nx = -d.y() / len;
    h.ny = d.x() / len;
    h.radius = h.nx * s.p.x() + h.ny * s.p.y();
    int count = 0;
    for (std::uint32_t j : near)
      if (h.distance(points_[j].p) <= params_.band_sigmas * points_[j].sigma) ++count;
    if (count > best_count)
    {
      best_count = count;
      best = h;
    }
  }
  return best_count >= 3;
}

bool SubmapExtractor::growRun(std::size_t seed, LineNormal& fit_line, std::vector<Candidate>& run) const
{
  // Grow along the whole window twice: collect the band's points on the seed's side, keep the
  // contiguous run through the seed, refit.
  const auto observer_side = [&](const LineNormal& l, std::uint32_t scan_id)
  {
    const WindowScan* ws = scanById(scan_id);
    return ws != nullptr && l.signedDistance(ws->laser.translation()) > 0.0 ? 1 : -1;
  };
  for (int pass = 0; pass < 2; ++pass)
  {
    const int side = observer_side(fit_line, points_[seed].scan);
    const Vec2 dir(-fit_line.ny, fit_line.nx);
    std::vector<Candidate> band;
    for (std::size_t j = 0; j < points_.size(); ++j)
    {
      const WindowPoint& w = points_[j];
      if (w.used || fit_line.distance(w.p) > params_.band_sigmas * w.sigma) continue;
      if (observer_side(fit_line, w.scan) != side) continue;
      band.push_back({static_cast<std::uint32_t>(j), dir.dot(w.p)});
    }
    std::sort(band.begin(), band.end(),
              [](const Candidate& a, const Candidate& b) { return a.along < b.along; });
    const auto at =
        std::find_if(band.begin(), band.end(), [seed](const Candidate& c) { return c.index == seed; });
    if (at == band.end()) return false;
    std::size_t lo = static_cast<std::size_t>(at - band.begin()), hi = lo;
    const auto joined = [&](std::size_t a, std::size_t b)
    {
      const double allowed = std::max({params_.max_gap, static_cast<double>(points_[band[a].index].gap),
                                       static_cast<double>(points_[band[b].index].gap)});
      return band[b].along - band[a].along <= allowed;
    };
    while (lo > 0 && joined(lo - 1, lo)) --lo;
    while (hi + 1 < band.size() && joined(hi, hi + 1)) ++hi;
    run.assign(band.begin() + static_cast<std::ptrdiff_t>(lo),
               band.begin() + static_cast<std::ptrdiff_t>(hi) + 1);
    LineSums sums;
    for (const Candidate& c : run) sums.add(points_[c.index].p);
    if (!fitNormal(sums, fit_line)) return false;
  }
  return true;
}

bool SubmapExtractor::acceptRun(const std::vector<Candidate>& run, const LineNormal& fit_line,
                                FoundLine& line) const
{
  // Support, extent, fit and the absence of clutter beside it.
  const double band_k = params_.band_sigmas;
  if (static_cast<int>(run.size()) < params_.min_points) return false;
  std::unordered_set<std::uint32_t> scans;
  double sigma_sum = 0.0, squares = 0.0;
  for (const Candidate& c : run)
  {
    const WindowPoint& w = points_[c.index];
    scans.insert(w.scan);
    sigma_sum += w.sigma;
    const double d = fit_line.signedDistance(w.p);
    squares += d * d;
  }
  if (static_cast<int>(scans.size()) < params_.min_scans) return false;
  const double n = static_cast<double>(run.size());
  const double sigma = sigma_sum / n;
  if (std::sqrt(squares / n) > params_.max_rms_sigmas * sigma) return false;
  const Vec2 dir(-fit_line.ny, fit_line.nx);
  double t0 = dir.dot(points_[run.front().index].p), t1 = t0;
  for (const Candidate& c : run)
  {
    const double t = dir.dot(points_[c.index].p);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
  }
  if (t1 - t0 < params_.min_length) return false;
  if (curved(run, fit_line, t0, t1, sigma)) return false;
  // Beside the band: between one and two bands off the line, away from the ends (where a
  // corner's other wall starts).
  const double margin = 2.0 * band_k * sigma;
  std::size_t beside = 0;
  for (const WindowPoint& w : points_)
  {
    const double t = dir.dot(w.p);
    if (t < t0 + margin || t > t1 - margin) continue;
    const double d = fit_line.distance(w.p);
    if (d > band_k * w.sigma && d <= 2.0 * band_k * w.sigma) ++beside;
  }
  if (static_cast<double>(beside) > params_.max_side_share * n) return false;

  const Vec2 foot = Vec2(fit_line.nx, fit_line.ny) * fit_line.radius;
  line.start = foot + dir * t0;
  line.end = foot + dir * t1;
  line.sigma = sigma;
  return !seenThrough(line.start, line.end, band_k * sigma);
}

bool SubmapExtractor::curved(const std::vector<Candidate>& run, const LineNormal& line, double t0, double t1,
                             double sigma) const
{
  // Residuals against the position along the line, u in [-1, 1]: d = a + b u + c u^2. A chord of
  // a curved wall has a significant c (its sagitta); a straight wall's c is noise.
  const Vec2 dir(-line.ny, line.nx);
  const double mid = 0.5 * (t0 + t1), half = std::max(0.5 * (t1 - t0), 1e-9);
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Candidate& c : run)
  {
    const Vec2& p = points_[c.index].p;
    const double u = (dir.dot(p) - mid) / half;
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

bool SubmapExtractor::seenThrough(const Vec2& a, const Vec2& b, double band) const
{
  // Only the interior counts: near an end, a beam grazing past a corner is no contradiction.
  const double length = (b - a).norm();
  const double margin = std::min(0.25 * length, 2.0 * band);
  std::size_t on = 0, through = 0;
  for (const WindowScan& ws : scans_)
  {
    const Pose2 to_laser = ws.laser.inverse();
    const Vec2 la = to_laser.apply(a), lb = to_laser.apply(b);
    const Vec2 d = lb - la;
    for (std::size_t i = 0; i < ws.angles.size(); ++i)
    {
      const Vec2 u(std::cos(ws.angles[i]), std::sin(ws.angles[i]));
      // Ray u * s meets la + d * t where s u - t d = la.
      const double det = d.x() * u.y() - d.y() * u.x();
      if (std::abs(det) < 1e-12) continue;
      const double t = (u.x() * la.y() - u.y() * la.x()) / det;
      const double s = (d.x() * la.y() - d.y() * la.x()) / det;
      if (s <= 0.0 || t * length < margin || (1.0 - t) * length < margin) continue;
      if (ws.ranges[i] > s + band)
        ++through;
      else if (ws.ranges[i] >= s - band)
        ++on;
    }
  }
  return static_cast<double>(through) > params_.max_through_share * static_cast<double>(on);
}

void SubmapExtractor::emit(const Pose2& laser)
{
  const Pose2 to_laser = laser.inverse();
  for (const FoundLine& line : pending_)
  {
    LineSums sums;
    for (const Vec2& p : line.members) sums.add(to_laser.apply(p));
    const LineFit fit = fitLine(sums, line.sigma);
    if (!fit.valid) continue;
    Segment seg;
    seg.angle = fit.angle;
    seg.radius = fit.radius;
    seg.covariance = fit.covariance;
    // The endpoints projected onto the laser-frame fit (the same line up to rounding).
    const Vec2 a = to_laser.apply(line.start), b = to_laser.apply(line.end);
    seg.start = a - fit.normal * fit.signedDistance(a);
    seg.end = b - fit.normal * fit.signedDistance(b);
    seg.num_points = static_cast<int>(line.members.size());
    output_.push_back(seg);
  }
}

}  // namespace line_extraction
