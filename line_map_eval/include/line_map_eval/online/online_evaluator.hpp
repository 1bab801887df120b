// The online evaluator (ROS-free): everything the evaluator nodelet does between receiving data and
// publishing metrics. It converts scans to points, keeps the keyframe scans and original segments
// (MapEvaluator: gating, replays, re-registration on a trajectory by anchoring), detects time
// jumping back on either stream, holds the latest map, decides when the metrics are due (a changed
// map or frames, at most every min_period) and counts what the diagnostics show.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_eval/online/map_evaluator.hpp"
#include "linemap/time_jump_detector.hpp"

namespace line_map_eval
{
struct OnlineEvaluatorParams
{
  EvaluatorParams evaluator;
  double min_period = 1.0;           ///< [s] shortest time between two evaluations of a changing map
  double time_jump_tolerance = 1.0;  ///< [s] clock or stamp this much earlier than before = time jumped back

  /// EvaluatorParams' keys plus "min_period" and "time_jump_tolerance"; throws linemap::ParameterError.
  static OnlineEvaluatorParams fromParams(const linemap::ParamSet& params);
};

/// A laser scan's geometry and ranges as received.
struct ScanRanges
{
  double angle_min = 0.0, angle_increment = 0.0, range_min = 0.0, range_max = 0.0;
  std::vector<float> ranges;
};

struct EvaluatorCounters
{
  std::size_t dropped_scans = 0, rejected_scans = 0, rejected_poses = 0, unmatched_poses = 0, time_jumps = 0;
  std::size_t scans = 0, segment_sets = 0, trajectories = 0;  ///< received (posed) by the core
  double last_quality = 0.0, last_eval_ms = 0.0;
  double last_structure_coverage = 0.0, last_unmapped_structure = 0.0;  ///< [%], [m]
  std::size_t last_crossing_pairs = 0;
};

class OnlineEvaluator
{
 public:
  enum Stream
  {
    kScans = 0,
    kSegments = 1,  ///< each stream is monotonic, but segments lag their scans
  };

  explicit OnlineEvaluator(const OnlineEvaluatorParams& params);

  /// The clock reading and a stamp of `stream` (0: not known). True when time jumped back (rosbag
  /// play --loop): the caller drops what it holds of the old time line (tf buffer); the stored
  /// scans are kept (a replay adds none).
  bool observeTime(double clock, double stamp, Stream stream);
  /// What the last time jump observeTime() reported was: the clock or a stamp, from and to.
  const std::string& timeJumpCause() const { return time_jumps_.cause(); }

  /// Stores a keyframe scan (valid ranges as points in the laser frame) taken at `laser` (map
  /// frame); `odom` is the laser in the odometry frame. A geometry without a finite, non-zero
  /// angle increment is rejected and counted. Returns whether the scan was stored.
  bool addScan(double stamp, const ScanRanges& scan, const linemap::Pose2& laser,
               const std::optional<linemap::Pose2>& odom);
  bool addSegments(double stamp, std::vector<linemap::Segment2> segments, const linemap::Pose2& laser,
                   const std::optional<linemap::Pose2>& odom);
  /// Laser poses of the back end's nodes (map frame); non-finite ones are counted and skipped.
  void addTrajectory(const std::vector<std::pair<double, linemap::Pose2>>& laser_poses);
  void setMap(std::vector<linemap::Segment2> map, double stamp);

  /// The metrics of the latest map when they are due at `now` [s]: a map is known, it or the stored
  /// frames changed since the last evaluation, and min_period has passed (or `force`).
  std::optional<MapMetrics> evaluateIfDue(double now, bool force = false);
  /// The metrics of `map` against the current frames (nothing is marked evaluated).
  MapMetrics evaluate(const std::vector<linemap::Segment2>& map);

  void countDroppedScan() { ++counters_.dropped_scans; }
  bool hasMap() const { return have_map_; }
  const std::vector<linemap::Segment2>& map() const { return map_; }
  double mapStamp() const { return map_stamp_; }
  const MapEvaluator& evaluator() const { return evaluator_; }
  const EvaluatorCounters& counters() const { return counters_; }
  /// Every counter of the diagnostics with its label, in display order.
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

  /// The valid ranges of a scan as points in the laser frame (r in [range_min, range_max)).
  static std::vector<linemap::Vec2> scanPoints(const ScanRanges& scan);

 private:
  OnlineEvaluatorParams params_;
  MapEvaluator evaluator_;
  EvaluatorCounters counters_;
  std::vector<linemap::Segment2> map_;
  double map_stamp_ = 0.0;
  bool have_map_ = false, dirty_ = false;
  linemap::TimeJumpDetector time_jumps_;  ///< streams: kScans, kSegments
  double last_evaluation_ = -1e300;
};

}  // namespace line_map_eval
