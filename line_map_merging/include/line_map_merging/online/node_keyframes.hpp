// Keyframes chosen by a SLAM back end: once a trajectory has been received, the scans whose stamps are
// nodes of it become keyframes, posed by their node, and no other scan does. A keyframe between two
// nodes has no pose of its own and must be corrected from its neighbours (trajectory_anchor.hpp); on
// a real log that correction costs map quality against the keyframes at their own corrected poses.
// So recent scans are held (by stamp, bounded in time) until the
// trajectory tells which of them are nodes; a node whose scan has not arrived yet waits for it, so
// the result does not depend on whether a trajectory or the scans of its nodes come first.
// Header-only: the merger holds segment sets, the evaluator scan points and segment sets.
#pragma once

#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/online/keyframe_gate.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
/// Who chooses the keyframes.
enum class KeyframeSource
{
  kAuto,        ///< the keyframe gate on tf until the first trajectory, the trajectory's nodes from then on
  kTf,          ///< always the keyframe gate on tf; trajectories only adjust
  kTrajectory,  ///< only the trajectory's nodes (nothing is merged before the first trajectory)
};

/// "auto", "tf" or "trajectory"; throws linemap::ParameterError naming `key` otherwise.
inline KeyframeSource keyframeSourceFromString(const std::string& key, const std::string& value)
{
  if (value == "auto") return KeyframeSource::kAuto;
  if (value == "tf") return KeyframeSource::kTf;
  if (value == "trajectory") return KeyframeSource::kTrajectory;
  throw linemap::ParameterError("parameter '" + key + "': expected 'auto', 'tf' or 'trajectory', got '" +
                                value + "'");
}

template <class Payload>
class NodeKeyframes
{
 public:
  /// A scan that became a keyframe: its stamp, the pose of its node (as given) and what was held.
  struct Ready
  {
    double stamp = 0.0;
    linemap::Pose2 pose;
    Payload payload;
  };

  /// `tolerance`: node <-> scan stamp [s]; `buffer`: how long a scan is held for a trajectory [s]
  /// (scan time). The gate thins the nodes on their poses as the tf gate thins scans.
  NodeKeyframes(const KeyframeGateParams& gate, double tolerance, double buffer)
      : gate_(gate), tolerance_(tolerance), buffer_duration_(buffer)
  {
  }

  /// Whether the nodes choose the keyframes (after activate()).
  bool active() const { return active_; }
  /// From now on the nodes choose: nodes stamped at or before `horizon` are done (keyframes exist up
  /// to there), and the gate measures from `reference` (the newest keyframe), when given.
  void activate(double horizon, const std::optional<linemap::Pose2>& reference)
  {
    active_ = true;
    horizon_ = std::max(horizon_, horizon);
    if (reference) gate_.setReference(*reference);
    prune();
  }

  /// A scan that is not a keyframe (yet). Held for a later trajectory when newer than the horizon; a
  /// node waiting for it makes it a keyframe at once (returned, with any later nodes it unblocked).
  std::vector<Ready> addScan(double stamp, Payload payload)
  {
    if (!std::isfinite(stamp) || stamp <= horizon_) return {};  // done with (e.g. a replayed scan)
    newest_scan_ = std::max(newest_scan_, stamp);
    buffer_.emplace(stamp, std::move(payload));
    return drain();
  }

  /// The nodes (stamp, pose) of a trajectory: those after the horizon, in stamp order, take their
  /// held scans through the gate. The poses of a later trajectory replace those of nodes still waiting.
  std::vector<Ready> addTrajectory(const std::vector<std::pair<double, linemap::Pose2>>& nodes)
  {
    if (!active_) return {};
    waiting_.clear();
    for (const auto& [stamp, pose] : nodes)
      if (std::isfinite(stamp) && stamp > horizon_) waiting_[stamp] = pose;
    return drain();
  }

