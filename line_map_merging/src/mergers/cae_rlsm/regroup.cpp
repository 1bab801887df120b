// Regrouping on adjustment (CAE-RLSM with regroup_on_adjust): under new keyframe poses the leaves are
// grouped again from scratch, OTM-ILSM over every leaf in arrival order with the same steps after each
// keyframe as addKeyframe, and the map segments then take their ids back by their leaves.
//
// The pass is a function of the leaves' world segments in arrival order alone. So when the keyframes
// the last pass covered kept their poses bit for bit (a back end that re-publishes the old part of
// its trajectory unchanged and corrects only the new part), the pass resumes from the state it had
// reached then (the checkpoint) and only the keyframes since are merged again: the same map, without
// walking the whole map at each adjustment.
#include <algorithm>
#include <cstring>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
bool CaeRlsm::checkpointStillHolds() const
{
  const RegroupCheckpoint& c = checkpoint_;
  if (!c.valid || c.transforms.size() > transforms_.size()) return false;
  // Bit for bit: a changed sign of zero could change a printed digit of the map.
  return c.transforms.empty() ||
         std::memcmp(c.transforms.data(), transforms_.data(), c.transforms.size() * sizeof(Transform)) == 0;
}

std::size_t CaeRlsm::regroup()
{
  const std::size_t before = nodes_.size();
  std::vector<std::uint64_t> old_id(leaves_.size(), UINT64_MAX);
  for (const auto& [id, node] : nodes_)
    for (std::uint32_t l : node.leaves) old_id[l] = id;
  const std::uint64_t first_fresh = next_id_;
  // The pass numbers its segments from 0; only their order matters to it (the smallest id survives a
  // merge), and keepOldIds names them afterwards.
  std::uint32_t first_leaf = 0;
  if (params_.incremental_regroup && checkpointStillHolds())
  {
    // Taken, not copied: the checkpoint is made again at the end of this pass.
    nodes_ = std::move(checkpoint_.nodes);
    checkpoint_.valid = false;
    next_id_ = checkpoint_.next_id;
    first_leaf = checkpoint_.leaves;
    ++checkpoint_.resumed;
    index_stale_ = true;  // bulk loaded by the first search
  }
  else
  {
    nodes_.clear();
    index_.clear();
    index_stale_ = false;
    next_id_ = 0;
  }
  IdQueue touched;
  for (std::uint32_t l = first_leaf; l < leaves_.size(); ++l)
  {
    if (l > first_leaf && leaves_[l].slot != leaves_[l - 1].slot)
    {
      finishKeyframe(touched, kAdjustOtm);
      touched.clear();
    }
    const StepTimes<kStepCount>::Scope timed(steps_, kAdjustOtm);
    touched.insert(insertSegment(worldLeaf(l), l));
  }
  finishKeyframe(touched, kAdjustOtm);
  const StepTimes<kStepCount>::Scope timed(steps_, kAdjustIds);
  if (params_.incremental_regroup)
  {
    checkpoint_.valid = true;
    checkpoint_.transforms = transforms_;
    checkpoint_.leaves = static_cast<std::uint32_t>(leaves_.size());
    checkpoint_.nodes = nodes_;
    checkpoint_.next_id = next_id_;
  }
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
  renamed.reserve(nodes_.size());
  std::unordered_set<std::uint64_t> taken;
  taken.reserve(nodes_.size());
  next_id_ = first_fresh;
  std::vector<std::uint64_t> mine;
  for (const auto& [smallest, temporary] : order)
  {
    Node& node = nodes_.at(temporary);
    mine.clear();
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
