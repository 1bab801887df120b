// Pairs a robot's segment sets with the scans they came from (the extractor runs in between, and a
// nodelet's callbacks may run in any order): the merger nodelet keeps each keyframe's scan for the
// map-level lines. The sets leave in the order they came, each with its scan, so the map does not
// depend on which callback ran first. ROS-free.
#pragma once

#include <cmath>
#include <cstddef>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include "line_map_merging/online/online_mapper.hpp"

namespace line_map_merging
{
/// `Tag`: what the caller keeps with each segment set (the nodelet: its exact stamp).
template <class Tag>
class ScanPairing
{
 public:
  /// Keeps at most `max_scans` scans; at most `max_waiting` segment sets wait (the oldest then goes
  /// without its scan); a stamp matches within `tolerance` [s].
  explicit ScanPairing(std::size_t max_scans = 200, std::size_t max_waiting = 50, double tolerance = 1e-6)
      : max_scans_(max_scans), max_waiting_(max_waiting), tolerance_(tolerance)
  {
  }

  void addScan(double stamp, std::shared_ptr<const KeyframeScan> scan)
  {
    scans_seen_ = true;
    scans_.emplace_back(stamp, std::move(scan));
    while (scans_.size() > max_scans_) scans_.pop_front();
  }

  void addSegments(StampedScan segments, Tag tag)
  {
    waiting_.emplace_back(std::move(segments), std::move(tag));
  }

  /// The segment sets ready, in the order they came, with their scans (`beams`). A set waits for its
  /// scan until it comes; it goes without when a later scan came first (its own was lost), when no scan
  /// ever came (nothing publishes them), or when too many wait.
  std::vector<std::pair<StampedScan, Tag>> ready()
  {
    std::vector<std::pair<StampedScan, Tag>> out;
    while (!waiting_.empty())
    {
      StampedScan& front = waiting_.front().first;
      while (!scans_.empty() && scans_.front().first < front.stamp - tolerance_) scans_.pop_front();
      const bool found = !scans_.empty() && std::abs(scans_.front().first - front.stamp) <= tolerance_;
      const bool lost = !scans_.empty() && !found;  // the oldest scan kept is later than the set
      if (!found && !lost && scans_seen_ && waiting_.size() <= max_waiting_) break;
      if (found)
      {
        front.beams = std::move(scans_.front().second);
        scans_.pop_front();
      }
      out.push_back(std::move(waiting_.front()));
      waiting_.pop_front();
    }
    return out;
  }

  std::size_t waiting() const { return waiting_.size(); }

 private:
  std::size_t max_scans_, max_waiting_;
  double tolerance_;
  bool scans_seen_ = false;
  std::deque<std::pair<double, std::shared_ptr<const KeyframeScan>>> scans_;
  std::deque<std::pair<StampedScan, Tag>> waiting_;
};

}  // namespace line_map_merging
