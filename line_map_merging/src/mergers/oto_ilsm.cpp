// OTO-ILSM (Kuo et al.): one-to-one incremental merging with the CAE-RLSM fusion conditions and
// fusion, so that it differs from OTM-ILSM only in merging with one map segment instead of all.
#include "line_map_merging/mergers/oto_ilsm.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>

#include "line_map_merging/mergers/offline_merger.hpp"

namespace line_map_merging
{
namespace bgi = boost::geometry::index;

OtoIlsm::OtoIlsm(const FusionParams& params) : params_(params)
{
  params_.validate();
}

AddResult OtoIlsm::addKeyframe(const Keyframe& keyframe)
{
  validateKeyframe(keyframe);
  if (slot_of_.count(keyframe.index))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) + ": index already merged");
  slot_of_.emplace(keyframe.index, keyframes_.size());
  keyframes_.push_back({keyframe.index, keyframe.stamp, keyframe.pose, keyframe.mount});
  AddResult result;
  for (const Segment2& local : keyframe.segments)
  {
    if (!isValidSegment(local))
    {
      ++result.rejected;
      continue;
    }
    insertSegment(local.transformed(keyframe.pose));
    ++result.merged;
  }
  leaf_count_ += result.merged;
  return result;
}

AddResult OtoIlsm::addOriginals(std::uint64_t keyframe, const std::vector<Segment2>& segments)
{
  const auto slot = slot_of_.find(keyframe);
  if (slot == slot_of_.end())
    throw std::invalid_argument("keyframe " + std::to_string(keyframe) +
                                ": no such keyframe for its originals");
  const linemap::Pose2 pose = keyframes_[slot->second].pose;
  AddResult result;
  for (const Segment2& local : segments)
  {
    if (!isValidSegment(local))
    {
      ++result.rejected;
      continue;
    }
    insertSegment(local.transformed(pose));
    ++result.merged;
  }
  leaf_count_ += result.merged;
  return result;
}

void OtoIlsm::insertSegment(const Segment2& world)
{
  // A map segment meeting the conditions has its padded box intersecting the scan segment's box.
  const Box query(Point(std::min(world.start.x(), world.end.x()), std::min(world.start.y(), world.end.y())),
                  Point(std::max(world.start.x(), world.end.x()), std::max(world.start.y(), world.end.y())));
  hits_.clear();
  index_.query(bgi::intersects(query), std::back_inserter(hits_));

  std::uint64_t best = UINT64_MAX;
  std::tuple<double, double, std::uint64_t> best_key;
  for (const Entry& e : hits_)
  {
    const Segment2& m = nodes_.at(e.second).segment;
    if (!meetsFusionConditions(m, world, params_)) continue;
    const auto key = std::make_tuple(verticalDistance(m, world), headingDeviation(m, world), e.second);
    if (best == UINT64_MAX || key < best_key)
    {
      best = e.second;
      best_key = key;
    }
  }

  Node* node = nullptr;
  std::uint64_t id = best;
  if (best == UINT64_MAX)
  {
    id = next_id_++;
    node = &nodes_[id];
    node->segment = world;
    node->moments.add(world);
  }
  else
  {
    node = &nodes_.at(best);
    index_.remove(Entry(node->box, best));
    node->moments.add(world);
    FusedLine line(node->moments, params_.weighting);
    line.include(node->segment);
    line.include(world);
    node->segment = line.segment();
  }
  ++node->count;
  const double pad = params_.searchPadding();
  const Segment2& s = node->segment;
  node->box = Box(Point(std::min(s.start.x(), s.end.x()) - pad, std::min(s.start.y(), s.end.y()) - pad),
                  Point(std::max(s.start.x(), s.end.x()) + pad, std::max(s.start.y(), s.end.y()) + pad));
  index_.insert(Entry(node->box, id));
}

AdjustResult OtoIlsm::adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses)
{
  AdjustResult result;
  for (const auto& p : poses)
    if (!slot_of_.count(p.first)) ++result.unknown;
  return result;
}

std::vector<MapSegment> OtoIlsm::map() const
{
  std::vector<MapSegment> out;
  out.reserve(nodes_.size());
  for (const auto& [id, node] : nodes_) out.push_back({id, node.segment, node.count});
  std::sort(out.begin(), out.end(), [](const MapSegment& a, const MapSegment& b) { return a.id < b.id; });
  return out;
}

std::vector<KeyframeInfo> OtoIlsm::keyframes() const
{
  std::vector<KeyframeInfo> out = keyframes_;
  std::sort(out.begin(), out.end(),
            [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.index < b.index; });
  return out;
}

void OtoIlsm::reset()
{
  keyframes_.clear();
  slot_of_.clear();
  nodes_.clear();
  index_.clear();
  next_id_ = 0;
  leaf_count_ = 0;
}

}  // namespace line_map_merging
