// Merging of neighbouring segments that describe the same line.
#pragma once

#include <limits>
#include <vector>

#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"
#include "line_extraction/types.hpp"

namespace line_extraction
{
struct CollinearMergeParams
{
  double gate = 2.77;         ///< chi-square gate on the (radius, angle) Mahalanobis distance (2 dof, 75 %)
  double range_sigma = 0.01;  ///< point noise for the refit covariance [m]
  /// Largest distance between the facing endpoints of two merged segments [m]; where those are
  /// neighbouring beams, at least the scan's gap (PreparedScan::maxGap2).
  double max_gap = std::numeric_limits<double>::infinity();
};

/// The merge an algorithm runs inside its own steps: default gate and gap, the pipeline's range_sigma.
inline CollinearMergeParams algorithmMergeParams(const linemap::ParamSet& ps)
{
  CollinearMergeParams p;
  p.range_sigma = rangeSigmaParam(ps);
  return p;
}

/// Squared Mahalanobis distance between the lines of a and b with covariance
/// a.covariance + b.covariance; the (radius, angle) and (-radius, angle + pi)
/// forms of b are both tried so that lines through the origin compare correctly.
double lineMahalanobis(const Segment& a, const Segment& b);

class CollinearMerger
{
 public:
  explicit CollinearMerger(const CollinearMergeParams& params = CollinearMergeParams()) : params_(params) {}

  /// Appends to `out` the segments of `in` (in order) with consecutive collinear
  /// ones merged and refitted from the union of their points. With `wrap` (a full
  /// 360 degree scan) the last segment may also merge into the first.
  void merge(const PreparedScan& scan, const ExtractionResult& in, ExtractionResult& out, bool wrap);

  const CollinearMergeParams& params() const { return params_; }

 private:
  /// a_last, b_first: a's last and b's first member point.
  bool mergeable(const PreparedScan& scan, int a_last, int b_first, const Segment& a, const Segment& b) const;
  void absorb(const PreparedScan& scan, const ExtractionResult& in, const Segment& seg,
              ExtractionResult& out);
  void refit(const PreparedScan& scan, ExtractionResult& out);
  void track(const PreparedScan& scan, const ExtractionResult& out);
  void untrack(const ExtractionResult& out);

  CollinearMergeParams params_;
  LineSums sums_;                      // points of the segment being grown (out.segments.back())
  std::vector<unsigned char> member_;  // marks its points, for the union
  bool tracked_ = false;               // sums_ and member_ describe out.segments.back()
};

}  // namespace line_extraction
