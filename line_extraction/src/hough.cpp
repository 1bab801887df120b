// Hough transform line extraction.
#include "line_extraction/hough.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <new>

#include "line_extraction/extractor_registry.hpp"

namespace line_extraction
{
HoughExtractor::HoughExtractor(const linemap::ParamSet& params)
    : runs_(readRunSettings(params, "hough")),
      radius_resolution_(params.getDouble("hough/radius_resolution", 0.01)),
      angle_resolution_(params.getDouble("hough/angle_resolution", 0.4 * linemap::kPi / 180.0)),
      inlier_distance_(params.getDouble("hough/inlier_distance", 0.05)),
      min_votes_(params.getInt("hough/min_votes", 5))
{
  if (!(radius_resolution_ > 0.0))
    throw linemap::ParameterError("parameter 'hough/radius_resolution' must be > 0");
  if (!(angle_resolution_ > 0.0 && angle_resolution_ <= 0.5))
    throw linemap::ParameterError("parameter 'hough/angle_resolution' must be in (0, 0.5] rad");
  if (!(inlier_distance_ > 0.0))
    throw linemap::ParameterError("parameter 'hough/inlier_distance' must be > 0");
  if (min_votes_ < 2) throw linemap::ParameterError("parameter 'hough/min_votes' must be >= 2");
  // Whole bins over [0, pi): the resolution actually used is pi / bins.
  angle_bins_ = std::max(1, static_cast<int>(std::lround(linemap::kPi / angle_resolution_)));
  angle_resolution_ = linemap::kPi / angle_bins_;
  cos_.resize(angle_bins_);
  bins_.resize(angle_bins_);
  sin_.resize(angle_bins_);
  for (int a = 0; a < angle_bins_; ++a)
  {
    // Pre-scaled by 1 / radius_resolution so that a vote is two multiply-adds.
    cos_[a] = std::cos(a * angle_resolution_) / radius_resolution_;
    sin_[a] = std::sin(a * angle_resolution_) / radius_resolution_;
  }
}

void HoughExtractor::vote(const Vec2& p, int delta)
{
  // Locals only, so that the compiler neither reloads members nor fears aliasing.
  const int bins = angle_bins_, min_votes = min_votes_;
  const double x = p.x(), y = p.y(), offset = max_radius_ / radius_resolution_ + 0.5;  // + 0.5: nearest bin
  const double* __restrict c = cos_.data();
  const double* __restrict s = sin_.data();
  int* __restrict index = bins_.data();
  // Cell indices first (a loop the compiler vectorises), then the scattered increments.
  for (int a = 0; a < bins; ++a) index[a] = static_cast<int>(x * c[a] + y * s[a] + offset) * bins + a;
  std::uint16_t* acc = acc_.get();
  if (delta < 0)
  {
    for (int a = 0; a < bins; ++a) --acc[index[a]];
    return;
  }
  for (int a = 0; a < bins; ++a)
  {
    // Counts only fall after the voting, so the cells that ever reach min_votes are the only
    // possible peaks: remembering them spares a scan of the whole accumulator per line.
    if (++acc[index[a]] == min_votes) candidates_.push_back(index[a]);
  }
}

void HoughExtractor::extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out)
{
  peaks_.clear();
  if (range.size() < std::max(min_votes_, 2)) return;
  // Votes are 16 bit: a cell can hold every point of any laser scan (< 65536 beams).
  if (range.size() > std::numeric_limits<std::uint16_t>::max())
    range.end = range.begin + std::numeric_limits<std::uint16_t>::max();
  const std::size_t cells = prepareAccumulator(scan, range);

  const std::size_t first_segment = out.segments.size();
  remaining_.clear();
  candidates_.clear();
  for (int i = range.begin; i < range.end; ++i)
  {
    remaining_.push_back(i);
    vote(scan.points[i], +1);
  }
  while (static_cast<int>(remaining_.size()) >= min_votes_)
  {
    int best_votes = 0;
    const int best_cell = strongestCell(best_votes);
    if (best_votes < min_votes_) break;
    takeLine(scan, best_cell, best_votes, out);
  }
  // Leave the accumulator all zero for the next call: withdraw the remaining votes, or
  // clear the whole span when that is cheaper (a sequential clear costs a small fraction of a
  // withdrawn vote per cell: the factor below).
  if (remaining_.size() * static_cast<std::size_t>(angle_bins_) * 16 < cells)
    for (int idx : remaining_) vote(scan.points[idx], -1);
  else
    std::fill_n(acc_.get(), cells, std::uint16_t{0});
  sortSegmentsByFirstPoint(out, first_segment);
}

