#include "line_map_merging/slam/scan_matcher.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

#include "silent_solve.hpp"

namespace line_map_merging
{
namespace
{

/// The field at (r, c) as Ceres' interpolator gives it to a Jet: the derivatives chained to r's and c's.
double bicubic(const LikelihoodGrid& grid, double r, double c)
{
  return grid.interpolate(r, c);
}
template <typename JetT>
JetT bicubic(const LikelihoodGrid& grid, const JetT& r, const JetT& c)
{
  double dfdr, dfdc;
  JetT f;
  f.a = grid.interpolate(r.a, c.a, &dfdr, &dfdc);
  f.v = dfdr * r.v + dfdc * c.v;
  return f;
}

// One residual per point: 1 - field value, scaled so that all points together weigh 1.
struct FieldCost
{
  FieldCost(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points)
      : grid_(grid), points_(points), scale_(1.0 / std::sqrt(static_cast<double>(points.size())))
  {
  }
  template <typename T>
  bool operator()(const T* pose, T* residual) const
  {
    const T c = cos(pose[2]), s = sin(pose[2]);
    const double inv = 1.0 / grid_.resolution();
    for (std::size_t i = 0; i < points_.size(); ++i)
    {
      const auto& p = points_[i];
      const T x = c * p.x() - s * p.y() + pose[0];
      const T y = s * p.x() + c * p.y() + pose[1];
      const T value = bicubic(grid_, (y - grid_.origin().y()) * inv, (x - grid_.origin().x()) * inv);
      residual[i] = scale_ * (1.0 - value);
    }
    return true;
  }
  const LikelihoodGrid& grid_;
  const std::vector<linemap::Vec2>& points_;
  double scale_;
};

/// Mean interpolated field value of the points at `pose`.
double interpolatedScore(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                         const linemap::Pose2& pose)
{
  double sum = 0.0;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (const auto& p : points)
    sum += bicubic(grid, (s * p.x() + c * p.y() + pose.y - grid.origin().y()) / grid.resolution(),
                   (c * p.x() - s * p.y() + pose.x - grid.origin().x()) / grid.resolution());
  return sum / static_cast<double>(points.size());
}

/// How sharply the score falls off around `pose`, where it is `centre`: minus its Hessian over (x, y, theta)
/// by central differences (one cell, 0.01 rad), negative curvatures clipped to zero. The least-squares J^T J
/// would not do: at the peak of a field the points' gradients vanish, whatever the scan determines.
Eigen::Matrix3d scoreCurvature(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                               const linemap::Pose2& pose, double centre)
{
  const double h[3] = {grid.resolution(), grid.resolution(), 0.01};
  auto at = [&](int i, double di, int j, double dj)
  {
    double d[3] = {0.0, 0.0, 0.0};
    d[i] += di;
    d[j] += dj;
    return interpolatedScore(grid, points, linemap::Pose2(pose.x + d[0], pose.y + d[1], pose.theta + d[2]));
  };
  Eigen::Matrix3d hessian;
  for (int i = 0; i < 3; ++i)
  {
    hessian(i, i) = (at(i, h[i], i, 0.0) - 2.0 * centre + at(i, -h[i], i, 0.0)) / (h[i] * h[i]);
    for (int j = i + 1; j < 3; ++j)
      hessian(i, j) = hessian(j, i) =
          (at(i, h[i], j, h[j]) - at(i, h[i], j, -h[j]) - at(i, -h[i], j, h[j]) + at(i, -h[i], j, -h[j])) /
          (4.0 * h[i] * h[j]);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(-hessian);
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() *
         eigen.eigenvectors().transpose();
}

struct PriorCost
{
  PriorCost(const linemap::Pose2& prior, double wt, double wr) : prior_(prior), wt_(wt), wr_(wr) {}
  template <typename T>
  bool operator()(const T* pose, T* residual) const
  {
    residual[0] = wt_ * (pose[0] - prior_.x);
    residual[1] = wt_ * (pose[1] - prior_.y);
    T d = pose[2] - prior_.theta;
    const double two_pi = 2.0 * linemap::kPi;
    d = d - two_pi * ceres::floor((d + linemap::kPi) / two_pi);
    residual[2] = wr_ * d;
    return true;
  }
  linemap::Pose2 prior_;
  double wt_, wr_;
};
}  // namespace

double matchScore(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                  const linemap::Pose2& pose)
{
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points)
  {
    const linemap::Vec2 q = pose.apply(p);
    sum += grid.nearest(q.x(), q.y());
  }
  return sum / static_cast<double>(points.size());
}

double TranslationScores::bestAwayFrom(const linemap::Vec2& at, double distance) const
{
  double best_score = 0.0;
  const int side = 2 * reach + 1;
  for (int oy = -reach; oy <= reach; ++oy)
    for (int ox = -reach; ox <= reach; ++ox)
      if (std::hypot(centre.x() + ox * step - at.x(), centre.y() + oy * step - at.y()) >= distance)
        best_score = std::max(best_score, best[static_cast<std::size_t>((oy + reach) * side + ox + reach)]);
  return best_score;
}

std::optional<TranslationScores::Ridge> TranslationScores::ridgeThrough(const linemap::Vec2& at,
                                                                        double threshold) const
{
  std::vector<linemap::Vec2> offsets;
  const int side = 2 * reach + 1;
  for (int oy = -reach; oy <= reach; ++oy)
    for (int ox = -reach; ox <= reach; ++ox)
      if (best[static_cast<std::size_t>((oy + reach) * side + ox + reach)] >= threshold)
        offsets.push_back(centre + linemap::Vec2(ox * step, oy * step) - at);
  if (offsets.size() < 2) return std::nullopt;
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& o : offsets) scatter += o * o.transpose();
  Ridge ridge;
  ridge.direction = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvectors().col(1);
  ridge.from = ridge.to = 0.0;
  for (const auto& o : offsets)
  {
    const double along = o.dot(ridge.direction);
    ridge.from = std::min(ridge.from, along);
    ridge.to = std::max(ridge.to, along);
  }
  return ridge;
}

