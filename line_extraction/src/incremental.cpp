// Incremental line tracking: a line grows from a seed by blocks of `step` points
// while the refitted line keeps the new points, and the segment's first point,
// within the threshold; after the first failing block it continues one point at a
// time, and the first failing point ends the segment.
#include <cmath>
#include <memory>
#include <vector>

#include "line_extraction/extractor_registry.hpp"
#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
namespace
{
class Incremental : public Extractor
{
 public:
  explicit Incremental(const linemap::ParamSet& ps)
      : threshold_(positiveParam(ps, "incremental/distance_threshold", 0.04)),
        step_(intParamAtLeast(ps, "incremental/step", 5, 1)),
        seed_points_(intParamAtLeast(ps, "incremental/seed_points", 5, 2)),
        min_points_(intParamAtLeast(ps, "incremental/min_points", 5, 2)),
        max_gap_(positiveParam(ps, "incremental/max_gap", 0.3)),
        range_sigma_(rangeSigmaParam(ps))
  {
  }

  const char* name() const override { return "incremental"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    segments_.clear();
    if (range.size() <= 0) return;
    prefix_.build(scan, range);
    const double max_gap2 = max_gap_ * max_gap_;
    int i = range.begin;
    while (i + seed_points_ <= range.end)
    {
      // Seed: no gap and every point near its line.
      int gap = -1;
      for (int k = i + 1; k < i + seed_points_ && gap < 0; ++k)
        if (scan.gapBefore(k, max_gap2)) gap = k;
      if (gap >= 0)
      {
        i = gap;
        continue;
      }
      LineSums sums = prefix_.sums(i, i + seed_points_);
      LineNormal line;
      if (!fitNormal(sums, line) || !allNear(scan, line, i, i + seed_points_))
      {
        ++i;
        continue;
      }
      const int end = grow(scan, range, i, sums);
      segments_.push_back({i, end});
      i = end;
    }
    resolveOverlaps(scan, segments_, &prefix_);
    for (const PointRange& s : segments_)
    {
      if (s.size() < min_points_) continue;
      const LineFit fit = fitLine(prefix_.sums(s.begin, s.end), range_sigma_);
      if (fit.valid) appendSegment(scan, fit, s, out);
    }
  }

 private:
  /// The end of the segment seeded at i (its sums given), grown by blocks of `step` points
  /// while the refitted line stays near every point and the seed's first one; single points once a
  /// block fails.
  int grow(const PreparedScan& scan, PointRange range, int i, LineSums sums) const
  {
    const auto& pts = scan.points;
    const double max_gap2 = max_gap_ * max_gap_;
    int end = i + seed_points_;
    int step = step_;
    while (end < range.end)
    {
      // The block stops before the first gap.
      int block_end = std::min(end + step, range.end);
      for (int k = end; k < block_end; ++k)
        if (scan.gapBefore(k, max_gap2)) block_end = k;
      if (block_end == end) break;
      LineSums grown = sums;
      for (int k = end; k < block_end; ++k) grown.add(pts[k]);
      LineNormal candidate;
      if (fitNormal(grown, candidate) && allNear(scan, candidate, end, block_end) &&
          candidate.distance(pts[i]) <= scan.tolerance(i, threshold_))
      {
        sums = grown;
        end = block_end;
      }
      else if (step > 1)
      {
        step = 1;
      }
      else
      {
        break;
      }
    }
    return end;
  }

  bool allNear(const PreparedScan& scan, const LineNormal& line, int begin, int end) const
  {
    for (int k = begin; k < end; ++k)
      if (line.distance(scan.points[k]) > scan.tolerance(k, threshold_)) return false;
    return true;
  }

  double threshold_;
  int step_, seed_points_, min_points_;
  double max_gap_, range_sigma_;
  std::vector<PointRange> segments_;
  PrefixSums prefix_;
};

const ExtractorRegistration registration("incremental", 50, &makeExtractorOf<Incremental>);
}  // namespace

}  // namespace line_extraction
