// Turning an optimised trajectory into new keyframe poses: matching poses to keyframes by stamp,
// and correcting keyframes without a pose of their own by the interpolated correction of their
// nearest matched neighbours in time.
//
// Keyframes are registered in the map frame through the back end's map->odom, which jumps each time
// the back end publishes a new estimate (the bags of carmen_to_bag: every N keyframes, by up to 17 m
// and 150 degrees on Intel). The map-frame correction new * old^-1 jumps with it, so interpolating
// it across a jump moves the keyframes before the jump by a blend of two unrelated corrections
// (up to 20 m on the first 4000 Intel scans). Given each keyframe's pose in the odometry frame, the
// correction is interpolated there instead: D = new * odom^-1, the corrected map->odom, which is
// continuous in time.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"

namespace line_map_merging
{
/// Index of the keyframe whose stamp is nearest to `stamp`, if within `tolerance` seconds and
/// nearer to it than to the scans just before and after the keyframe's scan (half its
/// scan_gap_before / scan_gap_after; an exact stamp always matches): a pose of a scan that did
/// not become a keyframe must not move the keyframe next to it, however close their stamps.
/// `keyframes` must be sorted by stamp.
std::optional<std::size_t> matchByStamp(const std::vector<KeyframeInfo>& keyframes, double stamp,
                                        double tolerance);

/// The time from each keyframe's scan to the scans just before and after it, learnt from the
/// stream of every scan (KeyframeInfo::scan_gap_before / scan_gap_after). Stamps that do not
/// increase (time jumped back, a replay) start the stream afresh: their gaps are unknown.
class ScanGapTracker
{
 public:
  /// Every new scan, in arrival order (replayed scans that are skipped are not new).
  void scan(double stamp);
  /// The scan just passed to scan() became keyframe `index`.
  void keyframe(std::uint64_t index);
  /// Sets the gaps of the keyframes it knows (the others keep theirs).
  void fill(std::vector<KeyframeInfo>& keyframes) const;
  void clear();
  std::size_t size() const { return gaps_.size(); }

 private:
  double last_stamp_ = std::numeric_limits<double>::quiet_NaN();
  double last_gap_ = std::numeric_limits<double>::infinity();
  std::optional<std::uint64_t> waiting_;  ///< the last keyframe, until the scan after it
  std::unordered_map<std::uint64_t, std::pair<double, double>> gaps_;
};

/// New laser poses for every keyframe. `matched` maps keyframe index -> new laser pose. A keyframe
/// without a match gets the correction C = new * old^-1 of its nearest matched keyframes before and
/// after it in time, interpolated by stamp (clamped at the ends), applied to its old pose. Empty
/// when nothing matched. `keyframes` must be sorted by stamp.
std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched);

/// The same, interpolating in the odometry frame: `odom` maps keyframe index -> its laser pose in a
/// frame in which the keyframes' poses are continuous in time (tf odom -> laser at its stamp).
/// Matched keyframes give D = new * odom^-1; every other keyframe gets D interpolated by stamp
/// (clamped at the ends) and the new pose D * odom. A keyframe without an odometry pose is taken to
/// have been registered with the map->odom (old * odom^-1) of the nearest keyframe before it that
/// has one (after it, when none before). With an empty `odom` this is the map-frame correction above.
std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched,
    const std::map<std::uint64_t, linemap::Pose2>& odom);

}  // namespace line_map_merging
