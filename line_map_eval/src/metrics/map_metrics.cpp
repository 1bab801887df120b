#include "line_map_eval/metrics/map_metrics.hpp"

#include <cmath>
#include <string>

namespace line_map_eval
{
CoverageParams CoverageParams::fromParams(const linemap::ParamSet& params)
{
  CoverageParams p;
  p.point_sigmas = params.getDouble("eval/point_coverage_sigmas", p.point_sigmas);
  p.structure = StructureParams::fromParams(params);
  p.validate();
  return p;
}

void CoverageParams::validate() const
{
  if (!(point_sigmas >= 0.0) || !std::isfinite(point_sigmas))
    throw linemap::ParameterError("parameter 'eval/point_coverage_sigmas' must be finite and >= 0, got " +
                                  std::to_string(point_sigmas));
  structure.validate();
}

MapMetrics computeMapMetrics(const LookupTable& table, const std::vector<linemap::Vec2>& scan_points,
                             const std::vector<linemap::Segment2>& originals,
                             const std::vector<linemap::Segment2>& map, const MapMetricParams& params,
                             const ErrorAssignment* provenance, const StructurePoints* structure)
{
  params.coverage.validate();
  MapMetrics m;
  m.quality = computeMapQuality(table, map, params.quality);
  if (provenance)
    m.error = computeErrorMetric(provenance->originals, provenance->map_index, map);
  else
    m.error = computeErrorMetric(originals, assignToMapSegments(originals, map, params.fusion), map);
  m.statistics = computeMapStatistics(map, originals.size());
  const double radius = params.coverage.point_sigmas * table.params().sigma;
  m.point_coverage = computePointCoverage(scan_points, map, radius);
  if (structure)
    m.structure_coverage = computeStructureCoverage(*structure, m.point_coverage, map, radius);
  else
    m.structure_coverage = computeStructureCoverage(
        classifyStructure(scan_points, table.params().sigma, params.coverage.structure), m.point_coverage,
        map, radius);
  m.length_coverage =
      computeLengthCoverage(originals, map, params.fusion.max_distance, params.fusion.max_angle);
  m.redundancy = findRedundantPairs(map, params.fusion);
  m.crossing_pairs = line_map_merging::findCrossingPairs(map, radius);
  return m;
}

}  // namespace line_map_eval
