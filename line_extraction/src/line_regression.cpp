// Line regression (sliding windows): a line is fitted to every window of Nf
// consecutive points; the fidelity between neighbouring windows is the Mahalanobis
// distance of their (radius, angle) with the summed covariances. Runs of windows
// whose neighbours agree are clustered into one line (its points are the union of
// the windows), clusters that drifted are split at their farthest point, shared
// points go to the nearer line, and collinear neighbours are merged.
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "line_extraction/collinear_merge.hpp"
#include "line_extraction/extractor_registry.hpp"
#include "line_extraction/iepf.hpp"
#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
namespace
{
class LineRegression : public Extractor
{
 public:
  explicit LineRegression(const linemap::ParamSet& ps)
      : window_(intParamAtLeast(ps, "line_regression/window", 7, 3)),
        threshold_(positiveParam(ps, "line_regression/fidelity_threshold", 2.77)),
        min_windows_(intParamAtLeast(ps, "line_regression/min_windows", 2, 1)),
        max_gap_(positiveParam(ps, "line_regression/max_gap", 0.3)),
        range_sigma_(rangeSigmaParam(ps)),
        max_distance_(positiveParam(ps, "line_regression/max_distance", 0.05)),
        residual_limit_(positiveParam(ps, "line_regression/residual_gate", 15.09) * range_sigma_ *
                        range_sigma_),
        merger_(algorithmMergeParams(ps))
  {
  }

  const char* name() const override { return "line_regression"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    const int count = range.size() - window_ + 1;
    if (count < 1) return;
    prefix_.build(scan, range);
    // Window lines; a window spanning a gap is invalid and breaks every run.
    windows_.resize(count);
    valid_.resize(count);
    const double max_gap2 = max_gap_ * max_gap_;
    int last_gap = -1;  // largest k with a gap between points k-1 and k
    for (int k = range.begin + 1; k < range.begin + window_; ++k)
      if (scan.gapBefore(k, max_gap2)) last_gap = k;
    for (int w = 0; w < count; ++w)
    {
      const int b = range.begin + w, e = b + window_;
      if (w > 0 && scan.gapBefore(e - 1, max_gap2)) last_gap = e - 1;
      const LineFit fit = fitLine(prefix_.sums(b, e), range_sigma_);
      // A window whose residuals are beyond the noise (a spike, a corner) is no
      // line: without this test the windows sharing one spike agree with each
      // other and carry it into a segment.
      const double scale = membersNoiseScale(scan, b, e - 1), scale2 = scale * scale;
      valid_[w] = fit.valid && last_gap <= b && fit.sum_squared_residuals <= residual_limit_ * scale2;
      Segment& s = windows_[w];
      s.angle = fit.angle;
      s.radius = fit.radius;
      s.covariance = fit.covariance * scale2;
    }
    // Agglomerative clustering of consecutive windows.
    clusters_.clear();
    int run_start = -1;
    for (int w = 0; w <= count; ++w)
    {
      const bool joins = w < count && valid_[w] && run_start >= 0 &&
                         lineMahalanobis(windows_[w - 1], windows_[w]) < threshold_;
      if (joins) continue;
      if (run_start >= 0 && w - run_start >= min_windows_)
        clusters_.push_back({range.begin + run_start, range.begin + (w - 1) + window_});
      run_start = (w < count && valid_[w]) ? w : -1;
    }
    // Neighbouring windows agree along a gentle curve or a shallow corner too, so
    // a cluster can drift; each is split (end-point fit) where a point is farther
    // than max_distance from its chord.
    pieces_.clear();
    for (const PointRange& c : clusters_)
      splitter_.split(scan, c, max_distance_, std::numeric_limits<double>::infinity(), pieces_);
    resolveOverlaps(scan, pieces_, &prefix_);
    lines_.clear();
    for (const PointRange& c : pieces_)
    {
      if (c.size() < window_) continue;
      const LineFit fit = fitLine(prefix_.sums(c.begin, c.end), range_sigma_);
      if (fit.valid) appendSegment(scan, fit, c, lines_);
    }
    merger_.merge(scan, lines_, out, false);
  }

 private:
  int window_;
  double threshold_;
  int min_windows_;
  double max_gap_, range_sigma_;
  double max_distance_;    ///< of a point from its cluster's chord [m]
  double residual_limit_;  ///< largest sum of squared residuals of a window [m^2]
  CollinearMerger merger_;
  PrefixSums prefix_;
  std::vector<Segment> windows_;
  std::vector<unsigned char> valid_;
  std::vector<PointRange> clusters_, pieces_;
  IepfSplitter splitter_;
  ExtractionResult lines_;
};

const ExtractorRegistration registration("line_regression", 60, &makeExtractorOf<LineRegression>);
}  // namespace

}  // namespace line_extraction
