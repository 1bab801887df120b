// The last scans of a robot by stamp, for the segment sets that come from them later (the extractor
// runs in between): the merger nodelet keeps each keyframe's scan for the map-level lines. ROS-free.
#pragma once

#include <cmath>
#include <cstddef>
#include <deque>
#include <memory>
#include <utility>

#include "line_map_merging/online/map_level_lines.hpp"

namespace line_map_merging
{
class RecentScans
{
 public:
  /// Keeps at most `capacity` scans; a stamp matches within `tolerance` [s].
  explicit RecentScans(std::size_t capacity = 200, double tolerance = 1e-6)
      : capacity_(capacity), tolerance_(tolerance)
  {
  }

  void add(double stamp, std::shared_ptr<const KeyframeScan> scan)
  {
    scans_.emplace_back(stamp, std::move(scan));
    while (scans_.size() > capacity_) scans_.pop_front();
  }

  /// The scan stamped `stamp` (null when none is kept); it and every older one are forgotten.
  std::shared_ptr<const KeyframeScan> take(double stamp)
  {
    std::shared_ptr<const KeyframeScan> found;
    while (!scans_.empty() && scans_.front().first <= stamp + tolerance_)
    {
      if (std::abs(scans_.front().first - stamp) <= tolerance_) found = std::move(scans_.front().second);
      scans_.pop_front();
    }
    return found;
  }

  std::size_t size() const { return scans_.size(); }

 private:
  std::size_t capacity_;
  double tolerance_;
  std::deque<std::pair<double, std::shared_ptr<const KeyframeScan>>> scans_;
};

}  // namespace line_map_merging
