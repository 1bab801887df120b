// Every metric of one line map (ROS-free), computed in one place for both consumers: the
// evaluator nodelet (MapEvaluator::evaluate) and the batch tool (runBatch).
#pragma once

#include <vector>

#include "line_map_eval/metrics/error_metric.hpp"
#include "line_map_eval/metrics/length_coverage.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/metrics/map_statistics.hpp"
#include "line_map_eval/metrics/point_coverage.hpp"
#include "line_map_eval/metrics/redundant_pairs.hpp"
#include "line_map_eval/metrics/structure_coverage.hpp"
#include "line_map_merging/mergers/crossing_pairs.hpp"
#include "line_map_merging/mergers/fusion.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// Keys "eval/point_coverage_sigmas" and "eval/structure_*".
struct CoverageParams
{
  double point_sigmas =
      1.0;  ///< a scan point is covered within this many lookup-table sigmas of a map segment
  StructureParams structure;  ///< which scan points lie on straight structure

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
  PointCoverage point_coverage;          ///< of the lookup table's scan points
  StructureCoverage structure_coverage;  ///< of those on straight structure (same radius)
  LengthCoverage length_coverage;        ///< of the originals
  RedundancyResult redundancy;
  /// Map segments crossing in an X, each running on past the crossing by more than the point-coverage
  /// radius: within it, a crossing is an L or T corner drawn a little long (registration noise).
  std::vector<line_map_merging::CrossingPair> crossing_pairs;
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
/// radius point_sigmas * table.params().sigma, and so does structure coverage, over `structure`: the
/// straight-structure points of `scan_points` (classifyStructure with the table's sigma), computed
/// here when not given — callers scoring several maps against one table classify once.
MapMetrics computeMapMetrics(const LookupTable& table, const std::vector<linemap::Vec2>& scan_points,
                             const std::vector<linemap::Segment2>& originals,
                             const std::vector<linemap::Segment2>& map, const MapMetricParams& params,
                             const ErrorAssignment* provenance = nullptr,
                             const StructurePoints* structure = nullptr);

}  // namespace line_map_eval