double TranslationScores::bestAcross(const linemap::Vec2& at, const linemap::Vec2& direction,
                                     double distance) const
{
  double best_score = 0.0;
  const int side = 2 * reach + 1;
  for (int oy = -reach; oy <= reach; ++oy)
    for (int ox = -reach; ox <= reach; ++ox)
    {
      const linemap::Vec2 o = centre + linemap::Vec2(ox * step, oy * step) - at;
      if (std::fabs(o.x() * direction.y() - o.y() * direction.x()) >= distance)
        best_score = std::max(best_score, best[static_cast<std::size_t>((oy + reach) * side + ox + reach)]);
    }
  return best_score;
}

linemap::Vec2 TranslationScores::borderDirection(const linemap::Vec2& at) const
{
  linemap::Vec2 out = linemap::Vec2::Zero();
  if (reach <= 0) return out;
  const double inner = (reach - 0.5) * step;
  const linemap::Vec2 offset = at - centre;
  for (int i = 0; i < 2; ++i)
    if (std::fabs(offset(i)) > inner) out(i) = offset(i) > 0.0 ? 1.0 : -1.0;
  return out.norm() > 0.0 ? linemap::Vec2(out.normalized()) : out;
}

namespace
{
int floorDiv(int a, int b)
{
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// translationSums for a window of kSide x kSide translations (0: any side). A point on the grid under every
/// shift, the common case, adds its cells row by row with a loop the compiler unrolls for the front end's
/// few-cell windows; one partly off the grid adds only its cells on it.
template <int kSide>
inline __attribute__((always_inline)) void sumShiftedCells(const LikelihoodGrid& grid, int step, int reach,
                                                           const std::vector<int>& ix,
                                                           const std::vector<int>& iy, double* sums)
{
  const int side = kSide > 0 ? kSide : 2 * reach + 1, w = grid.width(), h = grid.height();
  const double* cells = grid.cells().data();
  const std::ptrdiff_t row_step = static_cast<std::ptrdiff_t>(step) * w;
  for (std::size_t i = 0; i < ix.size(); ++i)
  {
    // The shifts o with 0 <= i + o * step < size.
    const auto first = [&](int at) { return std::max(-reach, -floorDiv(at, step)); };
    const auto last = [&](int at, int size) { return std::min(reach, floorDiv(size - 1 - at, step)); };
    const int ox0 = first(ix[i]), ox1 = last(ix[i], w), oy0 = first(iy[i]), oy1 = last(iy[i], h);
    if (kSide > 0 && ox0 == -reach && ox1 == reach && oy0 == -reach && oy1 == reach)
    {
      const double* row =
          cells + (iy[i] - reach * step) * static_cast<std::ptrdiff_t>(w) + ix[i] - reach * step;
      double* out = sums;
      for (int r = 0; r < kSide; ++r, row += row_step, out += kSide)
        for (int c = 0; c < kSide; ++c) out[c] += row[c * step];
      continue;
    }
    for (int oy = oy0; oy <= oy1; ++oy)
    {
      const double* row = cells + static_cast<std::size_t>(iy[i] + oy * step) * w;
      double* out = sums + static_cast<std::size_t>(oy + reach) * side + reach;
      for (int ox = ox0; ox <= ox1; ++ox) out[ox] += row[ix[i] + ox * step];
    }
  }
}

/// The summed field values of the points (cells ix, iy at the window's centre) under every translation of
/// the window, row-major (y outer), in `sums`: each point's cell shifted by whole cells, those off the grid
/// adding nothing. Point by point, each adding to every translation that keeps it on the grid (its rows and
/// columns clipped once, not tested per translation): every sum still adds its points in their order.
/// The front end's windows (5 and 13 translations a side, strided) have their own unrolled loops. Built for
/// AVX2 too where the processor has it: the additions are the same, four at a time.
__attribute__((target_clones("avx2", "default"))) void translationSums(const LikelihoodGrid& grid, int step,
                                                                       int reach, const std::vector<int>& ix,
                                                                       const std::vector<int>& iy,
                                                                       std::vector<double>& sums)
{
  const int side = 2 * reach + 1;
  sums.assign(static_cast<std::size_t>(side) * side, 0.0);
  if (step > 1 && side == 5)  // a step of one cell reads contiguous cells: the general loop vectorises them
    sumShiftedCells<5>(grid, step, reach, ix, iy, sums.data());
  else if (step > 1 && side == 13)
    sumShiftedCells<13>(grid, step, reach, ix, iy, sums.data());
  else
    sumShiftedCells<0>(grid, step, reach, ix, iy, sums.data());
}

/// The `keep` best matches by ranked score, best first; of equal scores the one offered first.
class BestMatches
{
 public:
  explicit BestMatches(std::size_t keep) : keep_(keep) {}

  /// Whether a match ranked at `score` would enter.
  bool admits(double score) const { return ranked_.size() < keep_ || score > ranked_.back().first; }

  void offer(double score, const MatchResult& match)
  {
    if (!admits(score)) return;
    const auto at = std::upper_bound(ranked_.begin(), ranked_.end(), score,
                                     [](double v, const auto& e) { return v > e.first; });
    ranked_.insert(at, {score, match});
    if (ranked_.size() > keep_) ranked_.pop_back();
  }

  std::vector<MatchResult> matches() const
  {
    std::vector<MatchResult> out;
    for (const auto& r : ranked_) out.push_back(r.second);
    return out;
  }

 private:
  std::size_t keep_;
  std::vector<std::pair<double, MatchResult>> ranked_;  // `keep` is small: a sorted vector is enough
};

/// The cell of every point rotated by `theta` about the window's centre and moved there.
void rotatedCells(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                  const linemap::Pose2& center, double theta, std::vector<int>& ix, std::vector<int>& iy)
{
  const double c = std::cos(theta), s = std::sin(theta), res = grid.resolution();
  ix.resize(points.size());
  iy.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    const auto& p = points[i];
    ix[i] = static_cast<int>(roundHalfAway((c * p.x() - s * p.y() + center.x - grid.origin().x()) / res));
    iy[i] = static_cast<int>(roundHalfAway((s * p.x() + c * p.y() + center.y - grid.origin().y()) / res));
  }
}
}  // namespace

