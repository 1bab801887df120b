// Adjustment off the merge path (ROS-free): an OnlineMapper whose trajectories (MP-GMA, the
// consistency pass, regrouping, node keyframes) are applied to a copy by a worker thread while the
// live mapper goes on merging scans. When the copy is done, the scans and calls the live mapper took
// meanwhile are applied to it in the same order and it replaces the live one in one step. So every map
// the caller reads is a whole state (never half adjusted), and once no adjustment is pending the map
// equals the one OnlineMapper makes from the same calls in the same order (as linemap_batch --replay
// does). Trajectories arriving during an adjustment wait their turn, in order.
// Not thread-safe: the caller serialises its calls (the worker touches only its own copy).
#pragma once

#include <cstddef>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/online/online_mapper.hpp"

namespace line_map_merging
{
/// A map service's answer: whether it succeeded, and what was done or why it failed.
struct MapCommandAnswer
{
  bool success = false;
  std::string message;
};

class ConcurrentMapper
{
 public:
  /// `background` false, or a merger that cannot be copied: every trajectory is applied at once
  /// (OnlineMapper's behaviour).
  ConcurrentMapper(std::unique_ptr<OnlineMapper> mapper, bool background);
  /// Merger `method` (makeMerger) in an OnlineMapper (OnlineMapperParams::fromParams); key
  /// "adjust_in_background" (default true). Throws linemap::ParameterError naming the key.
  static std::unique_ptr<ConcurrentMapper> fromParams(const std::string& method,
                                                      const linemap::ParamSet& params);
  ~ConcurrentMapper();  ///< waits for the adjustment in progress

  ScanOutcome addScan(const StampedScan& scan);
  /// Starts adjusting a copy to the trajectory (or queues it behind the one in progress). Returns
  /// whether the live map changed now: only without background adjustment. `lane`: whose (OnlineMapper).
  bool addTrajectory(const std::vector<StampedPose>& base_poses, std::size_t lane = 0);
  /// OnlineMapper::placeLane on the live mapper (and on the copy being adjusted, after it).
  bool placeLane(std::size_t lane, const linemap::Pose2& lane_in_map);
  /// Replaces the live mapper by a finished adjustment (and starts the next queued trajectory).
  /// Returns whether the map changed. Cheap when nothing is finished: call it often.
  bool poll();
  /// Waits until no adjustment is in progress or queued; whether the map changed.
  bool finish();

  bool observeTime(double clock, double stamp);
  /// Before an incoming segment set waits for tf: why it is turned away, counted, or "" to hold it.
  /// A zero stamp would be posed at the latest transform; a frame unknown to tf (`frame_known` false)
  /// would wait unreported until the queue overflows. The stamp is observed for time jumping back
  /// (observeTime) unless zero: `jumped`.
  std::string admit(double clock, double stamp, bool frame_known, bool& jumped);
  void countDropped(std::size_t n = 1);
  void countZeroStamp();
  void countIgnoredTrajectory();
  void countBadPoses(std::size_t n);
  /// Both finish() first: they act on the newest map.
  void reset();
  void load(const std::string& path);
  /// The map services (save, load): finish() first, then what was done, or why it failed (a failed
  /// load keeps the map).
  MapCommandAnswer saveMap(const std::string& path);
  MapCommandAnswer loadMap(const std::string& path);
  /// OnlineMapper::appendText of the file at `path` (the append_map service), after finish().
  MapCommandAnswer appendMap(const std::string& path, const linemap::Pose2& placed);
  /// OnlineMapper::autosave on the live mapper (a snapshot of a whole state); `wait` (the last save)
  /// finishes the adjustments first.
  std::string autosave(const std::string& path, double now, bool wait = false);

  /// The live mapper: the map to publish, its counters.
  const OnlineMapper& mapper() const { return *live_; }
  /// Whether an adjustment is in progress.
  bool adjusting() const { return job_.valid(); }
  /// The live mapper's diagnostics plus the adjustment's own.
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

 private:
  /// A call the live mapper took, or a trajectory waiting for its turn.
  struct Event
  {
    std::function<void(OnlineMapper&)> apply;  ///< null for a trajectory
    std::vector<StampedPose> trajectory;
    std::size_t lane = 0;  ///< the trajectory's
  };
  void apply(std::function<void(OnlineMapper&)> call);
  /// Clones the live mapper and adjusts the clone to `nodes` on a worker thread; false when the
  /// merger cannot be copied.
  bool start(const std::vector<StampedPose>& nodes, std::size_t lane);
  /// Takes the finished adjustment (waiting for it); whether the map changed.
  bool takeResult();
  std::size_t queuedTrajectories() const;

  std::unique_ptr<OnlineMapper> live_;
  bool background_;
  struct Adjusted
  {
    std::unique_ptr<OnlineMapper> mapper;
    double ms = 0.0;  ///< the worker's time
  };
  std::future<Adjusted> job_;
  std::vector<Event> log_;  ///< since the job's copy was taken, in arrival order
  std::size_t background_adjustments_ = 0, background_failures_ = 0, queued_max_ = 0;
  double last_copy_ms_ = 0.0, last_worker_ms_ = 0.0, last_swap_ms_ = 0.0;
  std::size_t last_replayed_ = 0;
};

}  // namespace line_map_merging
