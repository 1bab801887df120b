#include "line_map_merging/online_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <sstream>

#include "line_map_merging/cae_rlsm.hpp"
#include "line_map_merging/oto_ilsm.hpp"

namespace line_map_merging
{
namespace
{
double nonNegative(const linemap::ParamSet& params, const std::string& key, double fallback)
{
  const double value = params.getDouble(key, fallback);
  if (!std::isfinite(value) || value < 0.0)
    throw linemap::ParameterError("parameter '" + key + "' must be finite and >= 0, got " +
                                  std::to_string(value));
  return value;
}

bool finite(const linemap::Pose2& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
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
  p.stamp_tolerance = nonNegative(params, "stamp_tolerance", p.stamp_tolerance);
  p.max_gap = nonNegative(params, "trajectory_max_gap", p.max_gap);
  p.time_jump_tolerance = nonNegative(params, "time_jump_tolerance", p.time_jump_tolerance);
  p.autosave_period = nonNegative(params, "autosave_period", p.autosave_period);
  p.correction =
      correctionModeFromString("trajectory_correction", params.getString("trajectory_correction", "nearest"));
  return p;
}

OnlineMapper::OnlineMapper(std::unique_ptr<Merger> merger, const OnlineMapperParams& params)
    : merger_(std::move(merger)), params_(params), gate_(params.gate)
{
  if (!merger_) throw std::invalid_argument("OnlineMapper: no merger");
}

ScanOutcome OnlineMapper::addScan(const StampedScan& scan)
{
  ++counters_.scans;
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
  const linemap::Pose2 base = scan.laser * scan.mount.inverse();
  // A scan with the stamp of a keyframe is that keyframe again (a bag replayed with --loop):
  // merging it twice would only add duplicate leaves. The gate moves on from it as from a
  // keyframe, so a replay takes no keyframes in between.
  if (keyframe_stamps_.count(scan.stamp))
  {
    ++counters_.replayed;
    gate_.setReference(base);
    return ScanOutcome::kReplayed;
  }
  // Every scan, keyframe or not, may be a node of the back end's trajectory.
  const linemap::Pose2 continuous = scan.odom ? *scan.odom : scan.laser;
  history_.add(scan.stamp, continuous * scan.mount.inverse());
  if (!gate_.wouldAccept(base))
  {
    ++counters_.below_gate;
    return ScanOutcome::kBelowGate;
  }
  Keyframe keyframe;
  keyframe.index = next_index_;
  keyframe.stamp = scan.stamp;
  keyframe.pose = scan.laser;
  keyframe.mount = scan.mount;
  keyframe.segments = scan.segments;
  const auto t0 = std::chrono::steady_clock::now();
  AddResult result;
  try
  {
    result = merger_->addKeyframe(keyframe);
  }
  catch (const std::exception&)
  {
    ++counters_.dropped;
    return ScanOutcome::kRejected;
  }
  counters_.last_otm_ms = msSince(t0);
  counters_.bad_segments += result.rejected;
  ++counters_.keyframes_added;
  continuous_[keyframe.index] = continuous;
  keyframe_stamps_.insert(scan.stamp);
  keyframe_order_.push_back(scan.stamp);
  ++next_index_;
  gate_.accept(base);
  afterMapChange();
  return ScanOutcome::kKeyframe;
}

bool OnlineMapper::addTrajectory(const std::vector<StampedPose>& base_poses)
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
  const NodeCorrections nc = nodeCorrections(history_, nodes, params_.stamp_tolerance, params_.max_gap);
  counters_.unmatched_poses += nc.unmatched;
  if (nc.corrections.empty() || merger_->keyframeCount() == 0) return false;

  const std::vector<KeyframeInfo> keyframes = merger_->keyframes();
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
  counters_.last_gma_ms = msSince(t0);
  ++counters_.adjustments;
  // The gate measures motion from the last keyframe where it now is.
  const auto last =
      std::max_element(keyframes.begin(), keyframes.end(),
                       [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.index < b.index; });
  for (const auto& [index, pose] : poses)
    if (index == last->index) gate_.setReference(pose * last->mount.inverse());
  afterMapChange();
  return true;
}

bool OnlineMapper::observeTime(double clock, double stamp)
{
  const double tol = params_.time_jump_tolerance;
  const bool clock_back = last_clock_ > 0.0 && clock > 0.0 && last_clock_ - clock > tol;
  const bool stamp_back = last_stamp_ > 0.0 && stamp > 0.0 && last_stamp_ - stamp > tol;
  if (clock_back || stamp_back)
  {
    ++counters_.time_jumps;
    gate_.reset();
    last_stamp_ = 0.0;
  }
  if (clock > 0.0) last_clock_ = clock;
  if (stamp > 0.0) last_stamp_ = std::max(last_stamp_, stamp);
  return clock_back || stamp_back;
}

void OnlineMapper::reset()
{
  merger_->reset();
  gate_.reset();
  history_.clear();
  continuous_.clear();
  keyframe_stamps_.clear();
  keyframe_order_.clear();
  next_index_ = 0;
  afterMapChange();
}

void OnlineMapper::load(const std::string& path)
{
  merger_->load(path);
  gate_.reset();
  history_.clear();
  continuous_.clear();
  keyframe_stamps_.clear();
  keyframe_order_.clear();
  next_index_ = 0;
  for (const KeyframeInfo& k : merger_->keyframes())
  {
    next_index_ = std::max(next_index_, k.index + 1);
    keyframe_stamps_.insert(k.stamp);
    keyframe_order_.push_back(k.stamp);
    history_.add(k.stamp, k.pose * k.mount.inverse());
    continuous_[k.index] = k.pose;
  }
  afterMapChange();
}

std::shared_ptr<const Merger> OnlineMapper::snapshot() const
{
  // The online mergers hold plain containers: a copy is a consistent snapshot, taken in
  // milliseconds, where writing the file (fsync) takes tens.
  if (const auto* cae = dynamic_cast<const CaeRlsm*>(merger_.get())) return std::make_shared<CaeRlsm>(*cae);
  if (const auto* oto = dynamic_cast<const OtoIlsm*>(merger_.get())) return std::make_shared<OtoIlsm>(*oto);
  return nullptr;
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
  return {{"method", merger_->name()},
          {"keyframes", n(merger_->keyframeCount())},
          {"leaves", n(merger_->leafCount())},
          {"map segments", n(merger_->segmentCount())},
          {"last OTM time [ms]", text(c.last_otm_ms)},
          {"last GMA time [ms]", text(c.last_gma_ms)},
          {"scans", n(c.scans)},
          {"adjustments", n(c.adjustments)},
          {"failed adjustments", n(c.adjustment_failures)},
          {"dropped scans", n(c.dropped)},
          {"scans below the keyframe gate", n(c.below_gate)},
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