std::vector<MatchResult> correlativeSearch(const LikelihoodGrid& grid,
                                           const std::vector<linemap::Vec2>& points,
                                           const linemap::Pose2& center, const SearchWindow& window,
                                           std::size_t keep, TranslationScores* spread)
{
  if (grid.empty() || points.empty() || keep == 0) return {};
  const double res = grid.resolution();
  const int step = std::max(1, static_cast<int>(std::lround(window.linear_step / res)));
  const int reach = static_cast<int>(std::floor(window.linear / (step * res) + 1e-9));
  const double astep = window.angular_step > 0.0 ? window.angular_step : 0.01;
  const int areach = static_cast<int>(std::floor(window.angular / astep + 1e-9));
  const double inv_n = 1.0 / static_cast<double>(points.size());
  const int side = 2 * reach + 1;
  if (spread) *spread = {center.translation(), step * res, reach, std::vector<double>(side * side, 0.0)};
  // A penalty factor is then at most 1: a score that cannot enter unpenalised is not penalised.
  const bool unit_or_less = window.translation_penalty >= 0.0 && window.rotation_penalty >= 0.0;
  std::vector<double> sums;
  std::vector<int> ix, iy;  // translations then shift whole cells
  BestMatches best(keep);
  for (int a = -areach; a <= areach; ++a)
  {
    const double da = a * astep, theta = center.theta + da;
    rotatedCells(grid, points, center, theta, ix, iy);
    translationSums(grid, step, reach, ix, iy, sums);
    for (int oy = -reach; oy <= reach; ++oy)
      for (int ox = -reach; ox <= reach; ++ox)
      {
        const std::size_t at_translation = static_cast<std::size_t>((oy + reach) * side + ox + reach);
        const double score = sums[at_translation] * inv_n;
        if (spread) spread->best[at_translation] = std::max(spread->best[at_translation], score);
        if (unit_or_less && !best.admits(score)) continue;
        const double tx = ox * step * res, ty = oy * step * res;
        const double ranked =
            score *
            std::exp(-(window.translation_penalty * (tx * tx + ty * ty) + window.rotation_penalty * da * da));
        if (!best.admits(ranked)) continue;
        MatchResult m;
        m.pose = {center.x + tx, center.y + ty, linemap::normalizeAngle(theta)};
        m.score = score;
        best.offer(ranked, m);
      }
  }
  return best.matches();
}

