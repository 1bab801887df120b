// Adaptive breakpoint detector. For consecutive points p(i-1), p(i) at beam angle
// difference dphi, a surface inclined down to lambda against the beam puts p(i) at
// most r(i-1) sin(dphi) / sin(lambda - dphi) away (law of sines in the triangle of
// the two beams and the surface); 3 sigma adds room for range noise.
#include "line_extraction/breakpoint_clustering.hpp"

#include <cmath>

namespace line_extraction
{
bool isBreakpoint(const PreparedScan& scan, int i, const BreakpointParams& params)
{
  const double dphi = std::abs(scan.angles[i] - scan.angles[i - 1]);
  // Beams farther apart than lambda (e.g. many invalid beams between them) cannot
  // be bridged by the model.
  if (dphi >= params.lambda) return true;
  const double limit =
      scan.ranges[i - 1] * std::sin(dphi) / std::sin(params.lambda - dphi) + 3.0 * params.sigma;
  return (scan.points[i] - scan.points[i - 1]).squaredNorm() > limit * limit;
}

void breakpointClusters(const PreparedScan& scan, PointRange range, const BreakpointParams& params,
                        std::vector<PointRange>& out)
{
  if (range.size() <= 0) return;
  // Neighbouring points are almost always one increment apart: keep the last
  // sine ratio instead of two sines per point.
  double cached_dphi = -1.0, ratio = 0.0;
  const double margin = 3.0 * params.sigma;
  int start = range.begin;
  for (int i = range.begin + 1; i <= range.end; ++i)
  {
    bool split = i == range.end;
    if (!split)
    {
      // From the beam numbers, so equal steps give bit-equal angles for the cache.
      const int step = scan.beam_index[i] - scan.beam_index[i - 1];
      const double dphi =
          step > 0 ? step * scan.angle_increment : std::abs(scan.angles[i] - scan.angles[i - 1]);
      if (dphi >= params.lambda)
      {
        split = true;
      }
      else
      {
        if (dphi != cached_dphi)
        {
          cached_dphi = dphi;
          ratio = std::sin(dphi) / std::sin(params.lambda - dphi);
        }
        const double limit = scan.ranges[i - 1] * ratio + margin;
        split = (scan.points[i] - scan.points[i - 1]).squaredNorm() > limit * limit;
      }
    }
    if (split)
    {
      if (i - start >= params.min_points) out.push_back({start, i});
      start = i;
    }
  }
}

}  // namespace line_extraction
