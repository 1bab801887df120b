// Seeded region growing (after Gao et al. 2018). A window of consecutive points is
// a seed when each point lies near the window's fitted line and near the point
// where its own beam meets that line; the seed then grows forwards and backwards
// while new points stay near the (refitted) line. Backward growth may run into the
// previous segment: the overlap is split where the distances to the two lines cross.
#include <algorithm>
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
class SeededRegionGrowing : public Extractor
{
 public:
  explicit SeededRegionGrowing(const linemap::ParamSet& ps)
      : seed_points_(intParamAtLeast(ps, "srg/seed_points", 6, 2)),
        line_distance_(positiveParam(ps, "srg/line_distance", 0.03)),
        predict_distance_(positiveParam(ps, "srg/predict_distance", 0.1)),
        min_points_(intParamAtLeast(ps, "srg/min_points", 10, 2)),
        min_length_(nonNegativeParam(ps, "srg/min_length", 0.2)),
        max_gap_(positiveParam(ps, "srg/max_gap", 0.3)),
        range_sigma_(rangeSigmaParam(ps))
  {
  }

  const char* name() const override { return "srg"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    segments_.clear();
    if (range.size() < seed_points_) return;
    prefix_.build(scan, range);
    const auto& pts = scan.points;
    int i = range.begin;
    while (i + seed_points_ <= range.end)
    {
      LineNormal line;
      int bad = seedFailure(scan, i, line);
      if (bad >= 0)
      {
        i = bad;
        continue;
      }
      const PointRange grown = grow(scan, range, i, line);
      segments_.push_back(grown);
      i = grown.end;
    }
    resolveOverlaps(scan, segments_, &prefix_);
    for (const PointRange& s : segments_)
    {
      if (s.size() < min_points_) continue;
      const LineFit fit = fitLine(prefix_.sums(s.begin, s.end), range_sigma_);
      if (!fit.valid) continue;
      // Length between the projections of the end points onto the line.
      const Vec2 u(-fit.normal.y(), fit.normal.x());
      if (std::abs((pts[s.end - 1] - pts[s.begin]).dot(u)) < min_length_) continue;
      appendSegment(scan, fit, s, out);
    }
  }

 private:
  /// The seed [i, i + seed_points) on `line`, grown forward then backward while the next point lies
  /// within line_distance of the line and no gap intervenes.
  PointRange grow(const PreparedScan& scan, PointRange range, int i, LineNormal& line) const
  {
    const auto& pts = scan.points;
    const double max_gap2 = max_gap_ * max_gap_;
    LineSums sums = prefix_.sums(i, i + seed_points_);
    int fitted = seed_points_;  // points in the last fit
    int end = i + seed_points_;
    // Forward growth. Refitting after every point is what the method asks for;
    // refitting once the segment has grown by half gives the same decisions on
    // real walls at a fraction of the cost (a line from n points moves little
    // when n/2 more points within line_distance of it are added).
    while (end < range.end && !scan.gapBefore(end, max_gap2) &&
           line.distance(pts[end]) <= scan.tolerance(end, line_distance_))
      absorb(sums, pts[end++], line, fitted);
    if (sums.n != fitted)
    {
      fitNormal(sums, line);
      fitted = static_cast<int>(sums.n);
    }
    // Backward growth.
    int begin = i;
    while (begin > range.begin && !scan.gapBefore(begin, max_gap2) &&
           line.distance(pts[begin - 1]) <= scan.tolerance(begin - 1, line_distance_))
      absorb(sums, pts[--begin], line, fitted);
    return {begin, end};
  }

  /// Adds `p`, refitting `line` once the points have grown by half since the last fit (`fitted`).
  static void absorb(LineSums& sums, const Vec2& p, LineNormal& line, int& fitted)
  {
    sums.add(p);
    if (2.0 * (sums.n - fitted) >= fitted)
    {
      fitNormal(sums, line);
      fitted = static_cast<int>(sums.n);
    }
  }

  /// -1 when [i, i + seed_points) is a seed (its line in `line`), otherwise the
  /// index at which the next seed should start.
  int seedFailure(const PreparedScan& scan, int i, LineNormal& line) const
  {
    const auto& pts = scan.points;
    const int end = i + seed_points_;
    const double max_gap2 = max_gap_ * max_gap_;
    // A gap inside the window: no seed can contain it.
    for (int k = i + 1; k < end; ++k)
      if (scan.gapBefore(k, max_gap2)) return k;
    // Cheap necessary condition first: points within line_distance of one line lie
    // within twice that of the chord of the window's ends (3x leaves a margin), so
    // most windows over corners and clutter are rejected without a fit. The window's
    // largest tolerance is that of its farthest point (the scale grows with range).
    const Vec2 a = pts[i], chord = pts[end - 1] - a;
    double window_distance = line_distance_;
    for (int k = i; k < end; ++k)
      window_distance = std::max(window_distance, scan.tolerance(k, line_distance_));
    const double limit2 = 9.0 * window_distance * window_distance * chord.squaredNorm();
    for (int k = i + 1; k < end - 1; ++k)
    {
      const Vec2 v = pts[k] - a;
      const double cross = chord.x() * v.y() - chord.y() * v.x();
      if (cross * cross > limit2) return i + 1;
    }
    if (!fitNormal(prefix_.sums(i, end), line)) return i + 1;
    for (int k = i; k < end; ++k)
    {
      const Vec2& p = pts[k];
      const double along_normal = p.x() * line.nx + p.y() * line.ny;  // range * cos(beam - normal)
      const double d = std::abs(along_normal - line.radius);
      if (d > scan.tolerance(k, line_distance_)) return i + 1;
      // The beam through p meets the line at range radius / cos(beam - normal), so
      // p is d / cos(beam - normal) from that predicted point; compared without division.
      if (along_normal <= 1e-6 * scan.ranges[k]) return i + 1;
      if (d * scan.ranges[k] > scan.tolerance(k, predict_distance_) * along_normal) return i + 1;
    }
    return -1;
  }

  int seed_points_;
  double line_distance_, predict_distance_;
  int min_points_;
  double min_length_, max_gap_, range_sigma_;
  std::vector<PointRange> segments_;
  PrefixSums prefix_;
};

const ExtractorRegistration registration("srg", 10, &makeExtractorOf<SeededRegionGrowing>);
}  // namespace

}  // namespace line_extraction