  /// Forgets held scans and waiting nodes; nodes up to `horizon` count as done.
  void clear(double horizon)
  {
    buffer_.clear();
    waiting_.clear();
    horizon_ = horizon;
    gate_.reset();
  }

  std::size_t held() const { return buffer_.size(); }
  /// Stamp of the oldest scan held (infinite when none): whether the scans since then are all held.
  double oldestHeld() const { return buffer_.empty() ? INFINITY : buffer_.begin()->first; }

  // The policy at a back end's trajectory, one for every store of keyframes (the merger's keyframes,
  // the evaluator's scans and segment sets). Only a trajectory that names scans seen (`names_scans`)
  // hands the choice to the nodes: one before any scan, or of another sensor's stamps, would leave
  // the scans held for nodes that never come.

  /// At the first such trajectory, when every scan since the store's oldest keyframe
  /// (`oldest_stored`, nothing for an empty store) is still held, the store is made again from the
  /// nodes alone, so that no keyframe is corrected between nodes: true when the caller is to empty
  /// its store; the nodes then choose from the start.
  bool rebuildAtFirstTrajectory(bool names_scans, const std::optional<double>& oldest_stored)
  {
    if (active_ || !names_scans || !oldest_stored || oldestHeld() > *oldest_stored) return false;
    activate(-INFINITY, std::nullopt);
    return true;
  }
  /// Otherwise the nodes take over after the store's newest keyframe (`newest_stored`, -inf for
  /// none), their gate measuring from `reference`.
  void takeOver(bool names_scans, double newest_stored, const std::optional<linemap::Pose2>& reference)
  {
    if (!active_ && names_scans) activate(newest_stored, reference);
  }
  std::size_t waiting() const { return waiting_.size(); }
  std::size_t unmatched() const { return unmatched_; }  ///< nodes whose scan never came
  std::size_t gated() const { return gated_; }          ///< nodes the gate thinned out
  double horizon() const { return horizon_; }

 private:
  std::vector<Ready> drain()
  {
    std::vector<Ready> ready;
    while (active_ && !waiting_.empty())
    {
      const auto node = waiting_.begin();
      const double t = node->first;
      // The nearest held scan; a nearer one may still come until a scan past t + tolerance did.
      const auto after = buffer_.lower_bound(t);
      auto best = buffer_.end();
      double best_dt = INFINITY;
      if (after != buffer_.end())
      {
        best = after;
        best_dt = after->first - t;
      }
      if (after != buffer_.begin() && t - std::prev(after)->first < best_dt)
      {
        best = std::prev(after);
        best_dt = t - best->first;
      }
      if (best_dt > 0.0 && newest_scan_ < t + tolerance_) break;  // wait for the scans to catch up
      if (best == buffer_.end() || best_dt > tolerance_)
      {
        ++unmatched_;
        horizon_ = std::max(horizon_, t);
      }
      else
      {
        horizon_ = std::max(horizon_, std::max(t, best->first));
        if (gate_.accept(node->second))
          ready.push_back({best->first, node->second, std::move(best->second)});
        else
          ++gated_;
        buffer_.erase(best);
      }
      waiting_.erase(node);
    }
    prune();
    return ready;
  }

  void prune()
  {
    // Scans at or before the horizon can no longer become keyframes; older than the buffer, neither.
    const double oldest = std::max(horizon_, newest_scan_ - buffer_duration_);
    buffer_.erase(buffer_.begin(), buffer_.upper_bound(oldest));
  }

  KeyframeGate gate_;
  double tolerance_, buffer_duration_;
  bool active_ = false;
  double horizon_ = -std::numeric_limits<double>::infinity();
  double newest_scan_ = -std::numeric_limits<double>::infinity();
  std::map<double, Payload> buffer_;
  std::map<double, linemap::Pose2> waiting_;
  std::size_t unmatched_ = 0, gated_ = 0;
};

}  // namespace line_map_merging
