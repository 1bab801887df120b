// Removal of isolated readings (spurious returns) before extraction.
#pragma once

#include "line_extraction/breakpoint_clustering.hpp"
#include "line_extraction/types.hpp"

namespace line_extraction
{
/// Removes, in place, every point that the adaptive breakpoint test separates
/// from both neighbours while the two neighbours are not separated from each
/// other: a lone spurious return in the middle of a surface. The surface then
/// stays one piece for the extractors. Keeps capacity (no allocation).
/// Returns the number of points removed.
int removeIsolatedPoints(PreparedScan& scan, const BreakpointParams& params);

}  // namespace line_extraction
