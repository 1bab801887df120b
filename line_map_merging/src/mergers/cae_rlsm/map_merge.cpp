// Map-level merge of CAE-RLSM: map segment against map segment. OTM-ILSM only compares a scan
// segment with the map, so two map segments born apart (noise, early drift, a gap bridged later)
// would stay apart for ever; here each map segment a keyframe touched is merged with every map
// segment it meets the fusion conditions with, either way round, until none is left.
#include <algorithm>
#include <unordered_map>
#include <vector>

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
namespace bgi = boost::geometry::index;

std::size_t CaeRlsm::mergeMapSegments(std::set<std::uint64_t> pending, std::set<std::uint64_t>* changed)
{
  std::size_t merged = 0;
  std::vector<std::uint64_t> candidates;
  while (!pending.empty())
  {
    const std::uint64_t id = *pending.begin();
    pending.erase(pending.begin());
    const auto it = nodes_.find(id);
    if (it == nodes_.end()) continue;  // merged away meanwhile
    findCandidates(it->second.segment, id, candidates, true);
    if (candidates.empty()) continue;
    candidates.push_back(id);
    std::sort(candidates.begin(), candidates.end());
    // As in OTM-ILSM: the smallest id survives, takes the others' leaves and their summed moments.
    Node& target = nodes_.at(candidates.front());
    indexRemove(candidates.front(), target);
    FusionMoments moments = target.moments;
    for (std::size_t i = 1; i < candidates.size(); ++i) moments.add(nodes_.at(candidates[i]).moments);
    FusedLine line(moments, params_.fusion.weighting);
    line.include(target.segment);
    for (std::size_t i = 1; i < candidates.size(); ++i)
    {
      const auto other = nodes_.find(candidates[i]);
      line.include(other->second.segment);
      indexRemove(candidates[i], other->second);
      target.leaves.insert(target.leaves.end(), other->second.leaves.begin(), other->second.leaves.end());
      nodes_.erase(other);
      ++merged;
    }
    target.moments = moments;
    target.segment = line.segment();
    indexInsert(candidates.front(), target);
    if (changed) changed->insert(candidates.front());
    // The fused segment moved and grew: it may now meet others.
    pending.insert(candidates.front());
  }
  return merged;
}

std::size_t CaeRlsm::regroup()
{
  const std::size_t before = nodes_.size();
  std::vector<std::uint64_t> old_id(leaves_.size(), UINT64_MAX);
  for (const auto& [id, node] : nodes_)
    for (std::uint32_t l : node.leaves) old_id[l] = id;
  const std::uint64_t first_fresh = next_id_;
  nodes_.clear();
  index_.clear();
  index_stale_ = false;
  // OTM-ILSM over every leaf in arrival order, keyframe by keyframe, as if merged on these poses.
  // The same steps after each keyframe as addKeyframe.
  std::set<std::uint64_t> touched;
  const auto endOfKeyframe = [&]
  {
    std::set<std::uint64_t> changed;
    if (params_.map_merge) mergeMapSegments(touched, &changed);
    if (params_.resolve_crossings)
    {
      changed.insert(touched.begin(), touched.end());
      resolveCrossings(std::move(changed));
    }
    touched.clear();
  };
  for (std::uint32_t l = 0; l < leaves_.size(); ++l)
  {
    if (l > 0 && leaves_[l].slot != leaves_[l - 1].slot) endOfKeyframe();
    touched.insert(insertSegment(worldLeaf(l), l));
  }
  endOfKeyframe();
  keepOldIds(old_id, first_fresh);
  return before > nodes_.size() ? before - nodes_.size() : 0;
}

void CaeRlsm::keepOldIds(const std::vector<std::uint64_t>& old_id, std::uint64_t first_fresh)
{
  // Ids follow the leaves: in order of their smallest old id, each new segment takes the smallest
  // old id of its leaves that no segment took before it; a segment whose old ids are all taken (a
  // group that split) gets a fresh one.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> order;  // (smallest old id, temporary id)
  for (auto& [id, node] : nodes_)
  {
    std::sort(node.leaves.begin(), node.leaves.end());
    std::uint64_t smallest = UINT64_MAX;
    for (std::uint32_t l : node.leaves) smallest = std::min(smallest, old_id[l]);
    order.emplace_back(smallest, id);
  }
  std::sort(order.begin(), order.end());
  std::unordered_map<std::uint64_t, Node> renamed;
  std::set<std::uint64_t> taken;
  next_id_ = first_fresh;
  for (const auto& [smallest, temporary] : order)
  {
    Node& node = nodes_.at(temporary);
    std::vector<std::uint64_t> mine;
    for (std::uint32_t l : node.leaves) mine.push_back(old_id[l]);
    std::sort(mine.begin(), mine.end());
    std::uint64_t id = UINT64_MAX;
    for (std::uint64_t candidate : mine)
      if (candidate != UINT64_MAX && !taken.count(candidate))
      {
        id = candidate;
        break;
      }
    if (id == UINT64_MAX) id = next_id_++;
    taken.insert(id);
    renamed.emplace(id, std::move(node));
  }
  nodes_ = std::move(renamed);
  rebuildIndex();
}

}  // namespace line_map_merging
