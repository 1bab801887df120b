// What the pipeline does not judge in a scan's beam geometry, watched from scan to scan: angle_max
// disagreeing with angle_min + (n - 1) * angle_increment (the beams are placed by angle_min and
// angle_increment, as REP-117 readers do, so drivers writing n * increment are tolerated), and
// changes of the geometry. ROS-free; the nodelet reports what it finds.
#pragma once

#include <cstddef>

namespace line_extraction
{
class ScanGeometryMonitor
{
 public:
  struct Findings
  {
    bool inconsistent_angle_max = false;
    double expected_angle_max = 0.0;  ///< angle_min + (n - 1) * angle_increment [rad]
    bool changed = false;             ///< another geometry than the previous scan's
  };

  /// One scan's geometry, as its message gives it.
  Findings observe(float angle_min, float angle_max, float angle_increment, std::size_t count);

  std::size_t inconsistentAngleMax() const { return inconsistent_angle_max_; }
  std::size_t changes() const { return changes_; }

 private:
  bool seen_ = false;
  float last_angle_min_ = 0.0f, last_increment_ = 0.0f;
  std::size_t last_count_ = 0;
  std::size_t inconsistent_angle_max_ = 0, changes_ = 0;
};
}  // namespace line_extraction
