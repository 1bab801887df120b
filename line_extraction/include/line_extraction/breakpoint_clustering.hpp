// Adaptive breakpoint detection (Borges & Aldon): splits the ordered scan points
// where consecutive points are farther apart than a surface seen at grazing angle
// lambda could explain.
#pragma once

#include <vector>

#include "line_extraction/types.hpp"

namespace line_extraction
{
struct BreakpointParams
{
  double lambda = 10.0 * linemap::kPi / 180.0;  ///< smallest incidence angle of a surface [rad]
  double sigma = 0.01;                          ///< range noise [m]
  int min_points = 3;                           ///< clusters with fewer points are dropped
};

/// Appends to `out` the clusters of the points [range.begin, range.end).
void breakpointClusters(const PreparedScan& scan, PointRange range, const BreakpointParams& params,
                        std::vector<PointRange>& out);

/// True when points i-1 and i of the scan are separated by a breakpoint.
bool isBreakpoint(const PreparedScan& scan, int i, const BreakpointParams& params);

}  // namespace line_extraction
