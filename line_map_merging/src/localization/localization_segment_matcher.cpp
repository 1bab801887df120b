#include "line_map_merging/localization/localization_segment_matcher.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace line_map_merging
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
Vec2 closestOnSegment(const Vec2& p, const Vec2& a, const Vec2& b)
{
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return a;
  const double t = std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
  return a + t * d;
}

// How far the point at grid coordinates (fx, fy) (in cells) lies from every cell outside the square of cells
// [x0, x1] x [y0, y1] of a width x height grid [m]; beyond the grid's edge there is no cell.
double clearance(double fx, double fy, int x0, int x1, int y0, int y1, int width, int height, double cell)
{
  const double infinity = std::numeric_limits<double>::infinity();
  return std::min({x0 <= 0 ? infinity : (fx - x0) * cell, x1 >= width - 1 ? infinity : (x1 + 1 - fx) * cell,
                   y0 <= 0 ? infinity : (fy - y0) * cell,
                   y1 >= height - 1 ? infinity : (y1 + 1 - fy) * cell});
}

}  // namespace

LocalizationSegmentIndex::LocalizationSegmentIndex(std::vector<Segment2> segments, double cell_size,
                                                   double reach)
    : cell_size_(cell_size), reach_(reach)
{
  for (const auto& s : segments)
    if (s.start.allFinite() && s.end.allFinite() && s.length() > 0.0) segments_.push_back(s);
  if (segments_.empty() || !(cell_size > 0.0) || !(reach >= 0.0)) return;
  lower_ = upper_ = segments_.front().start;
  for (const auto& s : segments_)
  {
    lower_ = lower_.cwiseMin(s.start).cwiseMin(s.end);
    upper_ = upper_.cwiseMax(s.start).cwiseMax(s.end);
  }
  origin_ = lower_ - Vec2::Constant(cell_size);
  width_ = static_cast<int>(std::ceil((upper_.x() - origin_.x()) / cell_size)) + 2;
  height_ = static_cast<int>(std::ceil((upper_.y() - origin_.y()) / cell_size)) + 2;
  // A cell lists the segments that may pass through it: those within half its diagonal of its centre (a
  // little more, so that rounding never leaves one out). Counted first, then filled in place: no list is
  // built per cell.
  const double slack = 0.5 * std::sqrt(2.0) * cell_size * (1.0 + 1e-9);
  const auto for_each_cell = [&](const Segment2& s, auto&& take)
  {
    const Vec2 lo = s.start.cwiseMin(s.end) - Vec2::Constant(slack);
    const Vec2 hi = s.start.cwiseMax(s.end) + Vec2::Constant(slack);
    const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - origin_.x()) / cell_size)));
    const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - origin_.y()) / cell_size)));
    const int x1 = std::min(width_ - 1, static_cast<int>(std::floor((hi.x() - origin_.x()) / cell_size)));
    const int y1 = std::min(height_ - 1, static_cast<int>(std::floor((hi.y() - origin_.y()) / cell_size)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
      {
        const Vec2 centre = origin_ + Vec2((x + 0.5) * cell_size, (y + 0.5) * cell_size);
        if ((closestOnSegment(centre, s.start, s.end) - centre).norm() <= slack)
          take(static_cast<std::size_t>(y) * width_ + x);
      }
  };
  const std::size_t cells = static_cast<std::size_t>(width_) * height_;
  std::vector<std::size_t> count(cells + 1, 0);
  for (const auto& s : segments_) for_each_cell(s, [&](std::size_t cell) { ++count[cell + 1]; });
  for (std::size_t c = 0; c < cells; ++c) count[c + 1] += count[c];
  if (count[cells] > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("localization segment index: too many cell entries; raise match/index_cell");
  cell_start_.assign(count.begin(), count.end());
  candidates_.resize(count[cells]);
  // In segment order, so that every cell lists its segments in the input's order.
  for (std::size_t i = 0; i < segments_.size(); ++i)
  {
    const Vec2 d = segments_[i].end - segments_[i].start;
    const Candidate entry{segments_[i].start.x(), segments_[i].start.y(), d.x(), d.y(), d.squaredNorm(), i};
    for_each_cell(segments_[i], [&](std::size_t cell) { candidates_[count[cell]++] = entry; });
  }
}

std::optional<LocalizationSegmentIndex::Nearest> LocalizationSegmentIndex::nearest(const Vec2& p,
                                                                                   const Vec2* sensor) const
{
  if (segments_.empty() || !p.allFinite()) return std::nullopt;
  if (p.x() < lower_.x() - reach_ || p.y() < lower_.y() - reach_ || p.x() > upper_.x() + reach_ ||
      p.y() > upper_.y() + reach_)
    return std::nullopt;
  // Rings of cells around the point's cell, nearest first, until no unsearched cell can hold a nearer
  // segment: one is at least as far as the edge of the square searched (beyond the grid there is none).
  const double fx = (p.x() - origin_.x()) / cell_size_, fy = (p.y() - origin_.y()) / cell_size_;
  const int cx = static_cast<int>(std::floor(fx)), cy = static_cast<int>(std::floor(fy));
  // The arithmetic of closestOnSegment() and linemap::cross(); the nearest wins, and among equally near
  // segments the one listed last in the input (so any cell layout gives the same answer).
  const Candidate* best = nullptr;
  double best_d2 = reach_ * reach_, best_t = 0.0;
  const auto visit = [&](int x, int y)
  {
    const std::size_t cell = static_cast<std::size_t>(y) * width_ + x;
    for (std::size_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k)
    {
      const Candidate& s = candidates_[k];
      if (sensor && s.dx * (sensor->y() - s.ay) - s.dy * (sensor->x() - s.ax) < 0.0) continue;
      const double t = std::clamp(((p.x() - s.ax) * s.dx + (p.y() - s.ay) * s.dy) / s.length2, 0.0, 1.0);
      const double ex = p.x() - (s.ax + t * s.dx), ey = p.y() - (s.ay + t * s.dy);
      const double d2 = ex * ex + ey * ey;
      if (d2 < best_d2 || (d2 == best_d2 && (!best || s.segment > best->segment)))
      {
        best_d2 = d2;
        best_t = t;
        best = &s;
      }
    }
  };
  for (int k = 0;; ++k)
  {
    const int x0 = cx - k, x1 = cx + k, y0 = cy - k, y1 = cy + k;
    const int row0 = std::max(y0, 0), row1 = std::min(y1, height_ - 1);
    const int col0 = std::max(x0, 0), col1 = std::min(x1, width_ - 1);
    for (int y = row0; y <= row1; ++y)
    {
      if (y == y0 || y == y1)
        for (int x = col0; x <= col1; ++x) visit(x, y);
      else
      {
        if (x0 >= 0 && x0 < width_) visit(x0, y);
        if (x1 >= 0 && x1 < width_ && x1 != x0) visit(x1, y);
      }
    }
    const double clear = clearance(fx, fy, x0, x1, y0, y1, width_, height_, cell_size_);
    // A margin for rounding: a segment just beyond the square may compute as near as one inside it.
    const double sure = clear * (1.0 - 1e-9) - 1e-12;
    if (sure > reach_ || (best && sure > 0.0 && best_d2 < sure * sure)) break;
  }
  if (!best) return std::nullopt;
  return Nearest{best->segment, Vec2(best->ax + best_t * best->dx, best->ay + best_t * best->dy),
                 std::sqrt(best_d2)};
}

namespace
{
struct Accumulated
{
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  double score = 0.0;
  std::size_t inliers = 0, paired = 0;
};

// Linearises every point's residual at `pose`; the residual of a point is its distance to the nearest
// point c of its segment along u = (q - c) / |q - c| (the segment's normal inside it, the direction
// from an end point beyond it), with c held fixed.
Accumulated accumulate(const LocalizationSegmentIndex& index, const std::vector<Vec2>& points,
                       const Pose2& pose, const SegmentMatchParams& params, const Vec2& sensor_offset)
{
  Accumulated acc;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Vec2 t(pose.x, pose.y);
  const Vec2 sensor = pose.apply(sensor_offset);
  const double inv_var = 1.0 / (params.point_sigma * params.point_sigma);
  const double k_score = -0.5 * inv_var;
  for (const auto& p : points)
  {
    const Vec2 rotated(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    const Vec2 q = rotated + t;
    const auto near = index.nearest(q, params.check_free_side ? &sensor : nullptr);
    if (!near || near->distance > params.max_distance) continue;
    const double d = near->distance;
    acc.score += std::exp(k_score * d * d);
    if (d <= params.inlier_distance) ++acc.inliers;
    ++acc.paired;
    Vec2 u;
    if (d > 1e-12)
      u = (q - near->closest) / d;
    else
    {
      const auto& seg = index.segments()[near->segment];
      const Vec2 dir = (seg.end - seg.start).normalized();
      u = Vec2(-dir.y(), dir.x());
    }
    const Eigen::Vector3d j(u.x(), u.y(), u.x() * -rotated.y() + u.y() * rotated.x());
    const double ratio = d / params.loss_scale;
    const double w = inv_var / (1.0 + ratio * ratio);
    acc.information += w * j * j.transpose();
    acc.gradient += w * j * d;
  }
  return acc;
}

void finish(SegmentMatch& m, const Accumulated& acc, std::size_t n, const SegmentMatchParams& params)
{
  const double far =
      std::exp(-0.5 * params.max_distance * params.max_distance / (params.point_sigma * params.point_sigma));
  m.score = n == 0 ? 0.0 : (acc.score + static_cast<double>(n - acc.paired) * far) / static_cast<double>(n);
  m.inliers = acc.inliers;
  m.inlier_share = n == 0 ? 0.0 : static_cast<double>(acc.inliers) / static_cast<double>(n);
  m.scan_information = acc.information;
  m.valid = acc.paired > 0;
}
}  // namespace

SegmentMatch evaluateOnSegments(const LocalizationSegmentIndex& index, const std::vector<Vec2>& points,
                                const Pose2& pose, const SegmentMatchParams& params,
                                const Vec2& sensor_offset)
{
  SegmentMatch m;
  m.pose = pose;
  finish(m, accumulate(index, points, pose, params, sensor_offset), points.size(), params);
  return m;
}

namespace
{
// Gauss-Newton iterations from `pose` with the points paired within `gate`; returns the last pose.
Pose2 solve(const LocalizationSegmentIndex& index, const std::vector<Vec2>& points, Pose2 pose,
            const std::optional<PosePrior>& prior, const SegmentMatchParams& params,
            const Vec2& sensor_offset, int& iterations)
{
  for (int it = 0; it < params.max_iterations; ++it)
  {
    const Accumulated acc = accumulate(index, points, pose, params, sensor_offset);
    Eigen::Matrix3d h = acc.information;
    Eigen::Vector3d g = acc.gradient;
    if (prior)
    {
      const Eigen::Vector3d e(pose.x - prior->mean.x, pose.y - prior->mean.y,
                              linemap::normalizeAngle(pose.theta - prior->mean.theta));
      h += prior->information;
      g += prior->information * e;
    }
    ++iterations;
    if (acc.paired == 0 && !prior) break;
    // A tiny damping keeps the step finite where neither the scan nor a prior constrains a direction.
    const Eigen::Vector3d step = -(h + 1e-9 * Eigen::Matrix3d::Identity()).ldlt().solve(g);
    if (!step.allFinite()) break;
    pose = {pose.x + step.x(), pose.y + step.y(), linemap::normalizeAngle(pose.theta + step.z())};
    if (std::hypot(step.x(), step.y()) < 1e-6 && std::fabs(step.z()) < 1e-7) break;
  }
  return pose;
}
}  // namespace

SegmentMatch matchToSegments(const LocalizationSegmentIndex& index, const std::vector<Vec2>& points,
                             const Pose2& initial, const std::optional<PosePrior>& prior,
                             const SegmentMatchParams& params, const Vec2& sensor_offset)
{
  SegmentMatch m;
  Pose2 pose = solve(index, points, initial, prior, params, sensor_offset, m.iterations);
  SegmentMatchParams near = params;
  near.max_distance = std::min(params.max_distance, params.refine_distance);
  pose = solve(index, points, pose, prior, near, sensor_offset, m.iterations);
  // Score and inliers over the wide gate, the covariance from the points the pose rests on.
  m.pose = pose;
  finish(m, accumulate(index, points, pose, params, sensor_offset), points.size(), params);
  const Accumulated acc = accumulate(index, points, pose, near, sensor_offset);
  m.scan_information = acc.information;
  Eigen::Matrix3d h = acc.information;
  if (prior) h += prior->information;
  Eigen::FullPivLU<Eigen::Matrix3d> lu(h);
  m.covariance = lu.isInvertible()
                     ? Eigen::Matrix3d(lu.inverse())
                     : Eigen::Matrix3d(Eigen::Matrix3d::Identity() * std::numeric_limits<double>::infinity());
  return m;
}

}  // namespace line_map_merging
