// What a loop closure's submap looked at (ROS-free): each keyframe's view cone, the bearings and range its
// returns span, and the scan points that fall inside some keyframe's cone. A scan point where no keyframe
// of the submap looked (behind its keyframes, beyond their range) scores as missing wherever the scan is
// placed near it, and pulls the match towards poses that move it into view: the end of a corridor seen
// only by the scan slides the match along the corridor. Such points are left out of the loop match.
#pragma once
#include <utility>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct ViewCone
{
  double min_bearing = 0.0, max_bearing = 0.0;  ///< [rad] of the returns, in the keyframe's frame
  double max_range = 0.0;                       ///< [m]
  bool full_circle = false;                     ///< a laser seeing all around
};

/// The view cone of a keyframe's returns (base frame).
ViewCone viewCone(const std::vector<linemap::Vec2>& points);

/// Of `points` (the submap's frame), those inside the view cone of some keyframe (`views`: its pose in the
/// submap's frame and its cone) widened by `range_margin` [m] in range.
std::vector<bool> inView(const std::vector<linemap::Vec2>& points,
                         const std::vector<std::pair<linemap::Pose2, ViewCone>>& views, double range_margin);

}  // namespace line_map_merging
