// The online mapper (ROS-free): everything the merging nodelet and linemap_batch's replay mode do
// between receiving data and publishing a map. Fed plain data: stamped segment sets with their
// laser pose in the map frame (and in the odometry frame), stamped trajectories of base poses
// from a SLAM back end, save / load / reset. It owns the keyframe gate, the keyframe and scan pose
// bookkeeping, matching trajectory nodes to scans by stamp, correcting keyframes between nodes
// (trajectory_anchor.hpp), the adjustments, replay and time-jump handling, the autosave policy
// (when to save; the file is written by the merger's save()) and every counter of the diagnostics.
// Several robots feed one map as lanes (StampedScan::lane): each lane has its own keyframe gate, scan
// history, node keyframes and trajectories, in its own map frame, placed in this map's frame by placeLane
// (lane 0, the first robot's, defines it); a lane's scans and trajectory wait until it is placed.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/online/keyframe_gate.hpp"
#include "line_map_merging/online/map_level_lines.hpp"
#include "line_map_merging/online/node_keyframes.hpp"
#include "line_map_merging/online/trajectory_anchor.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"
#include "linemap/time_jump_detector.hpp"

namespace line_map_merging
{
struct OnlineMapperParams
{
  KeyframeGateParams gate;
  double stamp_tolerance = 0.01;     ///< [s] trajectory node <-> scan stamp
  double max_gap = 1.0;              ///< [s] a node between two scans at most this far apart is interpolated
  double time_jump_tolerance = 1.0;  ///< [s] clock or stamp this much earlier than before = time jumped back
  double autosave_period = 0.0;      ///< [s] 0 = no autosave
  CorrectionMode correction = CorrectionMode::kNearest;
  KeyframeSource keyframe_source = KeyframeSource::kAuto;
  double keyframe_buffer = 300.0;  ///< [s] scans held for a trajectory to name them nodes
  MapLevelParams map_level;        ///< lines in what no single keyframe's extractor explained

  /// Keys "keyframe_distance", "keyframe_angle", "stamp_tolerance", "trajectory_max_gap",
  /// "time_jump_tolerance", "autosave_period", "trajectory_correction" (nearest | interpolate),
  /// "keyframe_source" (auto | tf | trajectory), "keyframe_buffer";
  /// throws linemap::ParameterError naming the key.
  static OnlineMapperParams fromParams(const linemap::ParamSet& params);
};

/// One segment set as the extraction produced it, with its poses at its stamp.
struct StampedScan
{
  double stamp = 0.0;                       ///< [s]; zero is dropped (a "latest transform" stamp)
  linemap::Pose2 laser;                     ///< laser in the map frame
  std::optional<linemap::Pose2> odom;       ///< laser in the odometry frame, when there is one
  linemap::Pose2 mount;                     ///< base -> laser
  std::vector<linemap::Segment2> segments;  ///< laser frame
  /// The robot (OnlineMapper's lanes): `laser` is then in that robot's own map frame.
  std::size_t lane = 0;
  /// The scan the segments came from, for the map-level lines (MapLevelLines); none: the keyframe
  /// gives none.
  std::shared_ptr<const KeyframeScan> beams;
};

/// The beams of a scan for StampedScan::beams: `geometry` has a LaserScan message's angle_min,
/// angle_increment, range_min and range_max (the message itself, or a recording's scan geometry).
template <class Geometry>
std::shared_ptr<const KeyframeScan> makeKeyframeScan(const Geometry& geometry,
                                                     const std::vector<float>& ranges)
{
  auto scan = std::make_shared<KeyframeScan>();
  scan->angle_min = geometry.angle_min;
  scan->angle_increment = geometry.angle_increment;
  scan->range_min = geometry.range_min;
  scan->range_max = geometry.range_max;
  scan->ranges = ranges;
  return scan;
}

/// A trajectory node: base pose in the map frame at a stamp.
using StampedPose = std::pair<double, linemap::Pose2>;

enum class ScanOutcome
{
  kKeyframe,   ///< merged
  kBelowGate,  ///< the robot has not moved enough since the last keyframe
  kReplayed,   ///< a keyframe with this stamp exists (a replayed bag): skipped
  kZeroStamp,  ///< stamped zero: dropped
  kRejected,   ///< the merger refused it (non-finite pose)
  kHeld,       ///< the trajectory's nodes choose the keyframes: held until a trajectory names it (or not)
};

struct MapperCounters
{
  std::size_t scans = 0, keyframes_added = 0, below_gate = 0, replayed = 0, zero_stamps = 0;
  std::size_t dropped = 0;  ///< by the caller (no transform) or the merger (rejected)
  std::size_t bad_segments = 0;
  std::size_t retired =
      0;  ///< originals of earlier sessions retired as seen through (CaeParams::see_through)
  std::size_t trajectories = 0, ignored_trajectories = 0, bad_poses = 0, unmatched_poses = 0;
  std::size_t adjustments = 0, adjustment_failures = 0;
  std::size_t time_jumps = 0, autosaves = 0, autosave_failures = 0;
  std::size_t node_keyframes = 0;    ///< keyframes a trajectory node chose (at the node's pose)
  std::size_t unplaced_dropped = 0;  ///< scans of a lane not placed within keyframe_buffer, forgotten
  std::size_t rebuilds = 0;          ///< maps made again from the nodes of the first trajectory
  std::size_t handled =
      0;  ///< segment sets finished with: given to addScan, or counted dropped by the caller
  std::size_t map_level_passes = 0, map_level_lines = 0, map_level_originals = 0;
  double map_level_ms = 0.0;  ///< every map-level pass together, search and merge of its originals
  double last_otm_ms = 0.0, last_gma_ms = 0.0;
};

class OnlineMapper
{
 public:
  OnlineMapper(std::unique_ptr<Merger> merger, const OnlineMapperParams& params);
  ~OnlineMapper();  ///< waits for an autosave being written

