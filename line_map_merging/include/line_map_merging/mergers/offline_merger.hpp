// Keyframe storage shared by the offline mergers (cae_offline, o2to, ms, li2023): they get all
// keyframes at once, so addKeyframe() only stores them and the map is computed when asked for.
#pragma once

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"

namespace line_map_merging
{
/// Throws std::invalid_argument naming the keyframe and the field when its pose, mount or stamp
/// is not finite.
void validateKeyframe(const Keyframe& keyframe);

/// Base of the offline mergers. addKeyframe() stores the keyframe (bad segments dropped and
/// counted); adjust() replaces stored poses; map() runs compute() over the stored keyframes at
/// their current poses and caches the result until the next addKeyframe/adjust/reset. Not
/// thread-safe, not even for concurrent const calls (the cache is filled lazily).
class OfflineMerger : public Merger
{
 public:
  bool isOnline() const override { return false; }
  AddResult addKeyframe(const Keyframe& keyframe) override;
  AddResult addOriginals(std::uint64_t keyframe, const std::vector<linemap::Segment2>& segments) override;
  /// Replaces the poses; the map is recomputed from the stored segments on the next map().
  AdjustResult adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses) override;
  bool supportsAdjustment() const override { return true; }
  std::vector<MapSegment> map() const override { return cachedMap(); }
  std::vector<KeyframeInfo> keyframes() const override;
  std::size_t keyframeCount() const override { return stored_.size(); }
  std::size_t leafCount() const override { return leaf_count_; }
  std::size_t segmentCount() const override { return cachedMap().size(); }
  void reset() override;

 protected:
  /// The stored keyframes in arrival order, at their current poses, valid segments only.
  const std::vector<Keyframe>& stored() const { return stored_; }
  /// The merged map of stored(), sorted by id.
  virtual std::vector<MapSegment> compute() const = 0;
  /// Called whenever the cached map becomes invalid (derived caches follow it).
  virtual void invalidate() const {}
  const std::vector<MapSegment>& cachedMap() const;

 private:
  std::vector<Keyframe> stored_;
  std::unordered_map<std::uint64_t, std::size_t> slot_of_;
  std::size_t leaf_count_ = 0;
  mutable std::optional<std::vector<MapSegment>> cache_;
};

}  // namespace line_map_merging
