// MS-RLSM: offline redundant line segment merging by mean-shift clustering (Sarkar, Pal & Sarkar,
// 2014). All segments are clustered by undirected direction with mean shift on the circle of
// period pi; inside each angular cluster, segments whose lateral separation and longitudinal
// overlap (along the cluster direction) pass the thresholds are linked into spatial clusters; each
// spatial cluster is fused with length weights into one segment.
#pragma once

#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/offline_merger.hpp"

namespace line_map_merging
{
struct MsParams
{
  double angular_bandwidth = 0.1;       ///< flat mean-shift kernel half-width [rad], in (0, pi/2)
  double lateral_separation = 0.10;     ///< max distance across the cluster direction [m], >= 0
  double longitudinal_overlap = -0.10;  ///< min overlap along it [m]; negative: a gap up to |value|

  /// Reads "ms/angular_bandwidth", "ms/lateral_separation", "ms/longitudinal_overlap"; throws
  /// linemap::ParameterError naming the key for a malformed or out-of-range value.
  static MsParams fromParams(const linemap::ParamSet& params);
  void validate() const;
};

/// The undirected direction of s in [0, pi).
double undirectedAngle(const Segment2& s);

/// Mean shift with a flat kernel of half-width `bandwidth` on the circle of period pi, weighted by
/// `weights`. Returns a cluster label per angle (0, 1, ... in order of first appearance) and the
/// cluster modes in `modes` (in [0, pi)). Modes closer than bandwidth / 2 form one cluster.
std::vector<int> angularClusters(const std::vector<double>& angles, const std::vector<double>& weights,
                                 double bandwidth, std::vector<double>* modes = nullptr);

class MsRlsm : public OfflineMerger
{
 public:
  /// Throws linemap::ParameterError for invalid parameters.
  explicit MsRlsm(const MsParams& params = MsParams());
  const char* name() const override { return "ms"; }
  const MsParams& params() const { return params_; }

 protected:
  /// Ids 0, 1, ... in order of each cluster's first segment (arrival order).
  std::vector<MapSegment> compute() const override;

 private:
  MsParams params_;
};

}  // namespace line_map_merging
