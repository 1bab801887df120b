// Keyframe storage of the offline mergers.
#include "line_map_merging/mergers/offline_merger.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "line_map_merging/mergers/fusion.hpp"

namespace line_map_merging
{
namespace
{
bool finitePose(const linemap::Pose2& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}
}  // namespace

void validateKeyframe(const Keyframe& keyframe)
{
  const std::string who = "keyframe " + std::to_string(keyframe.index);
  if (!finitePose(keyframe.pose)) throw std::invalid_argument(who + ": pose is not finite");
  if (!finitePose(keyframe.mount)) throw std::invalid_argument(who + ": mount is not finite");
  if (!std::isfinite(keyframe.stamp)) throw std::invalid_argument(who + ": stamp is not finite");
}

AddResult OfflineMerger::addKeyframe(const Keyframe& keyframe)
{
  validateKeyframe(keyframe);
  if (slot_of_.count(keyframe.index))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) + ": index already merged");
  Keyframe k = keyframe;
  AddResult result;
  k.segments.clear();
  for (const Segment2& s : keyframe.segments)
  {
    if (isValidSegment(s))
      k.segments.push_back(s);
    else
      ++result.rejected;
  }
  result.merged = k.segments.size();
  leaf_count_ += result.merged;
  slot_of_.emplace(k.index, stored_.size());
  stored_.push_back(std::move(k));
  cache_.reset();
  invalidate();
  return result;
}

AddResult OfflineMerger::addOriginals(std::uint64_t keyframe, const std::vector<Segment2>& segments)
{
  const auto slot = slot_of_.find(keyframe);
  if (slot == slot_of_.end())
    throw std::invalid_argument("keyframe " + std::to_string(keyframe) +
                                ": no such keyframe for its originals");
  AddResult result;
  for (const Segment2& s : segments)
  {
    if (isValidSegment(s))
      stored_[slot->second].segments.push_back(s);
    else
      ++result.rejected;
  }
  result.merged = segments.size() - result.rejected;
  leaf_count_ += result.merged;
  cache_.reset();
  invalidate();
  return result;
}

AdjustResult OfflineMerger::adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses)
{
  for (const auto& [index, pose] : poses)
    if (!finitePose(pose))
      throw std::invalid_argument("adjust: pose of keyframe " + std::to_string(index) + " is not finite");
  AdjustResult result;
  for (const auto& [index, pose] : poses)
  {
    auto it = slot_of_.find(index);
    if (it == slot_of_.end())
    {
      ++result.unknown;
      continue;
    }
    stored_[it->second].pose = pose;
    ++result.moved;
  }
  if (result.moved > 0)
  {
    cache_.reset();
    invalidate();
  }
  return result;
}

std::vector<KeyframeInfo> OfflineMerger::keyframes() const
{
  std::vector<KeyframeInfo> out;
  out.reserve(stored_.size());
  for (const Keyframe& k : stored_) out.push_back({k.index, k.stamp, k.pose, k.mount});
  std::sort(out.begin(), out.end(),
            [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.index < b.index; });
  return out;
}

void OfflineMerger::reset()
{
  stored_.clear();
  slot_of_.clear();
  leaf_count_ = 0;
  cache_.reset();
  invalidate();
}

const std::vector<MapSegment>& OfflineMerger::cachedMap() const
{
  if (!cache_) cache_ = compute();
  return *cache_;
}

}  // namespace line_map_merging
