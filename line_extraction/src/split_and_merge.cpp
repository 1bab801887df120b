// Split-and-merge with least-squares lines. A piece is split while its total-least-
// squares line leaves two adjacent points beyond the threshold on the same side
// (a single stray point never splits a wall); the split goes to the point of such
// a pair farthest from the chord of the piece, which is the corner of an L rather
// than one of its ends. Neighbouring pieces whose union passes the same test are
// then merged.
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
class SplitAndMerge : public Extractor
{
 public:
  explicit SplitAndMerge(const linemap::ParamSet& ps)
      : threshold_(positiveParam(ps, "split_merge/distance_threshold", 0.04)),
        min_points_(intParamAtLeast(ps, "split_merge/min_points", 5, 2)),
        max_gap_(positiveParam(ps, "split_merge/max_gap", 0.3)),
        range_sigma_(rangeSigmaParam(ps))
  {
  }

  const char* name() const override { return "split_merge"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    if (range.size() <= 0) return;
    prefix_.build(scan, range);
    pieces_.clear();
    split_parents_.clear();
    const double max_gap2 = max_gap_ * max_gap_;
    int start = range.begin;
    for (int i = range.begin + 1; i <= range.end; ++i)
    {
      if (i == range.end || scan.gapBefore(i, max_gap2))
      {
        split(scan, {start, i});
        start = i;
      }
    }
    // Merge: neighbours sharing a point or touching, whose union is still one line.
    merged_.clear();
    for (const PointRange& p : pieces_)
    {
      if (!merged_.empty())
      {
        PointRange& last = merged_.back();
        if (p.begin <= last.end && !wasSplit(last.begin, p.end) && findSplit(scan, {last.begin, p.end}) < 0)
        {
          last.end = p.end;
          continue;
        }
      }
      merged_.push_back(p);
    }
    resolveOverlaps(scan, merged_, &prefix_);
    for (PointRange p : merged_)
    {
      if (p.size() < min_points_) continue;  // trimming only shrinks
      trimEnds(scan, p);
      if (p.size() < min_points_) continue;
      appendInliers(scan, p, out);
    }
  }

 private:
  void split(const PreparedScan& scan, PointRange range)
  {
    stack_.clear();
    stack_.push_back(range);
    while (!stack_.empty())
    {
      const PointRange r = stack_.back();
      stack_.pop_back();
      const int k = findSplit(scan, r);
      if (k < 0)
      {
        pieces_.push_back(r);
        continue;
      }
      split_parents_.push_back(r);
      stack_.push_back({k, r.end});
      stack_.push_back({r.begin, k + 1});
    }
  }

  /// Drops end points farther than the threshold from the piece's line: a single
  /// stray point at an end (a corner's first point on the next wall) has no
  /// neighbour to form a pair with, so splitting never removes it.
  void trimEnds(const PreparedScan& scan, PointRange& p) const
  {
    LineNormal line;
    while (p.size() > 2 && fitNormal(prefix_.sums(p.begin, p.end), line))
    {
      const double first = line.distance(scan.points[p.begin]), last = line.distance(scan.points[p.end - 1]);
      const double first_limit = scan.tolerance(p.begin, threshold_),
                   last_limit = scan.tolerance(p.end - 1, threshold_);
      if (first <= first_limit && last <= last_limit) break;
      if (first / first_limit > last / last_limit)
        ++p.begin;
      else
        --p.end;
    }
  }

  /// Fits the piece without the lone points the pair rule let through (a single
  /// spike never splits, but it must not pull the line either).
  void appendInliers(const PreparedScan& scan, PointRange p, ExtractionResult& out)
  {
    LineNormal line;
    LineSums sums = prefix_.sums(p.begin, p.end);
    if (!fitNormal(sums, line)) return;
    members_.clear();
    for (int k = p.begin; k < p.end; ++k)
    {
      if (line.distance(scan.points[k]) <= scan.tolerance(k, threshold_))
        members_.push_back(k);
      else
        sums.remove(scan.points[k]);
    }
    if (static_cast<int>(members_.size()) < min_points_) return;
    const LineFit fit = fitLine(sums, range_sigma_);
    if (!fit.valid) return;
    if (static_cast<int>(members_.size()) == p.size())
      appendSegment(scan, fit, p, out);
    else
      appendSegment(scan, fit, members_.data(), static_cast<int>(members_.size()), out);
  }

  /// True when [begin, end) was itself split: two sibling pieces never merge back
  /// (findSplit is deterministic), so the union need not be tested again.
  bool wasSplit(int begin, int end) const
  {
    for (const PointRange& r : split_parents_)
      if (r.begin == begin && r.end == end) return true;
    return false;
  }

  /// The split point of r, or -1 when r is one line.
  int findSplit(const PreparedScan& scan, PointRange r) const
  {
    if (r.size() < 4) return -1;
    LineNormal line;
    if (!fitNormal(prefix_.sums(r.begin, r.end), line)) return -1;
    const auto& pts = scan.points;
    const Vec2 a = pts[r.begin], chord = pts[r.end - 1] - a;
    int best = -1;
    double best_chord = -1.0;
    // Distances in units of each point's tolerance.
    double prev = line.signedDistance(pts[r.begin]) / scan.tolerance(r.begin, threshold_);
    for (int k = r.begin + 1; k < r.end; ++k)
    {
      const double d = line.signedDistance(pts[k]) / scan.tolerance(k, threshold_);
      // Pair (k-1, k) beyond the threshold on the same side.
      if (std::abs(d) > 1.0 && std::abs(prev) > 1.0 && (d > 0.0) == (prev > 0.0))
      {
        for (int j = k - 1; j <= k; ++j)
        {
          if (j <= r.begin || j >= r.end - 1) continue;  // the ends cannot split
          const Vec2 v = pts[j] - a;
          const double c = std::abs(chord.x() * v.y() - chord.y() * v.x());
          if (c > best_chord)
          {
            best_chord = c;
            best = j;
          }
        }
      }
      prev = d;
    }
    return best;
  }

  double threshold_;
  int min_points_;
  double max_gap_, range_sigma_;
  PrefixSums prefix_;
  std::vector<PointRange> stack_, pieces_, merged_, split_parents_;
  std::vector<int> members_;
};

const ExtractorRegistration registration("split_merge", 20, &makeExtractorOf<SplitAndMerge>);
}  // namespace

}  // namespace line_extraction