  /// Gates and merges one segment set. A scan whose stamp a keyframe already has is a replay:
  /// skipped, and the gate moves on from it as from that keyframe, so a replay adds nothing. Once the
  /// trajectory's nodes choose the keyframes (KeyframeSource), the scan is held instead, or merged at
  /// once when a node of the last trajectory was waiting for it (kKeyframe).
  ScanOutcome addScan(const StampedScan& scan);

  /// Looks for map-level lines (MapLevelLines) in the keyframes' scans at their current poses and
  /// merges each keyframe's part as an original of that keyframe. Done after every adjustment and
  /// every map_level.every_keyframes keyframes, so that the same input gives the same map live and
  /// in linemap_batch. Whether the map changed.
  bool extractMapLevel();

  /// Applies a trajectory of base poses (map frame) of the back end's nodes, at any stamps: each
  /// node found among the scans seen gives the corrected map->odom there; every keyframe gets the
  /// correction of its nearest node (or the interpolation, see CorrectionMode) and the map is
  /// adjusted. Then, unless keyframe_source is tf, the nodes newer than every keyframe take their
  /// held scans as keyframes at the nodes' poses (base pose * mount), through the keyframe gate. At
  /// the first trajectory (auto), when every scan since the first keyframe is held, the map is made
  /// again from the nodes alone.
  /// Non-finite poses are counted and skipped. Returns whether the map changed. `lane`: whose
  /// trajectory (in its own map frame); one of a lane not placed yet waits for its placement.
  bool addTrajectory(const std::vector<StampedPose>& base_poses, std::size_t lane = 0);

  /// Places `lane`'s map frame at `lane_in_map` in this map's frame (lane 0 is at the identity unless
  /// placed otherwise). At the first placement the lane's waiting scans are merged, then its newest
  /// trajectory applied; a lane placed again moves its keyframes by the change. Returns whether the map
  /// changed.
  bool placeLane(std::size_t lane, const linemap::Pose2& lane_in_map);
  /// Where `lane`'s map frame is in this map's frame; nothing before it is placed.
  std::optional<linemap::Pose2> lanePlacement(std::size_t lane) const;

