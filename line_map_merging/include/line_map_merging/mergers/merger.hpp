// The ROS-free interface of every online line map merger (CAE-RLSM and the competing methods)
// and the factory that creates them by name.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/step_times.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
/// One keyframe fed to a merger.
struct Keyframe
{
  std::uint64_t index = 0;  ///< unique, chosen by the caller (e.g. a running counter)
  double stamp = 0.0;       ///< [s]
  linemap::Pose2 pose;      ///< the laser in the map frame
  linemap::Pose2 mount;     ///< base -> laser; kept (and saved) for the caller, not used by merging
  std::vector<linemap::Segment2> segments;  ///< in the laser frame, as extracted
};

/// A keyframe as the merger holds it (without its segments).
struct KeyframeInfo
{
  std::uint64_t index = 0;
  double stamp = 0.0;
  linemap::Pose2 pose;
  linemap::Pose2 mount;
  /// Time from the scan before this keyframe's scan to it, and from it to the scan after [s]:
  /// scans that did not become keyframes included, as the caller saw them (infinite = unknown).
  /// Stamp matching gives a trajectory pose to this keyframe only when no other scan was nearer.
  double scan_gap_before = std::numeric_limits<double>::infinity();
  double scan_gap_after = std::numeric_limits<double>::infinity();
  /// The mapping session it was merged in: 0 for a map begun from nothing, one more than the
  /// loaded map's newest for a map continued from a file (CAE-RLSM; see CaeParams::see_through).
  std::uint32_t session = 0;
};

/// One segment of the merged map.
struct MapSegment
{
  std::uint64_t id = 0;            ///< stable; a merged group keeps the smallest id
  linemap::Segment2 segment;       ///< map frame
  std::uint32_t merged_count = 0;  ///< original segments fused into it
};

/// Provenance: an original segment as extracted, in its keyframe's laser frame.
struct Leaf
{
  std::uint64_t keyframe = 0;
  linemap::Segment2 segment;
};

struct AddResult
{
  std::size_t merged = 0;    ///< segments that entered the map
  std::size_t rejected = 0;  ///< non-finite or zero-length segments, skipped
  std::size_t retired = 0;   ///< original segments of earlier sessions this keyframe saw through, retired
};

struct AdjustResult
{
  std::size_t moved = 0;    ///< keyframes whose pose was replaced
  std::size_t unknown = 0;  ///< poses naming no keyframe of the merger (ignored)
  std::size_t split = 0;    ///< leaves split off their map segment (consistent adjustment)
  std::size_t merged = 0;   ///< map segments merged into others after the adjustment
};

/// Load/save failure; what() names the file and, where known, the line and field.
struct MapFileError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

class Merger
{
 public:
  virtual ~Merger() = default;
  /// The factory name ("cae", ...).
  virtual const char* name() const = 0;
  /// True for a merger that merges keyframe by keyframe as they come, its map ready after each (it is
  /// driven through OnlineMapper); false for one that computes the map from every keyframe at once.
  virtual bool isOnline() const { return true; }

  /// Merges the keyframe's segments into the map. Throws std::invalid_argument naming the field for
  /// a duplicate index or a non-finite pose (the map is then unchanged); bad segments are skipped
  /// and counted in the result.
  virtual AddResult addKeyframe(const Keyframe& keyframe) = 0;

  /// Merges further original segments (laser frame) of a keyframe merged before, at its current
  /// pose: lines found later in what the keyframe saw (MapLevelLines). Throws std::invalid_argument
  /// for an unknown index; bad segments are skipped and counted.
  virtual AddResult addOriginals(std::uint64_t keyframe, const std::vector<linemap::Segment2>& segments) = 0;

  /// Replaces the poses (laser in map) of the named keyframes and rebuilds the map from the
  /// provenance; keyframes not named keep their pose. Methods without provenance return
  /// moved == 0 and leave the map as it is (see supportsAdjustment()).
  virtual AdjustResult adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses) = 0;
  virtual bool supportsAdjustment() const { return false; }

  /// The map, sorted by id.
  virtual std::vector<MapSegment> map() const = 0;
  /// The keyframes, sorted by index.
  virtual std::vector<KeyframeInfo> keyframes() const = 0;
  /// The original segments under map segment `id` (empty when unknown or without provenance).
  virtual std::vector<Leaf> leaves(std::uint64_t /*id*/) const { return {}; }
  virtual bool hasProvenance() const { return false; }

  virtual std::size_t keyframeCount() const = 0;
  virtual std::size_t leafCount() const = 0;  ///< original segments merged so far
  virtual std::size_t segmentCount() const = 0;

  /// Empties the map, its provenance and its keyframes (ids restart at 0).
  virtual void reset() = 0;

  /// An independent copy of the whole state (for a snapshot, or to adjust a copy while merging goes
  /// on); null for a merger that cannot be copied.
  virtual std::unique_ptr<Merger> clone() const { return nullptr; }

  /// Writes the whole state to `path` atomically (temporary file, fsync, rename). Throws MapFileError.
  virtual void save(const std::string& /*path*/) const
  {
    throw MapFileError(std::string(name()) + ": saving is not supported");
  }
  /// Replaces the state by the file's; on any error throws MapFileError and keeps the current state.
  virtual void load(const std::string& /*path*/)
  {
    throw MapFileError(std::string(name()) + ": loading is not supported");
  }
  /// load() from the text of a map file; `origin` names it in errors (a file, a session's record).
  virtual void loadText(const std::string& /*text*/, const std::string& /*origin*/)
  {
    throw MapFileError(std::string(name()) + ": loading is not supported");
  }

  /// Turns the timing of the merger's own steps on or off; a merger without named steps ignores it.
  virtual void timeSteps(bool /*on*/) {}
  /// The time spent in each of its steps while timing was on [ms], in a fixed order; empty when the
  /// merger has no named steps.
  virtual std::vector<StepTime> stepTimes() const { return {}; }
};

/// Creates merger `name` from parameters (shared: "fusion/max_angle", "fusion/max_distance",
/// "fusion/min_overlap"; CAE-RLSM: "threads", "consistent_adjustment", "spatial_index").
/// Throws linemap::ParameterError naming an unknown method or a bad parameter.
std::unique_ptr<Merger> makeMerger(const std::string& name, const linemap::ParamSet& params);

/// Names accepted by makeMerger.
const std::vector<std::string>& mergerNames();

}  // namespace line_map_merging
