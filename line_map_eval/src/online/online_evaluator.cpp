#include "line_map_eval/online/online_evaluator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
OnlineEvaluatorParams OnlineEvaluatorParams::fromParams(const linemap::ParamSet& params)
{
  OnlineEvaluatorParams p;
  p.evaluator = EvaluatorParams::fromParams(params);
  p.min_period = params.getDouble("min_period", p.min_period);
  p.time_jump_tolerance = params.getDouble("time_jump_tolerance", p.time_jump_tolerance);
  if (!(p.min_period >= 0.0)) throw linemap::ParameterError("parameter 'min_period' must be >= 0");
  if (!(p.time_jump_tolerance >= 0.0))
    throw linemap::ParameterError("parameter 'time_jump_tolerance' must be >= 0");
  return p;
}

OnlineEvaluator::OnlineEvaluator(const OnlineEvaluatorParams& params)
    : params_(params),
      evaluator_(params.evaluator),
      time_jumps_(params.time_jump_tolerance, {"scan", "segment set"})
{
}

bool OnlineEvaluator::observeTime(double clock, double stamp, Stream stream)
{
  if (!time_jumps_.observe(clock, stamp, stream)) return false;
  ++counters_.time_jumps;
  return true;
}

std::vector<linemap::Vec2> OnlineEvaluator::scanPoints(const ScanRanges& scan)
{
  std::vector<linemap::Vec2> points;
  points.reserve(scan.ranges.size());
  for (std::size_t i = 0; i < scan.ranges.size(); ++i)
  {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r < scan.range_min || r >= scan.range_max) continue;
    const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    points.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return points;
}

bool OnlineEvaluator::addScan(double stamp, const ScanRanges& scan, const linemap::Pose2& laser,
                              const std::optional<linemap::Pose2>& odom)
{
  ++counters_.scans;
  if (!std::isfinite(scan.angle_increment) || scan.angle_increment == 0.0)
  {
    ++counters_.rejected_scans;
    return false;
  }
  const bool stored = evaluator_.addScan(stamp, laser, scanPoints(scan), odom);
  dirty_ = dirty_ || stored;
  return stored;
}

bool OnlineEvaluator::addSegments(double stamp, std::vector<linemap::Segment2> segments,
                                  const linemap::Pose2& laser, const std::optional<linemap::Pose2>& odom)
{
  ++counters_.segment_sets;
  return evaluator_.addSegments(stamp, laser, std::move(segments), odom);
}

void OnlineEvaluator::addTrajectory(const std::vector<std::pair<double, linemap::Pose2>>& laser_poses)
{
  ++counters_.trajectories;
  std::vector<std::pair<double, linemap::Pose2>> valid;
  valid.reserve(laser_poses.size());
  for (const auto& [stamp, p] : laser_poses)
    if (std::isfinite(stamp) && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta))
      valid.emplace_back(stamp, p);
  counters_.rejected_poses += laser_poses.size() - valid.size();
  if (valid.empty()) return;
  counters_.unmatched_poses += evaluator_.applyTrajectory(valid);
  dirty_ = true;
}

void OnlineEvaluator::setMap(std::vector<linemap::Segment2> map, double stamp)
{
  map_ = std::move(map);
  map_stamp_ = stamp;
  have_map_ = true;
  dirty_ = true;
}

std::optional<MapMetrics> OnlineEvaluator::evaluateIfDue(double now, bool force)
{
  if (!have_map_ || !dirty_ || (!force && now - last_evaluation_ < params_.min_period)) return std::nullopt;
  last_evaluation_ = now;
  const auto start = std::chrono::steady_clock::now();
  MapMetrics m = evaluator_.evaluate(map_);
  counters_.last_eval_ms = linemap::millisecondsSince(start);
  counters_.last_quality = m.quality.quality;
  counters_.last_structure_coverage = m.structure_coverage.fraction() * 100.0;
  counters_.last_unmapped_structure = m.structure_coverage.unmapped_length;
  counters_.last_crossing_pairs = m.crossing_pairs.size();
  dirty_ = false;
  return m;
}

MapMetrics OnlineEvaluator::evaluate(const std::vector<linemap::Segment2>& map)
{
  return evaluator_.evaluate(map);
}

std::vector<std::pair<std::string, std::string>> OnlineEvaluator::diagnostics() const
{
  auto n = [](std::size_t v) { return std::to_string(v); };
  auto d = [](double v)
  {
    std::ostringstream out;
    out << v;
    return out.str();
  };
  const EvaluatorCounters& c = counters_;
  return {{"scans", n(c.scans)},
          {"segment sets", n(c.segment_sets)},
          {"trajectories", n(c.trajectories)},
          {"keyframe scans", n(evaluator_.scanCount())},
          {"original segments", n(evaluator_.originalCount())},
          {"dropped scans (tf)", n(c.dropped_scans)},
          {"rejected scans", n(c.rejected_scans)},
          {"rejected trajectory poses", n(c.rejected_poses)},
          {"unmatched trajectory poses", n(c.unmatched_poses)},
          {"time jumps", n(c.time_jumps)},
          {"last quality [%]", d(c.last_quality)},
          {"last structure coverage [%]", d(c.last_structure_coverage)},
          {"last unmapped structure [m]", d(c.last_unmapped_structure)},
          {"last crossing pairs", n(c.last_crossing_pairs)},
          {"last evaluation [ms]", d(c.last_eval_ms)}};
}

}  // namespace line_map_eval
