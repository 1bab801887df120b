// Turning an optimised trajectory into new keyframe poses: matching poses to keyframes by stamp,
// and correcting keyframes without a pose of their own by the interpolated correction of their
// nearest matched neighbours in time.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "line_map_merging/merger.hpp"

namespace line_map_merging
{
/// Index of the keyframe whose stamp is nearest to `stamp`, if within `tolerance` seconds.
/// `keyframes` must be sorted by stamp.
std::optional<std::size_t> matchByStamp(const std::vector<KeyframeInfo>& keyframes, double stamp,
                                        double tolerance);

/// New laser poses for every keyframe. `matched` maps keyframe index -> new laser pose. A keyframe
/// without a match gets the correction C = new * old^-1 of its nearest matched keyframes before and
/// after it in time, interpolated by stamp (clamped at the ends), applied to its old pose. Empty
/// when nothing matched. `keyframes` must be sorted by stamp.
std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched);

}  // namespace line_map_merging
