// Hough transform line extraction over a (radius, angle) accumulator.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "line_extraction/extractor.hpp"
#include "line_extraction/ransac.hpp"

namespace line_extraction
{
/// Votes every point into a radius_resolution x angle_resolution accumulator
/// over (signed radius, angle in [0, pi)); repeatedly takes the strongest cell,
/// its inliers within inlier_distance, TLS-refits them, splits them into
/// segments and removes their votes, while the strongest cell has at least
/// min_votes votes.
class HoughExtractor : public Extractor
{
 public:
  /// The strongest cell of one round, before the refit, in Hessian form (radius >= 0).
  struct Peak
  {
    double angle = 0.0;
    double radius = 0.0;
    int votes = 0;
  };

  explicit HoughExtractor(const linemap::ParamSet& params);
  const char* name() const override { return "hough"; }
  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override;

  /// Peaks of the last extractRange call, strongest first.
  const std::vector<Peak>& peaks() const { return peaks_; }
  double radiusResolution() const { return radius_resolution_; }
  double angleResolution() const { return angle_resolution_; }

 private:
  void vote(const Vec2& p, int delta);
  /// Sizes the accumulator for the radii of `range`'s points; returns its cells in use.
  std::size_t prepareAccumulator(const PreparedScan& scan, PointRange range);
  /// The strongest candidate cell and its votes (0 when none is left at min_votes).
  int strongestCell(int& best_votes);
  /// Records the cell's peak, emits the segments of its refitted line, withdraws their votes.
  void takeLine(const PreparedScan& scan, int cell, int votes, ExtractionResult& out);

  RunSettings runs_;
  double radius_resolution_;
  double angle_resolution_;
  double inlier_distance_;
  int min_votes_;
  int angle_bins_ = 0;
  std::vector<double> cos_, sin_;
  std::vector<int> bins_;
  // Accumulator [radius][angle] over the signed radius [-max_radius_, max_radius_] (one point
  // votes into neighbouring rows: cache friendly); all zero between calls. Held in calloc'd
  // memory: a larger one then needs neither a copy nor a clear, and its fresh pages are
  // only faulted in where votes land.
  struct FreeDeleter
  {
    void operator()(std::uint16_t* p) const { std::free(p); }
  };
  std::unique_ptr<std::uint16_t[], FreeDeleter> acc_;
  std::size_t acc_cells_ = 0;
  int radius_bins_ = 0;
  double max_radius_ = 0.0;
  std::vector<int> remaining_, inliers_, candidates_;
  std::vector<char> taken_;
  std::vector<Peak> peaks_;
};

}  // namespace line_extraction
