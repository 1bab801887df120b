// Iterative end-point fit: a piece is accepted when no point is farther than the
// threshold from the chord joining its end points; otherwise it is split at the
// farthest point, which is where a corner or a jump lies.
#include "line_extraction/iepf.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "line_extraction/extractor_registry.hpp"
#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
void IepfSplitter::split(const PreparedScan& scan, PointRange range, double threshold, double max_gap,
                         std::vector<PointRange>& pieces)
{
  if (range.size() <= 0) return;
  const double max_gap2 = max_gap * max_gap;
  int start = range.begin;
  for (int i = range.begin + 1; i <= range.end; ++i)
  {
    if (i == range.end || scan.gapBefore(i, max_gap2))
    {
      splitGapFree(scan, {start, i}, threshold, pieces);
      start = i;
    }
  }
}

void IepfSplitter::splitGapFree(const PreparedScan& scan, PointRange range, double threshold,
                                std::vector<PointRange>& pieces)
{
  const auto& pts = scan.points;
  stack_.clear();
  stack_.push_back(range);
  while (!stack_.empty())
  {
    const PointRange r = stack_.back();
    stack_.pop_back();
    if (r.size() <= 2)
    {
      pieces.push_back(r);
      continue;
    }
    const Vec2 a = pts[r.begin], d = pts[r.end - 1] - a;
    const double len2 = d.squaredNorm();
    // The split goes to the farthest point (a corner); the piece is accepted when every point
    // lies within its own tolerance (threshold times its noise scale).
    int farthest = -1;
    double best = 0.0, worst_ratio = 0.0;
    for (int k = r.begin + 1; k < r.end - 1; ++k)
    {
      const Vec2 v = pts[k] - a;
      // Squared distance to the chord times |d|^2 (the point itself when the chord is degenerate).
      const double cross = d.x() * v.y() - d.y() * v.x();
      const double dist2 = len2 > 0.0 ? cross * cross : v.squaredNorm();
      const double scale = scan.tolerance(k, 1.0);
      worst_ratio = std::max(worst_ratio, dist2 / (scale * scale));
      if (dist2 > best)
      {
        best = dist2;
        farthest = k;
      }
    }
    const double limit = threshold * threshold * (len2 > 0.0 ? len2 : 1.0);
    if (farthest < 0 || worst_ratio <= limit)
    {
      pieces.push_back(r);
      continue;
    }
    // Right half pushed first so the left half is finished first (scan order).
    stack_.push_back({farthest, r.end});
    stack_.push_back({r.begin, farthest + 1});
  }
}

namespace
{
class Iepf : public Extractor
{
 public:
  explicit Iepf(const linemap::ParamSet& ps)
      : threshold_(positiveParam(ps, "iepf/distance_threshold", 0.04)),
        min_points_(intParamAtLeast(ps, "iepf/min_points", 5, 2)),
        max_gap_(positiveParam(ps, "iepf/max_gap", 0.3)),
        range_sigma_(rangeSigmaParam(ps))
  {
  }

  const char* name() const override { return "iepf"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    pieces_.clear();
    if (range.size() <= 0) return;
    prefix_.build(scan, range);
    splitter_.split(scan, range, threshold_, max_gap_, pieces_);
    resolveOverlaps(scan, pieces_, &prefix_);
    for (const PointRange& p : pieces_)
    {
      if (p.size() < min_points_) continue;
      const LineFit fit = fitLine(prefix_.sums(p.begin, p.end), range_sigma_);
      if (fit.valid) appendSegment(scan, fit, p, out);
    }
  }

 private:
  double threshold_;
  int min_points_;
  double max_gap_, range_sigma_;
  IepfSplitter splitter_;
  std::vector<PointRange> pieces_;
  PrefixSums prefix_;
};

const ExtractorRegistration registration("iepf", 30, &makeExtractorOf<Iepf>);
}  // namespace

}  // namespace line_extraction