  /// The clock reading and/or a message stamp (NaN or 0: not known). Returns true when time jumped
  /// back by more than the tolerance (rosbag play --loop): the gate is reset, the map kept, and
  /// the caller should drop what it holds of the old time line (tf buffer).
  bool observeTime(double clock, double stamp);

  /// Empties the map and every record of scans and keyframes (counters stay).
  void reset();
  /// Replaces the map by the file's (throws MapFileError and keeps everything on failure). The
  /// odometry of the loaded keyframes is unknown: their map poses stand in for it.
  void load(const std::string& path);
  /// The same from the text of a map file (a session's map); `origin` names it in errors.
  void loadText(const std::string& text, const std::string& origin);

  /// Adds the keyframes of a map file's text to this map (a saved map joined by a run that mapped apart,
  /// LaserSlam::joinSession): each keyframe's original segments are merged as a new keyframe at its pose
  /// moved by `placed` (the file's map frame in this one's), in the order of their stamps; keyframes whose
  /// stamp this map has are skipped. Their poses stand in for their odometry, so a trajectory naming their
  /// stamps moves them, as after load(). Needs a merger that keeps provenance (the originals); throws
  /// MapFileError naming `origin` (and keeps the map) for a file that cannot be read or such a merger.
  /// Returns the keyframes added.
  std::size_t appendText(const std::string& text, const std::string& origin, const linemap::Pose2& placed);

  /// The autosave policy: true when autosave is on, the map changed since the last save and the
  /// period has passed since the last save (`now` in seconds, e.g. wall time).
  bool autosaveDue(double now) const;
  /// Autosave: when due, a snapshot of the map is written to `path` by a worker thread, so merging
  /// goes on meanwhile (`wait`, e.g. at shutdown: written before returning; a merger that cannot be
  /// copied is written here too). Returns the error of a save finished since the last call, or "".
  std::string autosave(const std::string& path, double now, bool wait = false);
  /// The caller saved `revision` (of revision(), taken when it took the snapshot) at `now`, or failed.
  void autosaved(std::uint64_t revision, double now, bool ok);

  /// Whether the trajectory's nodes choose lane 0's keyframes now.
  bool nodesChoose() const { return lane(0).nodes.active(); }

  /// Counts a scan the caller could not pose (no transform) or that came stamped zero.
  void countDropped()
  {
    ++counters_.dropped;
    ++counters_.handled;
  }
  void countZeroStamp()
  {
    ++counters_.zero_stamps;
    ++counters_.handled;
  }
  /// Counts a trajectory the caller refused (wrong frame) and poses it could not convert.
  void countIgnoredTrajectory() { ++counters_.ignored_trajectories; }
  void countBadPoses(std::size_t n) { counters_.bad_poses += n; }

  /// A copy of the merger's state, for writing it while merging goes on (the autosave); null for a
  /// merger that cannot be copied.
  std::shared_ptr<const Merger> snapshot() const;
  /// An independent copy of the whole mapper (map, keyframe records, gate, held scans, counters), to
  /// adjust while this one goes on merging (concurrent_mapper.hpp); null when the merger cannot be
  /// copied. The copy writes no autosave of this one's.
  std::unique_ptr<OnlineMapper> clone() const;
  /// Takes over `previous`'s autosave (a file being written, when the last one was, the counters) when
  /// this mapper replaces it; the map counts as changed since that save.
  void adoptAutosave(OnlineMapper& previous);

  const Merger& merger() const { return *merger_; }
  Merger& merger() { return *merger_; }
  /// Increases with every change of the map.
  std::uint64_t revision() const { return revision_; }
  const MapperCounters& counters() const { return counters_; }
  const OnlineMapperParams& params() const { return params_; }
  /// Stamps of the keyframes, in the order they were merged.
  const std::vector<double>& keyframeStamps() const { return keyframe_order_; }
  /// Every counter of the diagnostics with its label, in display order.
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

