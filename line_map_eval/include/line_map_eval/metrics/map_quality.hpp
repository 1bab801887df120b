// Correlation quality q of a line map against the lookup table of the registered scans
// (ROS-free), after the correlation metric of CAE-RLSM (Wen et al., section IV).
#pragma once

#include <cstddef>
#include <vector>

#include "line_map_eval/metrics/lookup_table.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// Keys "eval/directed", "eval/direction_bins" and "eval/redundancy_penalty".
struct QualityParams
{
  /// The paper's directed pixels: bins over the full circle of headings, so the two faces of a
  /// wall (opposite headings under the orientation convention) are not redundant. false = the
  /// undirected variant (headings modulo pi), kept for comparison.
  bool directed = true;
  int direction_bins = 16;          ///< over [0, 2 pi) when directed, [0, pi) when not: 22.5 deg each
  double redundancy_penalty = 1.0;  ///< w: a redundant pixel subtracts w * L(p)

  static QualityParams fromParams(const linemap::ParamSet& params);
  void validate() const;
};

struct QualityResult
{
  double quality = 0.0;              ///< q [%]; 0 for an empty map
  std::size_t pixel_count = 0;       ///< N: all rasterised map pixels
  std::size_t redundant_pixels = 0;  ///< pixels counted as redundant
  double nonredundant_sum = 0.0;     ///< sum of L over the non-redundant pixels
  double redundant_sum = 0.0;        ///< sum of L over the redundant pixels (before w)
};

/// Direction bin of a heading: `bins` equal bins over the full circle (directed) or over headings
/// modulo pi (undirected: a wall drawn in either direction falls into the same bin). Bin k is
/// centred on k times the bin width, so axis-aligned walls lie in the middle of theirs.
int directionBin(double heading, int bins, bool directed);

/// q = 100 / N * (sum over non-redundant pixels of L(p) - w * sum over redundant pixels of L(p)).
/// Every segment is rasterised with Bresenham between the cells of its endpoints (cells of
/// the table's grid; pixels outside the table have L = 0). A pixel is the pair (cell,
/// direction bin of its segment's heading); the first pixel of each (cell, bin) pair is non-redundant
/// and every further pixel of the same pair is redundant. L(p) depends only on the cell, so
/// which pixel of a pair counts as the first does not change q. Throws std::invalid_argument
/// naming the segment for non-finite coordinates, linemap::ParameterError for bad params.
QualityResult computeMapQuality(const LookupTable& table, const std::vector<linemap::Segment2>& map,
                                const QualityParams& params);

}  // namespace line_map_eval
