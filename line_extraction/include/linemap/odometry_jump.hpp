// Whether odometry between two readings is motion or a jump (a reset, a wrap, a glitch). One policy for
// the SLAM front end and the localizer.
#pragma once

#include <algorithm>
#include <cmath>

#include "linemap/geometry.hpp"

namespace linemap
{
struct OdometryJumpLimits
{
  double step = 0.5;  ///< [m] motion up to this between two readings, however close in time
  double turn = 0.5;  ///< [rad]
  /// [m/s] and up to this speed over the time between them: readings far apart (a log of keyframes, a
  /// pause of the laser) span more motion than one scan period does.
  double speed = 2.0;
  double turn_rate = 2.0;  ///< [rad/s]

  /// `moved` (the odometry's motion from one reading to the next, `elapsed` seconds later) is motion.
  bool isMotion(const Pose2& moved, double elapsed) const
  {
    const double dt = std::isfinite(elapsed) ? std::max(elapsed, 0.0) : 0.0;
    return std::hypot(moved.x, moved.y) <= std::max(step, speed * dt) &&
           std::fabs(moved.theta) <= std::max(turn, turn_rate * dt);
  }
};

}  // namespace linemap
