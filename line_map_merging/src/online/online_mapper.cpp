#include "line_map_merging/online/online_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <sstream>

#include "linemap/small_helpers.hpp"

namespace line_map_merging
{
namespace
{

bool finite(const linemap::Pose2& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

std::string text(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}
}  // namespace

OnlineMapperParams OnlineMapperParams::fromParams(const linemap::ParamSet& params)
{
  OnlineMapperParams p;
  p.gate = KeyframeGateParams::fromParams(params);
  p.stamp_tolerance = params.getNonNegative("stamp_tolerance", p.stamp_tolerance);
  p.max_gap = params.getNonNegative("trajectory_max_gap", p.max_gap);
  p.time_jump_tolerance = params.getNonNegative("time_jump_tolerance", p.time_jump_tolerance);
  p.autosave_period = params.getNonNegative("autosave_period", p.autosave_period);
  p.correction =
      correctionModeFromString("trajectory_correction", params.getString("trajectory_correction", "nearest"));
  p.keyframe_source =
      keyframeSourceFromString("keyframe_source", params.getString("keyframe_source", "auto"));
  p.keyframe_buffer = params.getNonNegative("keyframe_buffer", p.keyframe_buffer);
  p.map_level = MapLevelParams::fromParams(params);
  return p;
}

OnlineMapper::Lane::Lane(const OnlineMapperParams& params)
    : gate(params.gate), nodes(params.gate, params.stamp_tolerance, params.keyframe_buffer)
{
  if (params.keyframe_source == KeyframeSource::kTrajectory) nodes.activate(-INFINITY, std::nullopt);
}

OnlineMapper::OnlineMapper(std::unique_ptr<Merger> merger, const OnlineMapperParams& params)
    : merger_(std::move(merger)), params_(params), time_jumps_(params.time_jump_tolerance, {"scan"})
{
  if (!merger_) throw std::invalid_argument("OnlineMapper: no merger");
  lane(0).placement = linemap::Pose2();
  if (params_.map_level.enabled) map_level_.emplace(params_.map_level);
}

OnlineMapper::Lane& OnlineMapper::lane(std::size_t index)
{
  auto it = lanes_.find(index);
  if (it == lanes_.end()) it = lanes_.emplace(index, Lane(params_)).first;
  return it->second;
}

const OnlineMapper::Lane& OnlineMapper::lane(std::size_t index) const
{
  return lanes_.at(index);
}

double OnlineMapper::newestKeyframeStamp(std::size_t lane) const
{
  double newest = -INFINITY;
  for (const double stamp : this->lane(lane).keyframe_stamps) newest = std::max(newest, stamp);
  return newest;
}

bool OnlineMapper::merge(std::size_t lane, double stamp, const linemap::Pose2& laser,
                         const linemap::Pose2& continuous, const linemap::Pose2& mount,
                         const std::vector<linemap::Segment2>& segments,
                         const std::shared_ptr<const KeyframeScan>& beams)
{
  Keyframe keyframe;
  keyframe.index = next_index_;
  keyframe.stamp = stamp;
  keyframe.pose = laser;
  keyframe.mount = mount;
  keyframe.segments = segments;
  const auto t0 = std::chrono::steady_clock::now();
  AddResult result;
  try
  {
    result = merger_->addKeyframe(keyframe);
  }
  catch (const std::exception&)
  {
    ++counters_.dropped;
    return false;
  }
  counters_.last_otm_ms = linemap::millisecondsSince(t0);
  counters_.bad_segments += result.rejected;
  counters_.retired += result.retired;
  ++counters_.keyframes_added;
  if (map_level_ && beams) map_level_->addKeyframe(keyframe.index, *beams, segments);
  continuous_[keyframe.index] = continuous;
  lane_of_[keyframe.index] = lane;
  this->lane(lane).keyframe_stamps.insert(stamp);
  keyframe_order_.push_back(stamp);
  ++next_index_;
  afterMapChange();
  if (map_level_ && params_.map_level.every_keyframes > 0 &&
      ++keyframes_since_map_level_ >= params_.map_level.every_keyframes)
    extractMapLevel();
  return true;
}

bool OnlineMapper::mergeNodes(std::size_t lane, std::vector<NodeKeyframes<HeldScan>::Ready> ready)
{
  Lane& l = this->lane(lane);
  bool merged = false;
  for (auto& r : ready)
  {
    if (l.keyframe_stamps.count(r.stamp)) continue;
    if (!merge(lane, r.stamp, r.pose * r.payload.mount, r.payload.continuous, r.payload.mount,
               r.payload.segments, r.payload.beams))
      continue;
    ++counters_.node_keyframes;
    l.gate.setReference(r.pose);
    merged = true;
  }
  return merged;
}

ScanOutcome OnlineMapper::addScan(const StampedScan& scan)
{
  ++counters_.scans;
  ++counters_.handled;
  if (!(scan.stamp != 0.0) || !std::isfinite(scan.stamp))
  {
    ++counters_.zero_stamps;
    return ScanOutcome::kZeroStamp;
  }
  if (!finite(scan.laser) || !finite(scan.mount) || (scan.odom && !finite(*scan.odom)))
  {
    ++counters_.dropped;
    return ScanOutcome::kRejected;
  }
  Lane& l = lane(scan.lane);
  if (!l.placement)
  {
    holdUnplaced(l, scan);
    return ScanOutcome::kHeld;
  }
  StampedScan placed = scan;
  placed.laser = *l.placement * scan.laser;
  return addPlacedScan(placed);
}

void OnlineMapper::holdUnplaced(Lane& l, const StampedScan& scan)
{
  l.unplaced.push_back(scan);
  const double horizon = scan.stamp - params_.keyframe_buffer;
  const auto kept = std::find_if(l.unplaced.begin(), l.unplaced.end(),
                                 [&](const StampedScan& s) { return s.stamp >= horizon; });
  counters_.unplaced_dropped += static_cast<std::size_t>(kept - l.unplaced.begin());
  l.unplaced.erase(l.unplaced.begin(), kept);
}

ScanOutcome OnlineMapper::addPlacedScan(const StampedScan& scan)
{
  Lane& l = lane(scan.lane);
  const linemap::Pose2 laser_to_base = scan.mount.inverse();
  const linemap::Pose2 base = scan.laser * laser_to_base;
  // A scan with the stamp of a keyframe is that keyframe again (a bag replayed with --loop):
  // merging it twice would only add duplicate leaves. The gate moves on from it as from a
  // keyframe, so a replay takes no keyframes in between.
  if (l.keyframe_stamps.count(scan.stamp))
  {
    ++counters_.replayed;
    l.gate.setReference(base);
    return ScanOutcome::kReplayed;
  }
  // Every scan, keyframe or not, may be a node of the back end's trajectory.
  const linemap::Pose2 continuous = scan.odom ? *scan.odom : scan.laser;
  l.history.add(scan.stamp, continuous * laser_to_base);
  if (params_.keyframe_source != KeyframeSource::kTf)
  {
    // Held for the trajectory that may name it a node (before the first one too: its nodes after
    // the newest keyframe are among these scans).
    const bool merged = mergeNodes(
        scan.lane, l.nodes.addScan(scan.stamp, {continuous, scan.mount, scan.segments, scan.beams}));
    if (l.nodes.active()) return merged ? ScanOutcome::kKeyframe : ScanOutcome::kHeld;
  }
  if (!l.gate.wouldAccept(base))
  {
    ++counters_.below_gate;
    return ScanOutcome::kBelowGate;
  }
  if (!merge(scan.lane, scan.stamp, scan.laser, continuous, scan.mount, scan.segments, scan.beams))
    return ScanOutcome::kRejected;
  l.gate.accept(base);
  return ScanOutcome::kKeyframe;
}

bool OnlineMapper::addTrajectory(const std::vector<StampedPose>& base_poses, std::size_t lane)
{
  ++counters_.trajectories;
  std::vector<StampedPose> nodes;
  nodes.reserve(base_poses.size());
  for (const auto& node : base_poses)
  {
    if (std::isfinite(node.first) && finite(node.second))
      nodes.push_back(node);
    else
      ++counters_.bad_poses;
  }
  if (nodes.empty())
  {
    ++counters_.ignored_trajectories;
    return false;
  }
  Lane& l = this->lane(lane);
  if (!l.placement)
  {
    l.unplaced_trajectory = std::move(nodes);
    return false;
  }
  for (auto& node : nodes) node.second = *l.placement * node.second;
  return addPlacedTrajectory(std::move(nodes), lane);
}

bool OnlineMapper::addPlacedTrajectory(std::vector<StampedPose> nodes, std::size_t lane)
{
  Lane& l = this->lane(lane);
  // A back end is present: its nodes choose the keyframes (NodeKeyframes' policy).
  const bool names_scans =
      params_.keyframe_source != KeyframeSource::kTf && !l.nodes.active() &&
      std::any_of(nodes.begin(), nodes.end(),
                  [&](const StampedPose& n)
                  { return l.history.at(n.first, params_.stamp_tolerance, 0.0).has_value(); });
  // The map is made again from the nodes only when it holds this lane's keyframes alone.
  const bool alone =
      std::all_of(lane_of_.begin(), lane_of_.end(), [&](const auto& entry) { return entry.second == lane; });
  std::optional<double> oldest;
  for (const double stamp : l.keyframe_stamps) oldest = std::min(oldest.value_or(INFINITY), stamp);
  const bool rebuilt = alone && l.nodes.rebuildAtFirstTrajectory(names_scans, oldest);
  if (rebuilt)
  {
    clearKeyframes();
    ++counters_.rebuilds;
  }
  const bool adjusted = adjustTo(lane, nodes);
  if (params_.keyframe_source == KeyframeSource::kTf) return adjusted;
  l.nodes.takeOver(names_scans, newestKeyframeStamp(lane), l.gate.reference());
  if (!l.nodes.active()) return adjusted;
  const bool merged = mergeNodes(lane, l.nodes.addTrajectory(nodes));
  return merged || adjusted || rebuilt;
}

bool OnlineMapper::placeLane(std::size_t lane, const linemap::Pose2& lane_in_map)
{
  if (!finite(lane_in_map)) throw std::invalid_argument("OnlineMapper::placeLane: a non-finite placement");
  Lane& l = this->lane(lane);
  if (l.placement)
  {
    // Placed again: its keyframes move by the change, the rest of the map stays.
    const linemap::Pose2 change = lane_in_map * l.placement->inverse();
    l.placement = lane_in_map;
    std::vector<std::pair<std::uint64_t, linemap::Pose2>> poses;
    for (const KeyframeInfo& k : merger_->keyframes())
      if (lane_of_.count(k.index) && lane_of_.at(k.index) == lane)
        poses.emplace_back(k.index, change * k.pose);
    if (poses.empty()) return false;
    merger_->adjust(poses);
    ++counters_.adjustments;
    afterMapChange();
    return true;
  }
  l.placement = lane_in_map;
  std::vector<StampedScan> waiting = std::move(l.unplaced);
  l.unplaced.clear();
  std::optional<std::vector<StampedPose>> trajectory = std::move(l.unplaced_trajectory);
  l.unplaced_trajectory.reset();
  bool changed = false;
  for (StampedScan& scan : waiting)
  {
    scan.laser = lane_in_map * scan.laser;
    changed = addPlacedScan(scan) == ScanOutcome::kKeyframe || changed;
  }
  if (trajectory)
  {
    for (auto& node : *trajectory) node.second = lane_in_map * node.second;
    changed = addPlacedTrajectory(std::move(*trajectory), lane) || changed;
  }
  return changed;
}

std::optional<linemap::Pose2> OnlineMapper::lanePlacement(std::size_t lane) const
{
  const auto it = lanes_.find(lane);
  return it == lanes_.end() ? std::nullopt : it->second.placement;
}

bool OnlineMapper::adjustTo(std::size_t lane, const std::vector<StampedPose>& nodes)
{
  Lane& l = this->lane(lane);
  const NodeCorrections nc = nodeCorrections(l.history, nodes, params_.stamp_tolerance, params_.max_gap);
  counters_.unmatched_poses += nc.unmatched;
  if (nc.corrections.empty() || merger_->keyframeCount() == 0) return false;

  std::vector<KeyframeInfo> keyframes = merger_->keyframes();
  keyframes.erase(std::remove_if(keyframes.begin(), keyframes.end(),
                                 [&](const KeyframeInfo& k)
                                 {
                                   const auto it = lane_of_.find(k.index);
                                   return (it == lane_of_.end() ? 0 : it->second) != lane;
                                 }),
                  keyframes.end());
  if (keyframes.empty()) return false;
  std::vector<std::pair<std::uint64_t, linemap::Pose2>> poses;
  poses.reserve(keyframes.size());
  for (const KeyframeInfo& k : keyframes)
  {
    const auto it = continuous_.find(k.index);
    const linemap::Pose2& continuous = it != continuous_.end() ? it->second : k.pose;
    poses.emplace_back(k.index, correctionAt(nc.corrections, k.stamp, params_.correction) * continuous);
  }
  const auto t0 = std::chrono::steady_clock::now();
  try
  {
    merger_->adjust(poses);
  }
  catch (const std::exception&)
  {
    ++counters_.adjustment_failures;
    return false;
  }
  counters_.last_gma_ms = linemap::millisecondsSince(t0);
  ++counters_.adjustments;
  // The gate measures motion from the lane's last keyframe where it now is.
  const auto last =
      std::max_element(keyframes.begin(), keyframes.end(),
                       [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.index < b.index; });
  for (const auto& [index, pose] : poses)
    if (index == last->index) l.gate.setReference(pose * last->mount.inverse());
  afterMapChange();
  extractMapLevel();
  return true;
}

bool OnlineMapper::extractMapLevel()
{
  if (!map_level_ || map_level_->keyframes() == 0) return false;
  keyframes_since_map_level_ = 0;
  ++counters_.map_level_passes;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<linemap::Segment2> lines;
  const std::vector<KeyframeOriginals> found =
      map_level_->extract(merger_->keyframes(), merger_->map(), &lines);
  counters_.map_level_lines += lines.size();
  std::size_t merged = 0;
  for (const KeyframeOriginals& k : found)
  {
    const AddResult result = merger_->addOriginals(k.keyframe, k.segments);
    merged += result.merged;
    counters_.bad_segments += result.rejected;
  }
  counters_.map_level_originals += merged;
  counters_.map_level_ms += linemap::millisecondsSince(t0);
  if (merged == 0) return false;
  afterMapChange();
  return true;
}

bool OnlineMapper::observeTime(double clock, double stamp)
{
  if (!time_jumps_.observe(clock, stamp)) return false;
  ++counters_.time_jumps;
  for (auto& [index, l] : lanes_) l.gate.reset();
  return true;
}

void OnlineMapper::clearKeyframes()
{
  merger_->reset();
  if (map_level_) map_level_->clear();
  keyframes_since_map_level_ = 0;
  continuous_.clear();
  lane_of_.clear();
  for (auto& [index, l] : lanes_) l.keyframe_stamps.clear();
  keyframe_order_.clear();
  next_index_ = 0;
  afterMapChange();
}

void OnlineMapper::reset()
{
  clearKeyframes();
  const double last_stamp = time_jumps_.lastStamp();
  for (auto& [index, l] : lanes_)
  {
    l.gate.reset();
    l.nodes.clear(last_stamp > 0.0 ? last_stamp : -INFINITY);  // no node of the past is waited for
    l.history.clear();
    l.unplaced.clear();
    l.unplaced_trajectory.reset();
  }
}

void OnlineMapper::load(const std::string& path)
{
  merger_->load(path);
  adoptLoadedMap();
}

void OnlineMapper::loadText(const std::string& text, const std::string& origin)
{
  merger_->loadText(text, origin);
  adoptLoadedMap();
}

std::size_t OnlineMapper::appendText(const std::string& text, const std::string& origin,
                                     const linemap::Pose2& placed)
{
  std::unique_ptr<Merger> saved = merger_->clone();
  if (!saved || !merger_->hasProvenance())
    throw MapFileError(origin + ": the " + merger_->name() +
                       " merger keeps no original segments, so a saved map cannot be merged into its map");
  saved->reset();
  saved->loadText(text, origin);  // throws before this map changes
  std::unordered_map<std::uint64_t, std::vector<linemap::Segment2>> originals;
  for (const MapSegment& s : saved->map())
    for (const Leaf& leaf : saved->leaves(s.id)) originals[leaf.keyframe].push_back(leaf.segment);
  std::vector<KeyframeInfo> keyframes = saved->keyframes();
  std::sort(keyframes.begin(), keyframes.end(),
            [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.stamp < b.stamp; });
  Lane& l = lane(0);
  std::size_t added = 0;
  for (const KeyframeInfo& k : keyframes)
  {
    if (l.keyframe_stamps.count(k.stamp)) continue;
    const linemap::Pose2 laser = placed * k.pose;
    if (!merge(0, k.stamp, laser, laser, k.mount, originals[k.index])) continue;
    l.history.add(k.stamp, laser * k.mount.inverse());
    ++added;
  }
  return added;
}

void OnlineMapper::adoptLoadedMap()
{
  // The loaded keyframes are lane 0's: a saved map keeps no robots apart.
  for (auto& [index, l] : lanes_)
  {
    l.gate.reset();
    l.history.clear();
    l.keyframe_stamps.clear();
  }
  continuous_.clear();
  lane_of_.clear();
  keyframe_order_.clear();
  next_index_ = 0;
  Lane& l = lane(0);
  for (const KeyframeInfo& k : merger_->keyframes())
  {
    next_index_ = std::max(next_index_, k.index + 1);
    l.keyframe_stamps.insert(k.stamp);
    keyframe_order_.push_back(k.stamp);
    l.history.add(k.stamp, k.pose * k.mount.inverse());
    continuous_[k.index] = k.pose;
    lane_of_[k.index] = 0;
  }
  l.nodes.clear(newestKeyframeStamp(0));
  afterMapChange();
}

std::shared_ptr<const Merger> OnlineMapper::snapshot() const
{
  // The online mergers hold plain containers: a copy is a consistent snapshot, taken in
  // milliseconds, where writing the file (fsync) takes tens.
  return merger_->clone();
}

OnlineMapper::OnlineMapper(const OnlineMapper& other, std::unique_ptr<Merger> merger)
    : merger_(std::move(merger)),
      params_(other.params_),
      map_level_(other.map_level_),
      keyframes_since_map_level_(other.keyframes_since_map_level_),
      lanes_(other.lanes_),
      continuous_(other.continuous_),
      lane_of_(other.lane_of_),
      keyframe_order_(other.keyframe_order_),
      next_index_(other.next_index_),
      time_jumps_(other.time_jumps_),
      revision_(other.revision_),
      saved_revision_(other.saved_revision_),
      last_save_(other.last_save_),
      counters_(other.counters_)
{
}

std::unique_ptr<OnlineMapper> OnlineMapper::clone() const
{
  std::unique_ptr<Merger> merger = merger_->clone();
  if (!merger) return nullptr;
  return std::unique_ptr<OnlineMapper>(new OnlineMapper(*this, std::move(merger)));
}

void OnlineMapper::adoptAutosave(OnlineMapper& previous)
{
  if (writer_.valid()) writer_.wait();
  writer_ = std::move(previous.writer_);
  writing_revision_ = previous.writing_revision_;
  writing_since_ = previous.writing_since_;
  last_save_ = previous.last_save_;
  saved_revision_ = previous.saved_revision_;
  // Revisions of both count on from the same one: above both, this map differs from any saved.
  revision_ = std::max(revision_, previous.revision_) + 1;
  counters_.autosaves = previous.counters_.autosaves;
  counters_.autosave_failures = previous.counters_.autosave_failures;
}

OnlineMapper::~OnlineMapper()
{
  if (writer_.valid()) writer_.wait();
}

std::string OnlineMapper::collectAutosave(bool wait)
{
  if (!writer_.valid() || (!wait && writer_.wait_for(std::chrono::seconds(0)) != std::future_status::ready))
    return "";
  const std::string error = writer_.get();
  autosaved(writing_revision_, writing_since_, error.empty());
  return error;
}

std::string OnlineMapper::autosave(const std::string& path, double now, bool wait)
{
  std::string error = collectAutosave(wait);
  if (writer_.valid() || !autosaveDue(now)) return error;
  writing_revision_ = revision_;
  writing_since_ = now;
  auto write = [path](std::shared_ptr<const Merger> merger) -> std::string
  {
    try
    {
      merger->save(path);
      return "";
    }
    catch (const std::exception& e)
    {
      return e.what();
    }
  };
  std::shared_ptr<const Merger> copy = snapshot();
  if (copy && !wait)
  {
    writer_ = std::async(std::launch::async, write, std::move(copy));
    return error;
  }
  // No copy: written from the live merger (not owned, so a no-op deleter), before returning.
  std::promise<std::string> done;
  done.set_value(write(copy ? copy : std::shared_ptr<const Merger>(merger_.get(), [](const Merger*) {})));
  writer_ = done.get_future();
  const std::string last = collectAutosave(true);
  return last.empty() ? error : last;
}

bool OnlineMapper::autosaveDue(double now) const
{
  return params_.autosave_period > 0.0 && revision_ != saved_revision_ &&
         now - last_save_ >= params_.autosave_period;
}

void OnlineMapper::autosaved(std::uint64_t revision, double now, bool ok)
{
  last_save_ = now;
  if (!ok)
  {
    ++counters_.autosave_failures;
    return;
  }
  saved_revision_ = revision;
  ++counters_.autosaves;
}

std::vector<std::pair<std::string, std::string>> OnlineMapper::diagnostics() const
{
  const MapperCounters& c = counters_;
  auto n = [](std::size_t v) { return std::to_string(v); };
  auto sum = [this](auto of)
  {
    std::size_t total = 0;
    for (const auto& [index, l] : lanes_) total += of(l);
    return total;
  };
  return {
      {"method", merger_->name()},
      {"keyframes", n(merger_->keyframeCount())},
      {"leaves", n(merger_->leafCount())},
      {"map segments", n(merger_->segmentCount())},
      {"last OTM time [ms]", text(c.last_otm_ms)},
      {"last GMA time [ms]", text(c.last_gma_ms)},
      {"scans", n(c.scans)},
      {"segment sets handled", n(c.handled)},
      {"trajectories", n(c.trajectories)},
      {"adjustments", n(c.adjustments)},
      {"failed adjustments", n(c.adjustment_failures)},
      {"dropped scans", n(c.dropped)},
      {"scans below the keyframe gate", n(c.below_gate)},
      {"keyframes chosen by", nodesChoose() ? "trajectory nodes" : "keyframe gate (tf)"},
      {"node keyframes", n(c.node_keyframes)},
      {"maps rebuilt from the nodes", n(c.rebuilds)},
      {"scans held for a trajectory", n(sum([](const Lane& l) { return l.nodes.held(); }))},
      {"nodes waiting for their scan", n(sum([](const Lane& l) { return l.nodes.waiting(); }))},
      {"nodes without a scan", n(sum([](const Lane& l) { return l.nodes.unmatched(); }))},
      {"robots", n(lanes_.size())},
      {"robots not placed yet", n(sum([](const Lane& l) -> std::size_t { return l.placement ? 0 : 1; }))},
      {"scans waiting for their robot's placement", n(sum([](const Lane& l) { return l.unplaced.size(); }))},
      {"scans of unplaced robots forgotten", n(c.unplaced_dropped)},
      {"originals retired (seen through)", n(c.retired)},
      {"map-level passes", n(c.map_level_passes)},
      {"map-level lines", n(c.map_level_lines)},
      {"map-level originals", n(c.map_level_originals)},
      {"map-level time [ms]", text(c.map_level_ms)},
      {"bad segments", n(c.bad_segments)},
      {"bad trajectory poses", n(c.bad_poses)},
      {"unmatched trajectory poses", n(c.unmatched_poses)},
      {"ignored trajectories", n(c.ignored_trajectories)},
      {"zero-stamp segments", n(c.zero_stamps)},
      {"replayed scans skipped", n(c.replayed)},
      {"time jumps", n(c.time_jumps)},
      {"autosaves", n(c.autosaves)},
      {"autosave failures", n(c.autosave_failures)}};
}

}  // namespace line_map_merging