std::size_t HoughExtractor::prepareAccumulator(const PreparedScan& scan, PointRange range)
{
  // The accumulator only spans the radii these points can have.
  double max_norm = 0.0;
  for (int i = range.begin; i < range.end; ++i) max_norm = std::max(max_norm, scan.points[i].norm());
  const int half = static_cast<int>(std::ceil(max_norm / radius_resolution_)) + 1;
  max_radius_ = half * radius_resolution_;
  radius_bins_ = 2 * half + 2;
  const std::size_t cells = static_cast<std::size_t>(angle_bins_) * radius_bins_;
  if (acc_cells_ < cells)
  {
    // Free the old block first (lower peak), and stay consistent if calloc fails.
    acc_.reset();
    acc_cells_ = 0;
    acc_.reset(static_cast<std::uint16_t*>(std::calloc(cells, sizeof(std::uint16_t))));
    if (!acc_) throw std::bad_alloc();
    acc_cells_ = cells;
  }
  return cells;
}

int HoughExtractor::strongestCell(int& best_votes)
{
  // Strongest cell among the candidates; those fallen below min_votes are dropped for good.
  best_votes = 0;
  int best_cell = 0;
  std::size_t kept_candidates = 0;
  for (int c : candidates_)
  {
    const int v = acc_[c];
    if (v < min_votes_) continue;
    candidates_[kept_candidates++] = c;
    if (v > best_votes || (v == best_votes && c < best_cell))
    {
      best_votes = v;
      best_cell = c;
    }
  }
  candidates_.resize(kept_candidates);
  return best_cell;
}

void HoughExtractor::takeLine(const PreparedScan& scan, int cell, int votes, ExtractionResult& out)
{
  const double theta = (cell % angle_bins_) * angle_resolution_;
  const double rho = (cell / angle_bins_) * radius_resolution_ - max_radius_;
  Peak peak;
  peak.votes = votes;
  peak.radius = std::abs(rho);
  peak.angle = linemap::normalizeAngle(rho < 0.0 ? theta + linemap::kPi : theta);
  peaks_.push_back(peak);

  // Inliers of the cell's line, TLS refit, inliers of the refitted line.
  Vec2 normal(std::cos(theta), std::sin(theta));
  double offset_line = rho;
  LineSums sums;
  taken_.assign(remaining_.size(), 0);
  for (std::size_t k = 0; k < remaining_.size(); ++k)
  {
    const Vec2& p = scan.points[remaining_[k]];
    if (std::abs(normal.dot(p) - offset_line) <= scan.tolerance(remaining_[k], inlier_distance_))
    {
      sums.add(p);
      taken_[k] = 1;
    }
  }
  const LineFit fit = fitLine(sums, runs_.range_sigma);
  inliers_.clear();
  if (fit.valid)
  {
    normal = Vec2(std::cos(fit.angle), std::sin(fit.angle));
    offset_line = fit.radius;
    for (std::size_t k = 0; k < remaining_.size(); ++k)
    {
      if (std::abs(normal.dot(scan.points[remaining_[k]]) - offset_line) <=
          scan.tolerance(remaining_[k], inlier_distance_))
      {
        inliers_.push_back(remaining_[k]);
        taken_[k] = 1;
      }
    }
  }
  emitInlierRuns(scan, inliers_.data(), static_cast<int>(inliers_.size()), runs_, out);

  // Withdraw the votes of every point taken (the cell's own voters at least, so the loop progresses).
  std::size_t kept = 0;
  for (std::size_t k = 0; k < remaining_.size(); ++k)
  {
    if (taken_[k])
      vote(scan.points[remaining_[k]], -1);
    else
      remaining_[kept++] = remaining_[k];
  }
  remaining_.resize(kept);
}

namespace
{
const ExtractorRegistration kRegistration("hough", 70, &makeExtractorOf<HoughExtractor>);
}  // namespace

}  // namespace line_extraction
