#include "line_map_merging/localization/localization_global_search.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace line_map_merging
{
using linemap::Pose2;
using linemap::Vec2;

std::vector<Vec2> sampleSegments(const std::vector<linemap::Segment2>& segments, double spacing)
{
  std::vector<Vec2> points;
  for (const auto& s : segments)
  {
    if (!s.start.allFinite() || !s.end.allFinite()) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(s.length() / spacing)));
    for (int i = 0; i <= n; ++i) points.push_back(s.start + (s.end - s.start) * (static_cast<double>(i) / n));
  }
  return points;
}

LocalizationGlobalSearch::LocalizationGlobalSearch(const std::vector<linemap::Segment2>& segments,
                                                   const GlobalSearchParams& params)
    : params_(params)
{
  const auto points = sampleSegments(segments, params.sample_spacing);
  if (points.empty()) return;
  coarse_ = LikelihoodGrid(points, params.coarse_resolution, params.coarse_sigma, 1.0);
  fine_ = LikelihoodGrid(points, params.fine_resolution, params.fine_sigma, 1.0);
}

namespace
{
/// The coarse stage: the mean field value of `points` at every cell centre x every heading, one table
/// of width x height a heading.
std::vector<float> coarseScores(const LikelihoodGrid& grid, const std::vector<Vec2>& points, int headings,
                                double astep)
{
  const int w = grid.width(), h = grid.height();
  const double res = grid.resolution();
  const double* cells = grid.cells().data();
  std::vector<float> scores(static_cast<std::size_t>(headings) * w * h, 0.0f);
  std::vector<int> dx(points.size()), dy(points.size());
  const float inv_n = 1.0f / static_cast<float>(points.size());
  for (int a = 0; a < headings; ++a)
  {
    const double c = std::cos(a * astep), s = std::sin(a * astep);
    for (std::size_t i = 0; i < points.size(); ++i)
    {
      dx[i] = static_cast<int>(std::lround((c * points[i].x() - s * points[i].y()) / res));
      dy[i] = static_cast<int>(std::lround((s * points[i].x() + c * points[i].y()) / res));
    }
    float* table = &scores[static_cast<std::size_t>(a) * w * h];
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
      {
        double sum = 0.0;
        for (std::size_t i = 0; i < points.size(); ++i)
        {
          const int px = x + dx[i], py = y + dy[i];
          if (px >= 0 && py >= 0 && px < w && py < h) sum += cells[static_cast<std::size_t>(py) * w + px];
        }
        table[static_cast<std::size_t>(y) * w + x] = static_cast<float>(sum) * inv_n;
      }
  }
  return scores;
}

/// The best entries of `scores`, then greedy suppression of poses near a better one.
std::vector<Pose2> separatedBest(const std::vector<float>& scores, const LikelihoodGrid& grid, double astep,
                                 const GlobalSearchParams& params)
{
  const int w = grid.width(), h = grid.height();
  const double res = grid.resolution();
  const std::size_t pool = std::min(scores.size(), params.candidates * 1000);
  std::vector<std::size_t> order(scores.size());
  std::iota(order.begin(), order.end(), 0);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(pool), order.end(),
                    [&](std::size_t l, std::size_t r) { return scores[l] > scores[r]; });
  std::vector<Pose2> coarse;
  for (std::size_t k = 0; k < pool && coarse.size() < params.candidates; ++k)
  {
    const std::size_t e = order[k];
    const int a = static_cast<int>(e / (static_cast<std::size_t>(w) * h));
    const std::size_t cell = e % (static_cast<std::size_t>(w) * h);
    const Pose2 p(grid.origin().x() + static_cast<double>(cell % w) * res,
                  grid.origin().y() + static_cast<double>(cell / w) * res,
                  linemap::normalizeAngle(a * astep));
    const bool near =
        std::any_of(coarse.begin(), coarse.end(),
                    [&](const Pose2& q)
                    {
                      return std::hypot(p.x - q.x, p.y - q.y) < params.separation &&
                             std::fabs(linemap::normalizeAngle(p.theta - q.theta)) < params.separation_angle;
                    });
    if (!near) coarse.push_back(p);
  }
  return coarse;
}
}  // namespace

std::vector<MatchResult> LocalizationGlobalSearch::search(const std::vector<Vec2>& all_points) const
{
  std::vector<MatchResult> out;
  if (coarse_.empty() || all_points.empty()) return out;
  std::vector<Vec2> points;
  const std::size_t n = all_points.size(), m = std::min(n, std::max<std::size_t>(params_.max_points, 1));
  for (std::size_t i = 0; i < m; ++i) points.push_back(all_points[i * n / m]);

  const int headings =
      std::max(1, static_cast<int>(std::round(2.0 * linemap::kPi / params_.coarse_angular_step)));
  const double astep = 2.0 * linemap::kPi / headings;
  const std::vector<Pose2> coarse =
      separatedBest(coarseScores(coarse_, points, headings, astep), coarse_, astep, params_);
  // Fine stage around each.
  SearchWindow window{coarse_.resolution(),      astep, params_.fine_resolution,
                      params_.fine_angular_step, 0.0,   0.0};
  for (const auto& p : coarse)
  {
    const auto found = correlativeSearch(fine_, all_points, p, window, 1);
    if (!found.empty()) out.push_back(found.front());
  }
  std::sort(out.begin(), out.end(),
            [](const MatchResult& l, const MatchResult& r) { return l.score > r.score; });
  return out;
}

}  // namespace line_map_merging
