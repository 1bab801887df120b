// Offline three-criteria line feature fusion (Li, Fu, Sun, Marzbani & Hu, ISPRS IJGI 2023).
// Two segments from different keyframes are close when
//  (1) their included angle beta = acos(|A1 A2 + B1 B2| / (|(A1, B1)| |(A2, B2)|)) <= delta,
//      with A x + B y + C = 0 the line of each segment;
//  (2) their feature circles (centre = midpoint, diameter = length) overlap by
//      epsilon = lens area / area of the smaller circle >= gamma;
//  (3) d_max, the larger distance of each midpoint to the other segment, <= eta.
// Close segments share a cluster (union-find); clusters with fewer than min_count segments are
// dropped as trivial; each remaining cluster becomes the total-least-squares line through all its
// endpoints, clipped to their extreme projections; finally endpoints of different fused segments
// closer than snap_distance are moved to their mean (corners).
#pragma once

#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/offline_merger.hpp"

namespace line_map_merging
{
struct Li2023Params
{
  double delta = 5.0 * linemap::kPi / 180.0;  ///< max included angle [rad], in [0, pi/2]
  double gamma = 0.3;                         ///< min feature circle overlap ratio, in (0, 1]
  double eta = 0.10;                          ///< max midpoint-to-segment distance [m], >= 0
  int min_count = 2;                          ///< clusters with fewer segments are dropped, >= 1
  double snap_distance = 0.10;                ///< endpoints closer than this are joined [m], >= 0

  /// Reads "li2023/delta", "li2023/gamma", "li2023/eta", "li2023/min_count",
  /// "li2023/snap_distance"; throws linemap::ParameterError naming the key for a bad value.
  static Li2023Params fromParams(const linemap::ParamSet& params);
  void validate() const;
};

/// Area of the intersection of two discs of radii r1, r2 whose centres are d apart (0 when apart
/// or tangent, the smaller disc when one contains the other).
double lensArea(double r1, double r2, double d);
/// Criterion (1): the included angle of the two lines in [0, pi/2].
double includedAngle(const Segment2& a, const Segment2& b);
/// Criterion (2): lens area of the feature circles over the area of the smaller one, in [0, 1].
double circleOverlapRatio(const Segment2& a, const Segment2& b);
/// Criterion (3): the larger distance of each midpoint to the other (closed) segment.
double midpointDistance(const Segment2& a, const Segment2& b);

class Li2023 : public OfflineMerger
{
 public:
  /// Throws linemap::ParameterError for invalid parameters.
  explicit Li2023(const Li2023Params& params = Li2023Params());
  const char* name() const override { return "li2023"; }
  const Li2023Params& params() const { return params_; }
  bool close(const Segment2& a, const Segment2& b) const;

 protected:
  /// Ids 0, 1, ... in order of each cluster's first segment (arrival order).
  std::vector<MapSegment> compute() const override;

 private:
  Li2023Params params_;
};

}  // namespace line_map_merging
