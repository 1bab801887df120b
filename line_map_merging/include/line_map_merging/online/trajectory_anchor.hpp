// Anchoring keyframes to the nodes of a SLAM back end's trajectory by relative odometry.
//
// A back end publishes the poses of its own keyframes (nodes), which are rarely the keyframes of the
// merger or the evaluator: matching poses to keyframes by stamp drops every node that is not also one
// of ours (Intel, first 4000 scans: most of them), and the keyframes in between were corrected by
// interpolating over the few that matched. Instead the pose of every scan in the odometry frame is
// kept (one pose per scan), so every node finds its odometry pose at its own stamp and gives the
// corrected map->odom there, D = node * odom^-1. A keyframe takes the D of the node nearest to it in
// time: new = D * odom_k, the node's pose composed with the relative odometry from the node to the
// keyframe, exact at every node and accurate to the odometry drift over the time to the nearest node.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// The pose of one frame (e.g. base_link) at every scan, in a frame where it is continuous in time
/// (odom; without odometry, the map frame).
class OdometryHistory
{
 public:
  /// Records `pose` at `stamp`; a stamp already held keeps its pose (a replay sends the same scans).
  void add(double stamp, const linemap::Pose2& pose);
  /// The pose at `stamp`: the recorded one nearest in time within `tolerance`, else the
  /// interpolation of the recorded poses just before and after it when they are at most `max_gap`
  /// apart; nothing outside the recorded span.
  std::optional<linemap::Pose2> at(double stamp, double tolerance, double max_gap) const;
  void clear() { poses_.clear(); }
  std::size_t size() const { return poses_.size(); }

 private:
  /// By stamp. Scans come in stamp order, so adding is an append, and the binary search of at() runs
  /// over contiguous memory (a tree's nodes scattered in memory cost a cache miss per step).
  std::vector<std::pair<double, linemap::Pose2>> poses_;
};

/// How a keyframe between two trajectory nodes is corrected.
enum class CorrectionMode
{
  kNearest,      ///< the correction of the node nearest in time (relative odometry from that node)
  kInterpolate,  ///< the corrections of the nodes before and after, interpolated by stamp
};

/// "nearest" or "interpolate"; throws linemap::ParameterError naming `key` otherwise.
CorrectionMode correctionModeFromString(const std::string& key, const std::string& value);

/// Corrections of trajectory nodes, in stamp order.
struct NodeCorrections
{
  std::vector<std::pair<double, linemap::Pose2>> corrections;  ///< (stamp, D = node * odom^-1)
  std::size_t unmatched = 0;  ///< nodes whose stamp lies outside the history (or non-finite)
};

/// D of every node `(stamp, pose in map of the history's frame)` found in the history (see
/// OdometryHistory::at); duplicate stamps keep the last node.
NodeCorrections nodeCorrections(const OdometryHistory& history,
                                const std::vector<std::pair<double, linemap::Pose2>>& nodes, double tolerance,
                                double max_gap);

/// The correction at `stamp`; clamped at the ends. `corrections` must be non-empty and sorted.
linemap::Pose2 correctionAt(const std::vector<std::pair<double, linemap::Pose2>>& corrections, double stamp,
                            CorrectionMode mode);

}  // namespace line_map_merging
