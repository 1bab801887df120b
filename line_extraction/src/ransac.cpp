// RANSAC line extraction: two-point hypotheses scored by inlier count.
#include "line_extraction/ransac.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "line_extraction/extractor_registry.hpp"

namespace line_extraction
{
RunSettings readRunSettings(const linemap::ParamSet& params, const std::string& name)
{
  RunSettings s;
  s.max_gap = params.getDouble(name + "/max_gap", s.max_gap);
  s.min_points = params.getInt(name + "/min_points", s.min_points);
  s.range_sigma = params.getDouble("range_sigma", s.range_sigma);
  if (!(s.max_gap > 0.0)) throw linemap::ParameterError("parameter '" + name + "/max_gap' must be > 0");
  if (s.min_points < 2) throw linemap::ParameterError("parameter '" + name + "/min_points' must be >= 2");
  if (!(s.range_sigma > 0.0)) throw linemap::ParameterError("parameter 'range_sigma' must be > 0");
  return s;
}

int emitInlierRuns(const PreparedScan& scan, const int* members, int count, const RunSettings& settings,
                   ExtractionResult& out)
{
  const double max_gap2 = settings.max_gap * settings.max_gap;
  int emitted = 0;
  int start = 0;
  for (int k = 1; k <= count; ++k)
  {
    // Neighbouring points may span the sensor model's gap; members with points between them
    // (not inliers) only max_gap.
    const bool cut =
        k == count || (scan.points[members[k]] - scan.points[members[k - 1]]).squaredNorm() >
                          (members[k] == members[k - 1] + 1 ? scan.maxGap2(members[k], max_gap2) : max_gap2);
    if (!cut) continue;
    if (k - start >= settings.min_points)
    {
      LineSums sums;
      for (int j = start; j < k; ++j) sums.add(scan.points[members[j]]);
      const LineFit fit = fitLine(sums, settings.range_sigma);
      if (fit.valid)
      {
        appendSegment(scan, fit, members + start, k - start, out);
        ++emitted;
      }
    }
    start = k;
  }
  return emitted;
}

void emitAssignedLines(const PreparedScan& scan, int begin, int n, const std::vector<int>& assignment,
                       std::size_t line_count, const RunSettings& settings, std::vector<int>& members,
                       ExtractionResult& out)
{
  const std::size_t first_segment = out.segments.size();
  for (std::size_t k = 0; k < line_count; ++k)
  {
    members.clear();
    for (int i = 0; i < n; ++i)
      if (assignment[i] == static_cast<int>(k)) members.push_back(begin + i);
    emitInlierRuns(scan, members.data(), static_cast<int>(members.size()), settings, out);
  }
  sortSegmentsByFirstPoint(out, first_segment);
}

void sortSegmentsByFirstPoint(ExtractionResult& out, std::size_t first)
{
  std::sort(out.segments.begin() + first, out.segments.end(),
            [&](const Segment& a, const Segment& b)
            { return out.point_indices[a.index_begin] < out.point_indices[b.index_begin]; });
}

RansacExtractor::RansacExtractor(const linemap::ParamSet& params)
    : runs_(readRunSettings(params, "ransac")),
      iterations_(params.getInt("ransac/iterations", 100)),
      inlier_distance_(params.getDouble("ransac/inlier_distance", 0.05)),
      min_inliers_(params.getInt("ransac/min_inliers", 8)),
      seed_(static_cast<std::uint32_t>(params.getInt("ransac/seed", 1)))
{
  if (iterations_ < 1) throw linemap::ParameterError("parameter 'ransac/iterations' must be >= 1");
  if (!(inlier_distance_ > 0.0))
    throw linemap::ParameterError("parameter 'ransac/inlier_distance' must be > 0");
  if (min_inliers_ < 2) throw linemap::ParameterError("parameter 'ransac/min_inliers' must be >= 2");
}

int RansacExtractor::bestSample(const PreparedScan& scan, Vec2& best_normal, double& best_offset)
{
  const int n = static_cast<int>(remaining_.size());
  int best_count = 0;
  for (int t = 0; t < iterations_; ++t)
  {
    const int a = randomBelow(rng_, n);
    int b = randomBelow(rng_, n - 1);
    if (b >= a) ++b;
    const Vec2& pa = scan.points[remaining_[a]];
    const Vec2 d = scan.points[remaining_[b]] - pa;
    const double len = d.norm();
    if (len < 1e-6) continue;
    const Vec2 normal(-d.y() / len, d.x() / len);
    const double offset = normal.dot(pa);
    int count = 0;
    for (int idx : remaining_)
      count += std::abs(normal.dot(scan.points[idx]) - offset) <= scan.tolerance(idx, inlier_distance_);
    if (count > best_count)
    {
      best_count = count;
      best_normal = normal;
      best_offset = offset;
    }
  }
  return best_count;
}

void RansacExtractor::extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out)
{
  rng_.seed(seed_);
  const std::size_t first_segment = out.segments.size();
  remaining_.clear();
  for (int i = range.begin; i < range.end; ++i) remaining_.push_back(i);
  const int min_inliers = std::max(min_inliers_, 2);

  while (static_cast<int>(remaining_.size()) >= min_inliers)
  {
    Vec2 best_normal = Vec2::Zero();
    double best_offset = 0.0;
    const int best_count = bestSample(scan, best_normal, best_offset);
    if (best_count < min_inliers) break;

    // TLS refit on the consensus set, then take the inliers of the refitted line.
    LineSums sums;
    for (int idx : remaining_)
      if (std::abs(best_normal.dot(scan.points[idx]) - best_offset) <= scan.tolerance(idx, inlier_distance_))
        sums.add(scan.points[idx]);
    const LineFit fit = fitLine(sums, runs_.range_sigma);
    if (fit.valid)
    {
      best_normal = Vec2(std::cos(fit.angle), std::sin(fit.angle));
      best_offset = fit.radius;
    }
    inliers_.clear();
    std::size_t kept = 0;
    for (int idx : remaining_)
    {
      if (std::abs(best_normal.dot(scan.points[idx]) - best_offset) <= scan.tolerance(idx, inlier_distance_))
        inliers_.push_back(idx);
      else
        remaining_[kept++] = idx;
    }
    if (inliers_.empty()) break;  // cannot happen with a valid refit; guards progress
    remaining_.resize(kept);
    emitInlierRuns(scan, inliers_.data(), static_cast<int>(inliers_.size()), runs_, out);
  }
  sortSegmentsByFirstPoint(out, first_segment);
}

namespace
{
const ExtractorRegistration kRegistration("ransac", 80, &makeExtractorOf<RansacExtractor>);
}  // namespace

}  // namespace line_extraction
