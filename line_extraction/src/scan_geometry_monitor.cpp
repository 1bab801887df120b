#include "line_extraction/scan_geometry_monitor.hpp"

#include <cmath>

namespace line_extraction
{
ScanGeometryMonitor::Findings ScanGeometryMonitor::observe(float angle_min, float angle_max,
                                                           float angle_increment, std::size_t count)
{
  Findings found;
  if (count > 1 && std::isfinite(angle_increment) && angle_increment > 0.0f)
  {
    found.expected_angle_max = angle_min + static_cast<double>(count - 1) * angle_increment;
    // Within about one increment: a driver writing angle_min + n * increment is tolerated.
    found.inconsistent_angle_max =
        !(std::abs(angle_max - found.expected_angle_max) <= 1.01 * angle_increment);
  }
  found.changed =
      seen_ && (angle_min != last_angle_min_ || angle_increment != last_increment_ || count != last_count_);
  inconsistent_angle_max_ += found.inconsistent_angle_max ? 1 : 0;
  changes_ += found.changed ? 1 : 0;
  seen_ = true;
  last_angle_min_ = angle_min;
  last_increment_ = angle_increment;
  last_count_ = count;
  return found;
}
}  // namespace line_extraction