MatchResult refineMatch(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                        const linemap::Pose2& initial, const linemap::Pose2& prior,
                        const RefinementParams& params)
{
  MatchResult result{initial, 0.0};
  if (grid.empty() || points.empty()) return result;
  double pose[3] = {initial.x, initial.y, initial.theta};
  ceres::Problem problem;
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FieldCost, ceres::DYNAMIC, 3>(
                               new FieldCost(grid, points), static_cast<int>(points.size())),
                           nullptr, pose);
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(
                               new PriorCost(prior, params.translation_weight, params.rotation_weight)),
                           nullptr, pose);
  solveSilently(problem, ceres::DENSE_QR, params.max_iterations);
  result.pose = {pose[0], pose[1], linemap::normalizeAngle(pose[2])};
  result.score = interpolatedScore(grid, points, result.pose);
  result.curvature = scoreCurvature(grid, points, result.pose, result.score);
  return result;
}

linemap::Pose2 heldToEstimate(const linemap::Pose2& match, const linemap::Pose2& prior,
                              const TranslationShape& shape)
{
  if (!shape.degenerate) return match;
  const linemap::Vec2 t = prior.translation() + shape.weights * (match.translation() - prior.translation());
  return {t.x(), t.y(), match.theta};
}

TranslationShape translationShape(const Eigen::Matrix3d& curvature, double isotropic_ratio, double floor)
{
  TranslationShape shape;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(curvature.topLeftCorner<2, 2>());
  const Eigen::Vector2d values = eigen.eigenvalues();                 // ascending
  if (!(values(1) > 0.0) || !std::isfinite(values(1))) return shape;  // nothing known: no shaping
  shape.ratio = std::max(0.0, values(0)) / values(1);
  Eigen::Vector2d weights;
  for (int i = 0; i < 2; ++i)
  {
    const double relative = std::max(0.0, values(i)) / values(1);
    weights(i) = relative >= isotropic_ratio ? 1.0 : std::max(floor, relative / isotropic_ratio);
  }
  shape.degenerate = weights(0) < 1.0;
  shape.weights = eigen.eigenvectors() * weights.asDiagonal() * eigen.eigenvectors().transpose();
  return shape;
}

}  // namespace line_map_merging

namespace line_map_merging
{
double matchLeverArm(const Eigen::Matrix3d& curvature)
{
  const double strongest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(curvature.topLeftCorner<2, 2>()).eigenvalues()(1);
  if (!(strongest > 0.0) || !(curvature(2, 2) > 0.0)) return 0.0;
  return std::sqrt(curvature(2, 2) / strongest);
}
}  // namespace line_map_merging
