// The online evaluator behind the evaluator nodelet (ROS-free): keeps the registered
// keyframe scans and original segments, re-registers them when an optimised trajectory
// arrives, and scores a line map against them.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "line_map_eval/metrics/error_metric.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_metrics.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/metrics/map_statistics.hpp"
#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/online/keyframe_gate.hpp"
#include "line_map_merging/online/node_keyframes.hpp"
#include "line_map_merging/online/trajectory_anchor.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
struct EvaluatorParams
{
  line_map_merging::KeyframeGateParams gate;
  double stamp_tolerance = 0.05;  ///< [s] trajectory node <-> scan matching
  double max_gap = 1.0;           ///< [s] a node between two scans at most this far apart is interpolated
  line_map_merging::CorrectionMode correction = line_map_merging::CorrectionMode::kNearest;
  /// Which scans are stored, as the merger chooses its keyframes
  /// (line_map_merging/online/node_keyframes.hpp).
  line_map_merging::KeyframeSource keyframe_source = line_map_merging::KeyframeSource::kAuto;
  double keyframe_buffer = 300.0;  ///< [s] scans held for a trajectory to name them nodes
  LookupTableParams table;
  QualityParams quality;
  line_map_merging::FusionParams fusion;  ///< error assignment, redundant pairs, length coverage
  CoverageParams coverage;

  /// Keys "keyframe_distance", "keyframe_angle", "eval/stamp_tolerance", "trajectory_max_gap",
  /// "trajectory_correction", "keyframe_source", "keyframe_buffer", "eval/...", "fusion/...".
  static EvaluatorParams fromParams(const linemap::ParamSet& params);
};

class MapEvaluator
{
 public:
  explicit MapEvaluator(const EvaluatorParams& params);

  /// Stores a scan's valid points (laser frame) taken at `laser_pose` (laser in map) when the
  /// keyframe gate admits it and no stored scan has the same stamp (a bag replayed with --loop
  /// sends the same scans again: keeping them twice would only grow memory); returns whether it
  /// was stored. A scan older than the newest stored one (a replay, or a scan that arrived late) is
  /// stored only where the stored scans leave a gap: the gate must admit it after the stored scan
  /// before it and before the one after it, so a replay adds no scans. `odom_pose` is the laser in the
  /// odometry frame at the same stamp, when known: re-registration then interpolates corrections
  /// in the odometry frame, across the jumps of map->odom (line_map_merging::correctKeyframes).
  bool addScan(double stamp, const linemap::Pose2& laser_pose, std::vector<linemap::Vec2> points,
               const std::optional<linemap::Pose2>& odom_pose = std::nullopt);
  /// Stores the original segments (laser frame) of a scan, gated and deduplicated like the scans.
  bool addSegments(double stamp, const linemap::Pose2& laser_pose, std::vector<linemap::Segment2> segments,
                   const std::optional<linemap::Pose2>& odom_pose = std::nullopt);

  /// Re-registers every stored frame on a trajectory of laser poses (map frame) at any stamps: as
  /// the merger does (line_map_merging/online/trajectory_anchor.hpp), each node found among the scans and
  /// segment sets seen gives the corrected map->odom there, and every frame takes that of its nearest
  /// node (or the interpolation). Then, unless keyframe_source is tf, the nodes newer than the stored
  /// frames store their held scans and segment sets at the nodes' poses, through the keyframe gate,
  /// as the merger takes them as keyframes. Returns how many trajectory poses matched no scan seen.
  std::size_t applyTrajectory(const std::vector<std::pair<double, linemap::Pose2>>& laser_poses);

  /// Scores `map` (map frame) with computeMapMetrics; rebuilds the lookup table first when frames changed.
  MapMetrics evaluate(const std::vector<linemap::Segment2>& map);
  /// The lookup table of the last evaluate() (empty before).
  const LookupTable& table() const { return table_; }
  /// The straight-structure points of that table's scan points (structure coverage).
  const StructurePoints& structure() const { return structure_; }

  std::size_t scanCount() const { return scans_.size(); }
  std::size_t originalCount() const;
  void reset();

 private:
  struct Frame
  {
    double stamp = 0.0;
    linemap::Pose2 pose;
    std::optional<linemap::Pose2> odom;  ///< laser in the odometry frame, when known
    std::vector<linemap::Vec2> points;
    std::vector<linemap::Segment2> segments;
  };
  /// The keyframe gate for a frame that is not stored yet: `gate` (moved on when it admits) for a
  /// stamp past the stored ones, else the stored frames before and after it in time (`stored`:
  /// stamp -> pose).
  bool gateAccepts(const std::map<double, linemap::Pose2>& stored, line_map_merging::KeyframeGate& gate,
                   double stamp, const linemap::Pose2& pose) const;
  /// The laser pose in the frame where it is continuous: odometry when known, else the map.
  static linemap::Pose2 continuous(const Frame& f) { return f.odom ? *f.odom : f.pose; }
  /// Stores what the nodes chose; returns whether anything was stored.
  bool storeNodes(std::vector<line_map_merging::NodeKeyframes<Frame>::Ready> ready,
                  std::vector<Frame>& frames, std::map<double, linemap::Pose2>& stamps);
  /// Holds `frame` for a trajectory (unless keyframe_source is tf); true when nodes choose the frames
  /// now (`stored`: whether a waiting node stored it or an earlier held one).
  bool holdForNodes(line_map_merging::NodeKeyframes<Frame>& nodes, const Frame& frame,
                    std::vector<Frame>& frames, std::map<double, linemap::Pose2>& stamps, bool& stored);

  EvaluatorParams params_;
  line_map_merging::KeyframeGate scan_gate_;
  line_map_merging::KeyframeGate segment_gate_;
  std::vector<Frame> scans_;
  std::vector<Frame> segments_;
  std::map<double, linemap::Pose2> scan_stamps_, segment_stamps_;  // stored frames: stamp -> gate pose
  line_map_merging::NodeKeyframes<Frame> scan_nodes_, segment_nodes_;
  line_map_merging::OdometryHistory history_;  // continuous laser pose of every scan and segment set seen
  LookupTable table_;
  std::vector<linemap::Vec2> table_points_;  // the registered scan points of table_ (point coverage)
  StructurePoints structure_;                // which of them lie on straight structure
  bool table_dirty_ = true;
};

}  // namespace line_map_eval
