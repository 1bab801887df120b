#include "line_map_eval/online/map_evaluator.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>

namespace line_map_eval
{
EvaluatorParams EvaluatorParams::fromParams(const linemap::ParamSet& params)
{
  EvaluatorParams p;
  p.gate = line_map_merging::KeyframeGateParams::fromParams(params);
  p.stamp_tolerance = params.getDouble("eval/stamp_tolerance", p.stamp_tolerance);
  if (!(p.stamp_tolerance >= 0.0))
    throw linemap::ParameterError("parameter 'eval/stamp_tolerance' must be >= 0");
  p.max_gap = params.getDouble("trajectory_max_gap", p.max_gap);
  if (!(p.max_gap >= 0.0)) throw linemap::ParameterError("parameter 'trajectory_max_gap' must be >= 0");
  p.correction = line_map_merging::correctionModeFromString(
      "trajectory_correction", params.getString("trajectory_correction", "nearest"));
  p.keyframe_source = line_map_merging::keyframeSourceFromString("keyframe_source",
                                                                 params.getString("keyframe_source", "auto"));
  p.keyframe_buffer = params.getDouble("keyframe_buffer", p.keyframe_buffer);
  if (!(p.keyframe_buffer >= 0.0)) throw linemap::ParameterError("parameter 'keyframe_buffer' must be >= 0");
  p.table = LookupTableParams::fromParams(params);
  p.quality = QualityParams::fromParams(params);
  p.fusion = line_map_merging::FusionParams::fromParams(params);
  p.coverage = CoverageParams::fromParams(params);
  return p;
}

MapEvaluator::MapEvaluator(const EvaluatorParams& params)
    : params_(params),
      scan_gate_(params.gate),
      segment_gate_(params.gate),
      scan_nodes_(params.gate, params.stamp_tolerance, params.keyframe_buffer),
      segment_nodes_(params.gate, params.stamp_tolerance, params.keyframe_buffer)
{
  if (params_.keyframe_source == line_map_merging::KeyframeSource::kTrajectory)
  {
    scan_nodes_.activate(-INFINITY, std::nullopt);
    segment_nodes_.activate(-INFINITY, std::nullopt);
  }
}

bool MapEvaluator::storeNodes(std::vector<line_map_merging::NodeKeyframes<Frame>::Ready> ready,
                              std::vector<Frame>& frames, std::map<double, linemap::Pose2>& stamps)
{
  bool stored = false;
  for (auto& r : ready)
  {
    if (!stamps.emplace(r.stamp, r.pose).second) continue;
    r.payload.pose = r.pose;
    frames.push_back(std::move(r.payload));
    stored = true;
  }
  return stored;
}

bool MapEvaluator::holdForNodes(line_map_merging::NodeKeyframes<Frame>& nodes, const Frame& frame,
                                std::vector<Frame>& frames, std::map<double, linemap::Pose2>& stamps,
                                bool& stored)
{
  stored = false;
  if (params_.keyframe_source == line_map_merging::KeyframeSource::kTf) return false;
  stored = storeNodes(nodes.addScan(frame.stamp, frame), frames, stamps);
  return nodes.active();
}

bool MapEvaluator::gateAccepts(const std::map<double, linemap::Pose2>& stored,
                               line_map_merging::KeyframeGate& gate, double stamp,
                               const linemap::Pose2& pose) const
{
  if (stored.empty() || stamp > stored.rbegin()->first) return gate.accept(pose);
  // Within the stored time span: a replay after the clock jumped back, or a scan that the tf filter
  // let through late (common on a loaded machine). The live gate holds whatever came last, where the
  // last pass ended or the replay started, and would begin a chain of keyframes of its own beside
  // the stored one. Stored only where the stored frames leave a gap: the gate would
  // admit it after the stored frame before it and before the one after it.
  const auto next = stored.upper_bound(stamp);
  line_map_merging::KeyframeGate check(params_.gate);
  check.setReference(next->second);
  if (!check.wouldAccept(pose)) return false;
  if (next != stored.begin())
  {
    check.setReference(std::prev(next)->second);
    if (!check.wouldAccept(pose)) return false;
  }
  return true;  // the live gate stays with the newest frame
}

bool MapEvaluator::addScan(double stamp, const linemap::Pose2& laser_pose, std::vector<linemap::Vec2> points,
                           const std::optional<linemap::Pose2>& odom_pose)
{
  // A replayed scan is not stored again; the gate moves on from it as from a stored one.
  if (scan_stamps_.count(stamp))
  {
    scan_gate_.setReference(laser_pose);
    return false;
  }
  history_.add(stamp, odom_pose ? *odom_pose : laser_pose);
  Frame frame{stamp, laser_pose, odom_pose, std::move(points), {}};
  bool stored = false;
  if (holdForNodes(scan_nodes_, frame, scans_, scan_stamps_, stored))
  {
    table_dirty_ = table_dirty_ || stored;
    return stored;
  }
  if (stored) table_dirty_ = true;
  if (!gateAccepts(scan_stamps_, scan_gate_, stamp, laser_pose)) return stored;
  scan_stamps_.emplace(stamp, laser_pose);
  scans_.push_back(std::move(frame));
  table_dirty_ = true;
  return true;
}

bool MapEvaluator::addSegments(double stamp, const linemap::Pose2& laser_pose,
                               std::vector<linemap::Segment2> segments,
                               const std::optional<linemap::Pose2>& odom_pose)
{
  if (segment_stamps_.count(stamp))
  {
    segment_gate_.setReference(laser_pose);
    return false;
  }
  history_.add(stamp, odom_pose ? *odom_pose : laser_pose);
  Frame frame{stamp, laser_pose, odom_pose, {}, std::move(segments)};
  bool stored = false;
  if (holdForNodes(segment_nodes_, frame, segments_, segment_stamps_, stored)) return stored;
  if (!gateAccepts(segment_stamps_, segment_gate_, stamp, laser_pose)) return stored;
  segment_stamps_.emplace(stamp, laser_pose);
  segments_.push_back(std::move(frame));
  return true;
}

std::size_t MapEvaluator::applyTrajectory(const std::vector<std::pair<double, linemap::Pose2>>& laser_poses)
{
  // The merger's keyframe policy (NodeKeyframes), on both stores.
  const bool names_scans =
      params_.keyframe_source != line_map_merging::KeyframeSource::kTf &&
      std::any_of(laser_poses.begin(), laser_poses.end(),
                  [&](const auto& n)
                  { return history_.at(n.first, params_.stamp_tolerance, 0.0).has_value(); });
  auto rebuild = [&](line_map_merging::NodeKeyframes<Frame>& nodes, std::vector<Frame>& frames,
                     std::map<double, linemap::Pose2>& stamps)
  {
    if (!nodes.rebuildAtFirstTrajectory(
            names_scans, stamps.empty() ? std::nullopt : std::optional<double>(stamps.begin()->first)))
      return;
    frames.clear();
    stamps.clear();
    table_dirty_ = true;
  };
  rebuild(scan_nodes_, scans_, scan_stamps_);
  rebuild(segment_nodes_, segments_, segment_stamps_);
  const auto nc =
      line_map_merging::nodeCorrections(history_, laser_poses, params_.stamp_tolerance, params_.max_gap);
  if (!nc.corrections.empty())
  {
    for (std::vector<Frame>* frames : {&scans_, &segments_})
      for (Frame& f : *frames)
        f.pose = line_map_merging::correctionAt(nc.corrections, f.stamp, params_.correction) * continuous(f);
    table_dirty_ = true;
  }
  if (params_.keyframe_source == line_map_merging::KeyframeSource::kTf) return nc.unmatched;
  // The nodes take over from the newest stored frame on (the gate measures from that frame where it
  // now is).
  auto activate = [&](line_map_merging::NodeKeyframes<Frame>& nodes, const std::vector<Frame>& frames)
  {
    const auto newest = std::max_element(frames.begin(), frames.end(),
                                         [](const Frame& a, const Frame& b) { return a.stamp < b.stamp; });
    if (newest == frames.end())
      nodes.takeOver(names_scans, -INFINITY, std::nullopt);
    else
      nodes.takeOver(names_scans, newest->stamp, newest->pose);
  };
  activate(scan_nodes_, scans_);
  activate(segment_nodes_, segments_);
  if (storeNodes(scan_nodes_.addTrajectory(laser_poses), scans_, scan_stamps_)) table_dirty_ = true;
  storeNodes(segment_nodes_.addTrajectory(laser_poses), segments_, segment_stamps_);
  return nc.unmatched;
}

MapMetrics MapEvaluator::evaluate(const std::vector<linemap::Segment2>& map)
{
  if (table_dirty_)
  {
    table_points_.clear();
    for (const Frame& f : scans_) appendWorldPoints(f.pose, f.points, table_points_);
    table_ = LookupTable::build(table_points_, params_.table);
    // Straight structure depends on the points alone: classified once per table, reused per map.
    structure_ = classifyStructure(table_points_, params_.table.sigma, params_.coverage.structure);
    table_dirty_ = false;
  }
  std::vector<linemap::Segment2> originals;
  for (const Frame& f : segments_)
    for (const linemap::Segment2& s : f.segments) originals.push_back(s.transformed(f.pose));

  // The map message carries no provenance: each original goes to the nearest map segment that
  // meets the fusion conditions with it.
  return computeMapMetrics(table_, table_points_, originals, map,
                           {params_.quality, params_.fusion, params_.coverage}, nullptr, &structure_);
}

std::size_t MapEvaluator::originalCount() const
{
  std::size_t n = 0;
  for (const Frame& f : segments_) n += f.segments.size();
  return n;
}

void MapEvaluator::reset()
{
  const double horizon = std::max(scan_stamps_.empty() ? -INFINITY : scan_stamps_.rbegin()->first,
                                  segment_stamps_.empty() ? -INFINITY : segment_stamps_.rbegin()->first);
  scans_.clear();
  segments_.clear();
  scan_stamps_.clear();
  segment_stamps_.clear();
  history_.clear();
  scan_nodes_.clear(horizon);
  segment_nodes_.clear(horizon);
  scan_gate_ = line_map_merging::KeyframeGate(params_.gate);
  segment_gate_ = line_map_merging::KeyframeGate(params_.gate);
  table_ = LookupTable();
  table_points_.clear();
  structure_ = StructurePoints();
  table_dirty_ = true;
}

}  // namespace line_map_eval
