// Every metric of one line map (ROS-free), computed in one place for both consumers: the
// evaluator nodelet (MapEvaluator::evaluate) and the batch tool (runBatch).
#pragma once

#include <vector>

#include "line_extraction/geometry.hpp"
#include "line_extraction/params.hpp"
#include "line_map_eval/coverage.hpp"
#include "line_map_eval/error_metric.hpp"
#include "line_map_eval/lookup_table.hpp"
#include "line_map_eval/map_quality.hpp"
#include "line_map_eval/map_statistics.hpp"
#include "line_map_eval/redundant_pairs.hpp"
#include "line_map_merging/fusion.hpp"

namespace line_map_eval
{
/// Key "eval/point_coverage_sigmas".
struct CoverageParams
{
  double point_sigmas =
      1.0;  ///< a scan point is covered within this many lookup-table sigmas of a map segment

  static CoverageParams fromParams(const linemap::ParamSet& params);
  void validate() const;
};

struct MapMetricParams
{
  QualityParams quality;
  /// Error assignment without provenance, redundant pairs, and the bounds (d_max, theta_max) of
  /// the length coverage.
  line_map_merging::FusionParams fusion;
  CoverageParams coverage;
};

struct MapMetrics
{
  QualityResult quality;
  ErrorMetricResult error;
  MapStatistics statistics;
  PointCoverage point_coverage;    ///< of the lookup table's scan points
  LengthCoverage length_coverage;  ///< of the originals
  RedundancyResult redundancy;
};

/// The originals of the error metric with their map segment, when the merger keeps provenance.
struct ErrorAssignment
{
  std::vector<linemap::Segment2> originals;
  std::vector<int> map_index;  ///< per original; -1: none
};

/// Scores `map` against the lookup table built from `scan_points` and the original segments (all in
/// the map frame). The error metric uses `provenance` when given, else each original goes to the
/// nearest map segment meeting the fusion conditions (assignToMapSegments). Point coverage uses the
/// radius point_sigmas * table.params().sigma.
MapMetrics computeMapMetrics(const LookupTable& table, const std::vector<linemap::Vec2>& scan_points,
                             const std::vector<linemap::Segment2>& originals,
                             const std::vector<linemap::Segment2>& map, const MapMetricParams& params,
                             const ErrorAssignment* provenance = nullptr);

}  // namespace line_map_eval
