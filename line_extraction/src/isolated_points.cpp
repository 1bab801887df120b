// Isolated-point removal with the adaptive breakpoint distance: a reading that
// jumps away from a surface and straight back (a spurious return, rain, a thin
// leg) would otherwise cut the surface in two for every extractor.
#include "line_extraction/isolated_points.hpp"

#include <cmath>

namespace line_extraction
{
namespace
{
/// The breakpoint test between two points of the scan, with the sine ratio
/// cached for the last angle step (steps come from beam numbers, so they repeat
/// bit for bit).
class SeparationTest
{
 public:
  SeparationTest(const PreparedScan& scan, const BreakpointParams& params)
      : increment_(scan.angle_increment), params_(params)
  {
  }

  bool operator()(const Vec2& pa, double ra, double aa, int ba, const Vec2& pb, double ab, int bb)
  {
    const double dphi = bb > ba ? (bb - ba) * increment_ : std::abs(ab - aa);
    if (dphi >= params_.lambda) return true;
    if (dphi != cached_dphi_)
    {
      cached_dphi_ = dphi;
      ratio_ = std::sin(dphi) / std::sin(params_.lambda - dphi);
    }
    const double limit = ra * ratio_ + 3.0 * params_.sigma;
    return (pb - pa).squaredNorm() > limit * limit;
  }

 private:
  double increment_;
  const BreakpointParams& params_;
  double cached_dphi_ = -1.0, ratio_ = 0.0;
};
}  // namespace

int removeIsolatedPoints(PreparedScan& scan, const BreakpointParams& params)
{
  const int n = static_cast<int>(scan.size());
  if (n < 3) return 0;
  SeparationTest neighbours(scan, params), skip_one(scan, params);
  auto& pts = scan.points;
  auto& rs = scan.ranges;
  auto& as = scan.angles;
  auto& bs = scan.beam_index;
  // Compaction in place: slots [0, w) hold the kept points, so the kept point
  // before i is at w - 1, while point i and i + 1 are still in their own slots.
  int w = 1;  // point 0 is kept
  bool cut_before = neighbours(pts[0], rs[0], as[0], bs[0], pts[1], as[1], bs[1]);
  for (int i = 1; i < n; ++i)
  {
    bool keep = true, cut_after = false;
    if (i + 1 < n)
    {
      cut_after = neighbours(pts[i], rs[i], as[i], bs[i], pts[i + 1], as[i + 1], bs[i + 1]);
      if (cut_before && cut_after &&
          !skip_one(pts[w - 1], rs[w - 1], as[w - 1], bs[w - 1], pts[i + 1], as[i + 1], bs[i + 1]))
        keep = false;
    }
    if (keep)
    {
      if (w != i)
      {
        pts[w] = pts[i];
        rs[w] = rs[i];
        as[w] = as[i];
        bs[w] = bs[i];
      }
      ++w;
      cut_before = cut_after;
    }
    else
    {
      cut_before = false;  // the removed point's neighbours are adjacent now, and close
    }
  }
  const int removed = n - w;
  pts.resize(w);
  rs.resize(w);
  as.resize(w);
  bs.resize(w);
  return removed;
}

}  // namespace line_extraction
