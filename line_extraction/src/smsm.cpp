// Split-merge-split-merge: adaptive breakpoint clustering (split), joining of
// clusters whose facing ends are close (merge), iterative end-point fit inside each
// cluster (split), and collinear merging of the resulting lines (merge).
#include <limits>
#include <memory>
#include <vector>

#include "line_extraction/breakpoint_clustering.hpp"
#include "line_extraction/collinear_merge.hpp"
#include "line_extraction/extractor_registry.hpp"
#include "line_extraction/iepf.hpp"
#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
namespace
{
class Smsm : public Extractor
{
 public:
  explicit Smsm(const linemap::ParamSet& ps)
      : threshold_(positiveParam(ps, "smsm/distance_threshold", 0.04)),
        join_distance_(nonNegativeParam(ps, "smsm/join_distance", 0.1)),
        min_points_(intParamAtLeast(ps, "smsm/min_points", 5, 2)),
        range_sigma_(rangeSigmaParam(ps)),
        merger_(algorithmMergeParams(ps))
  {
    breakpoint_.lambda = positiveParam(ps, "smsm/breakpoint_lambda", breakpoint_.lambda);
    if (breakpoint_.lambda >= linemap::kPi / 2)
      throw linemap::ParameterError("parameter 'smsm/breakpoint_lambda' must be < pi/2 rad");
    breakpoint_.sigma = range_sigma_;
    breakpoint_.min_points = 1;
  }

  const char* name() const override { return "smsm"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    clusters_.clear();
    if (range.size() <= 0) return;
    prefix_.build(scan, range);
    breakpointClusters(scan, range, breakpoint_, clusters_);
    // Join clusters that are contiguous in the scan and whose facing ends are close.
    joined_.clear();
    const double join2 = join_distance_ * join_distance_;
    for (const PointRange& c : clusters_)
    {
      if (!joined_.empty() && joined_.back().end == c.begin && !scan.gapBefore(c.begin, join2))
        joined_.back().end = c.end;
      else
        joined_.push_back(c);
    }
    pieces_.clear();
    for (const PointRange& c : joined_)
      // Breakpoints already separate the clusters: no gap limit inside one.
      splitter_.split(scan, c, threshold_, std::numeric_limits<double>::infinity(), pieces_);
    resolveOverlaps(scan, pieces_, &prefix_);
    lines_.clear();
    for (const PointRange& p : pieces_)
    {
      if (p.size() < min_points_) continue;
      const LineFit fit = fitLine(prefix_.sums(p.begin, p.end), range_sigma_);
      if (fit.valid) appendSegment(scan, fit, p, lines_);
    }
    merger_.merge(scan, lines_, out, false);
  }

 private:
  double threshold_, join_distance_;
  int min_points_;
  double range_sigma_;
  BreakpointParams breakpoint_;
  IepfSplitter splitter_;
  CollinearMerger merger_;
  std::vector<PointRange> clusters_, joined_, pieces_;
  PrefixSums prefix_;
  ExtractionResult lines_;
};

const ExtractorRegistration registration("smsm", 40, &makeExtractorOf<Smsm>);
}  // namespace

}  // namespace line_extraction
