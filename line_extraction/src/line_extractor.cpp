// The extraction pipeline. Every buffer is a member reused between scans, so once
// warmed up on a scan geometry the pipeline does not allocate.
#include "line_extraction/line_extractor.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "line_extraction/isolated_points.hpp"

namespace line_extraction
{
namespace
{
[[noreturn]] void bad(const std::string& key, const std::string& why)
{
  throw linemap::ParameterError("parameter '" + key + "' " + why);
}
}  // namespace

void orientFreeSideLeft(Segment& segment)
{
  // The sensor sits at the origin of the laser frame; it is left of start -> end when the cross
  // product of the direction and (sensor - start) is positive. Members stay in scan order.
  const Vec2 d = segment.end - segment.start;
  const Vec2 to_sensor = -segment.start;
  if (d.x() * to_sensor.y() - d.y() * to_sensor.x() < 0.0) std::swap(segment.start, segment.end);
}

PipelineParams PipelineParams::fromParams(const linemap::ParamSet& ps)
{
  PipelineParams p;
  p.algorithm = ps.getString("algorithm", p.algorithm);
  p.clustering = ps.getBool("clustering", p.clustering);
  p.range_sigma = ps.getDouble("range_sigma", p.range_sigma);
  if (!(p.range_sigma > 0.0 && std::isfinite(p.range_sigma))) bad("range_sigma", "must be > 0");
  p.max_usable_range = ps.getDouble("max_usable_range", p.max_usable_range);
  if (!(p.max_usable_range > 0.0)) bad("max_usable_range", "must be > 0");
  p.breakpoint.sigma = p.range_sigma;
  p.breakpoint.lambda = ps.getDouble("breakpoint_lambda", p.breakpoint.lambda);
  if (!(p.breakpoint.lambda > 0.0 && p.breakpoint.lambda < linemap::kPi / 2.0))
    bad("breakpoint_lambda", "must be in (0, pi/2) rad");
  p.sensor = SensorModel::fromParams(ps);
  p.breakpoint.min_points = ps.getInt("cluster_min_points", p.breakpoint.min_points);
  if (p.breakpoint.min_points < 1) bad("cluster_min_points", "must be >= 1");
  p.remove_isolated = ps.getBool("remove_isolated", p.remove_isolated);
  p.merge = ps.getBool("merge", p.merge);
  p.merge_params.range_sigma = p.range_sigma;
  p.merge_params.gate = ps.getDouble("merge_gate", p.merge_params.gate);
  if (!(p.merge_params.gate > 0.0)) bad("merge_gate", "must be > 0");
  p.merge_params.max_gap = ps.getDouble("merge_max_gap", p.merge_params.max_gap);
  if (!(p.merge_params.max_gap >= 0.0)) bad("merge_max_gap", "must be >= 0");
  p.min_points = ps.getInt("min_points", p.min_points);
  if (p.min_points < 2) bad("min_points", "must be >= 2");
  p.min_length = ps.getDouble("min_length", p.min_length);
  if (!(p.min_length >= 0.0 && std::isfinite(p.min_length))) bad("min_length", "must be >= 0");
  return p;
}

LineExtractor::LineExtractor(const linemap::ParamSet& params)
    : params_(PipelineParams::fromParams(params)),
      algorithm_(makeExtractor(params_.algorithm, params)),
      preprocessor_(params_.max_usable_range),
      merger_(params_.merge_params)
{
}

const ExtractionResult& LineExtractor::extract(const ScanInput& scan)
{
  result_.clear();
  raw_.clear();
  merged_.clear();
  clusters_.clear();
  preprocessor_.prepare(scan, prepared_);
  if (params_.remove_isolated) removeIsolatedPoints(prepared_, params_.breakpoint);
  params_.sensor.annotate(prepared_);
  const PointRange all{0, static_cast<int>(prepared_.size())};
  if (all.size() < 2) return result_;

  if (params_.clustering)
    breakpointClusters(prepared_, all, params_.breakpoint, clusters_);
  else
    clusters_.push_back(all);
  for (const PointRange& range : clusters_) algorithm_->extractRange(prepared_, range, raw_);

  const ExtractionResult* source = &raw_;
  if (params_.merge)
  {
    merger_.merge(prepared_, raw_, merged_, prepared_.full_circle);
    source = &merged_;
  }
  // Size filters; copying keeps the index lists compact and in segment order. A fit whose ends lie
  // within the range noise of one spot has no direction: no line, even with min_length 0.
  const double degenerate = PipelineParams::kDegenerateSigmas * params_.range_sigma;
  for (const Segment& seg : source->segments)
  {
    if (seg.num_points < params_.min_points || seg.length() < params_.min_length ||
        seg.length() <= degenerate)
      continue;
    Segment copy = seg;
    orientFreeSideLeft(copy);
    copy.index_begin = static_cast<int>(result_.point_indices.size());
    result_.point_indices.insert(result_.point_indices.end(), source->point_indices.begin() + seg.index_begin,
                                 source->point_indices.begin() + seg.index_end);
    copy.index_end = static_cast<int>(result_.point_indices.size());
    result_.segments.push_back(copy);
  }
  return result_;
}

}  // namespace line_extraction