 private:
  /// Where the map-level merge step (map segment against map segment) is to be scheduled once the
  /// merger offers one: after each keyframe and after each adjustment, on the merger's own state.
  void afterMapChange() { ++revision_; }

  OnlineMapper(const OnlineMapper& other, std::unique_ptr<Merger> merger);

  /// What a scan leaves for a trajectory node to merge.
  struct HeldScan
  {
    linemap::Pose2 continuous, mount;
    std::vector<linemap::Segment2> segments;
    std::shared_ptr<const KeyframeScan> beams;
  };
  /// One robot's record: what is judged and matched by stamp per robot (two robots' scans may share
  /// stamps), and where its map frame lies in this map's.
  struct Lane
  {
    explicit Lane(const OnlineMapperParams& params);
    KeyframeGate gate;
    NodeKeyframes<HeldScan> nodes;
    OdometryHistory history;  ///< base pose of every scan seen, in the continuous frame
    std::unordered_set<double> keyframe_stamps;
    std::optional<linemap::Pose2> placement;
    std::vector<StampedScan> unplaced;  ///< scans waiting for the placement, oldest first
    std::optional<std::vector<StampedPose>> unplaced_trajectory;  ///< the newest, waiting too
  };
  Lane& lane(std::size_t index);
  const Lane& lane(std::size_t index) const;
  /// Merges one keyframe (laser pose in the map frame); false when the merger refused it.
  bool merge(std::size_t lane, double stamp, const linemap::Pose2& laser, const linemap::Pose2& continuous,
             const linemap::Pose2& mount, const std::vector<linemap::Segment2>& segments,
             const std::shared_ptr<const KeyframeScan>& beams = nullptr);
  bool mergeNodes(std::size_t lane, std::vector<NodeKeyframes<HeldScan>::Ready> ready);
  /// addScan for a scan of a placed lane, its laser pose in this map's frame.
  ScanOutcome addPlacedScan(const StampedScan& scan);
  /// Holds a scan of a lane not placed yet (dropping those older than keyframe_buffer).
  void holdUnplaced(Lane& lane, const StampedScan& scan);
  double newestKeyframeStamp(std::size_t lane) const;
  /// After the merger loaded a map: its keyframes become the mapper's, their map poses standing in for the
  /// odometry.
  void adoptLoadedMap();
  /// Empties the map and the keyframe records (not the scan history, nor the held scans).
  void clearKeyframes();
  /// Moves `lane`'s keyframes to the trajectory (anchored on the nodes, in this map's frame); whether the
  /// map changed.
  bool adjustTo(std::size_t lane, const std::vector<StampedPose>& nodes);
  /// addTrajectory for a placed lane, the poses in this map's frame.
  bool addPlacedTrajectory(std::vector<StampedPose> nodes, std::size_t lane);

  std::unique_ptr<Merger> merger_;
  OnlineMapperParams params_;
  std::optional<MapLevelLines> map_level_;  ///< when params_.map_level.enabled
  int keyframes_since_map_level_ = 0;
  std::map<std::size_t, Lane> lanes_;
  std::unordered_map<std::uint64_t, linemap::Pose2> continuous_;  ///< keyframe index -> laser, same frame
  std::unordered_map<std::uint64_t, std::size_t> lane_of_;        ///< keyframe index -> lane
  std::vector<double> keyframe_order_;
  std::uint64_t next_index_ = 0;
  linemap::TimeJumpDetector time_jumps_;  ///< the clock and the scans' stamps
  std::uint64_t revision_ = 0, saved_revision_ = 0;
  double last_save_ = -1e300;
  std::future<std::string> writer_;  ///< the autosave being written: its error, or ""
  std::uint64_t writing_revision_ = 0;
  double writing_since_ = 0.0;
  std::string collectAutosave(bool wait);
  MapperCounters counters_;
};

}  // namespace line_map_merging
