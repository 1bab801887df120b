// RANSAC line extraction, and the pieces the other consensus extractors
// (hough, em, wsac_ge) share with it: turning a line's inliers into segments
// and drawing random indices reproducibly.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "line_extraction/extractor.hpp"
#include "line_extraction/line_fit.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
/// How a consensus extractor turns the inliers of one line into segments.
struct RunSettings
{
  double max_gap = 0.25;      ///< [m] largest distance between consecutive points of one segment
  int min_points = 5;         ///< fewest points of one segment
  double range_sigma = 0.01;  ///< [m] point noise used for the segment covariance
};

/// Reads "<name>/max_gap", "<name>/min_points" and the pipeline's "range_sigma"; throws
/// linemap::ParameterError naming an impossible value.
RunSettings readRunSettings(const linemap::ParamSet& params, const std::string& name);

/// Splits `members` (point indices in scan order) where consecutive points are
/// more than max_gap apart, and appends every run of at least min_points as a
/// TLS-fitted segment. Returns the number of segments appended.
int emitInlierRuns(const PreparedScan& scan, const int* members, int count, const RunSettings& settings,
                   ExtractionResult& out);

/// Emits the inlier runs of each of `line_count` lines, point begin + i belonging to line
/// assignment[i] (-1: none) for i < n, and orders the new segments in scan order. `members` is
/// scratch space kept by the caller so that no call allocates once warmed up.
void emitAssignedLines(const PreparedScan& scan, int begin, int n, const std::vector<int>& assignment,
                       std::size_t line_count, const RunSettings& settings, std::vector<int>& members,
                       ExtractionResult& out);

/// Orders out.segments[first..] by their first point, i.e. in scan order (lines are
/// found strongest first; the collinear merge expects neighbours next to each other).
void sortSegmentsByFirstPoint(ExtractionResult& out, std::size_t first);

/// Uniform integer in [0, n), n >= 1; the same on every platform for a given engine state.
inline int randomBelow(std::mt19937& rng, int n)
{
  return static_cast<int>((static_cast<std::uint64_t>(rng()) * static_cast<std::uint64_t>(n)) >> 32);
}

/// Repeatedly: the best of `iterations` two-point hypotheses by inlier count,
/// TLS refit, inliers split into segments and removed; stops when the best
/// consensus has fewer than min_inliers points.
class RansacExtractor : public Extractor
{
 public:
  explicit RansacExtractor(const linemap::ParamSet& params);
  const char* name() const override { return "ransac"; }
  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override;

 private:
  /// Of iterations_ lines through two random remaining points, the one with the most remaining points
  /// within inlier_distance: its count, normal and offset (count 0 and the inputs kept if none).
  int bestSample(const PreparedScan& scan, Vec2& best_normal, double& best_offset);
  RunSettings runs_;
  int iterations_;
  double inlier_distance_;
  int min_inliers_;
  std::uint32_t seed_;
  std::mt19937 rng_;
  std::vector<int> remaining_, inliers_;
};

}  // namespace line_extraction
