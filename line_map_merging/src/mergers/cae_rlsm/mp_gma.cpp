// MP-GMA (Algorithm 2 of CAE-RLSM): with new keyframe poses, every leaf is re-transformed and every
// map segment re-fused from its own leaves, in parallel (TBB). Optionally followed by a consistency
// pass that the paper does not have: leaves that no longer meet the fusion conditions with their
// re-fused segment are split off (and re-merged through OTM-ILSM), and map segments that now meet
// the conditions are merged.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_set>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/mergers/crossing_pairs.hpp"

namespace line_map_merging
{
namespace bgi = boost::geometry::index;

namespace
{
/// body(i) for every i in [0, n), in parallel on `arena`.
template <class Body>
void parallelFor(tbb::task_arena& arena, std::size_t n, std::size_t grain, const Body& body)
{
#ifdef LINEMAP_TSAN
  // ThreadSanitizer cannot see TBB's synchronisation (libtbb is not instrumented), so the TSan
  // check (scripts/sanitize.sh tsan) runs the same bodies on plain threads, interleaved chunks.
  (void)grain;
  const std::size_t workers = std::max(2, arena.max_concurrency());
  std::vector<std::thread> threads;
  for (std::size_t w = 0; w < workers; ++w)
    threads.emplace_back(
        [&, w]
        {
          for (std::size_t i = w; i < n; i += workers) body(i);
        });
  for (std::thread& t : threads) t.join();
#else
  if (n <= grain)
  {
    // One chunk: waking the arena's workers would cost more than the work.
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  arena.execute(
      [&]
      {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                          [&](const tbb::blocked_range<std::size_t>& r)
                          {
                            for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                          });
      });
#endif
}
}  // namespace

Segment2 CaeRlsm::worldLeaf(std::uint32_t leaf) const
{
  const LeafRecord& l = leaves_[leaf];
  const Transform& t = transforms_[l.slot];
  return {t.leftCols<2>() * l.local.start + t.col(2), t.leftCols<2>() * l.local.end + t.col(2)};
}

void CaeRlsm::updateTransforms()
{
  transforms_.resize(keyframes_.size());
  for (std::size_t i = 0; i < keyframes_.size(); ++i)
  {
    const linemap::Pose2& p = keyframes_[i].pose;
    const double c = std::cos(p.theta), s = std::sin(p.theta);
    transforms_[i] << c, -s, p.x, s, c, p.y;
  }
}

void CaeRlsm::refuse(Node& node) const
{
  thread_local std::vector<Segment2> world;
  world.clear();
  for (std::uint32_t l : node.leaves) world.push_back(worldLeaf(l));
  fuseWorld(node, world);
}

void CaeRlsm::fuseWorld(Node& node, const std::vector<Segment2>& world) const
{
  // Two passes over the leaves: the moments fix the line, then the endpoints fix its extent.
  FusionMoments moments;
  for (const Segment2& s : world) moments.add(s);
  FusedLine line(moments, params_.fusion.weighting);
  for (const Segment2& s : world) line.include(s);
  node.moments = moments;
  node.segment = line.segment();
}

std::vector<std::uint32_t> CaeRlsm::splitInconsistentLeaves(Node& node) const
{
  std::vector<std::uint32_t> split;
  // Removing leaves moves the fused segment, which can expose more outliers: repeat until stable.
  for (;;)
  {
    // A lone leaf is its own group; with a non-finite world leaf it would fail the test against
    // itself and be split off and re-kept forever.
    if (node.leaves.size() <= 1) return split;
    std::vector<std::uint32_t> keep;
    std::size_t first_split = split.size();
    for (std::uint32_t l : node.leaves)
    {
      if (meetsFusionConditions(node.segment, worldLeaf(l), params_.fusion))
        keep.push_back(l);
      else
        split.push_back(l);
    }
    if (split.size() == first_split) return split;
    if (keep.empty())
    {
      // No leaf agrees with the group any more: the oldest one keeps the id.
      auto oldest = std::min_element(split.begin() + first_split, split.end());
      keep.push_back(*oldest);
      split.erase(oldest);
    }
    node.leaves = std::move(keep);
    refuse(node);
  }
}

void CaeRlsm::resolveAllCrossings(tbb::task_arena& arena)
{
  // Re-fusing restored every segment's full extent from its leaves: the crossings come back.
  if (!params_.resolve_crossings) return;
  std::vector<std::uint64_t> ids;
  ids.reserve(nodes_.size());
  for (const auto& entry : nodes_) ids.push_back(entry.first);
  std::sort(ids.begin(), ids.end(), std::greater<std::uint64_t>());
  IdQueue all(boost::container::ordered_unique_range, ids.begin(), ids.end());
  IdQueue cut;
  if (!params_.spatial_index)
  {
    resolveCrossings(std::move(all), nullptr, &cut);
    mergeCutSegments(std::move(cut));
    return;
  }
  // Most segments cross nothing: finding those that do is read-only and runs in parallel. The serial
  // pass then skips the others unless a pair resolved near them (resolveCrossings' suspects), which is
  // exactly when visiting them could find anything.
  if (index_stale_) rebuildIndex();
  std::vector<char> crosses(ids.size(), 0);
  parallelFor(
      arena, ids.size(), 256,
      [&](std::size_t i)
      {
        thread_local std::vector<Entry> hits;
        const Segment2& s = nodes_.at(ids[i]).segment;
        hits.clear();
        index_.query(bgi::intersects(boundingBox(s)), std::back_inserter(hits));
        for (const Entry& e : hits)
          if (e.second != ids[i] && segmentsCross(s, nodes_.at(e.second).segment, params_.crossing_overhang))
          {
            crosses[i] = 1;
            return;
          }
      });
  std::unordered_set<std::uint64_t> suspects;
  for (std::size_t i = 0; i < ids.size(); ++i)
    if (crosses[i]) suspects.insert(ids[i]);
  resolveCrossings(std::move(all), &suspects, &cut);
  mergeCutSegments(std::move(cut));
}

void CaeRlsm::rebuildIndex()
{
  index_stale_ = false;
  if (!params_.spatial_index) return;
  std::vector<Entry> entries;
  entries.reserve(nodes_.size());
  for (auto& [id, node] : nodes_)
  {
    node.box = indexedBox(node.segment);
    entries.emplace_back(node.box, id);
  }
  index_ = RTree(entries);  // bulk loading (packing) is much faster than inserting one by one
}

std::set<std::uint64_t> CaeRlsm::segmentsWithPartners(tbb::task_arena& arena) const
{
  std::vector<std::pair<std::uint64_t, const Node*>> all;
  all.reserve(nodes_.size());
  for (const auto& entry : nodes_) all.emplace_back(entry.first, &entry.second);
  std::vector<char> has_partner(all.size(), 0);
  parallelFor(arena, all.size(), 256,
              [&](std::size_t i)
              {
                thread_local std::vector<Entry> hits;
                has_partner[i] = hasCandidate(all[i].second->segment, all[i].first, hits, mapMeeting());
              });
  std::set<std::uint64_t> found;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (has_partner[i]) found.insert(all[i].first);
  return found;
}

std::size_t CaeRlsm::mergeConsistentSegments(tbb::task_arena& arena)
{
  std::size_t merged = 0;
  if (params_.spatial_index && index_stale_) rebuildIndex();
  // Most segments have no partner: finding those that do is read-only and runs in parallel. Skipping
  // the others changes nothing: a segment gains partners only through a merge near it, and every
  // merge below re-queues the segments near its result.
  std::set<std::uint64_t> pending = segmentsWithPartners(arena);
  std::vector<std::uint64_t> candidates;
  while (!pending.empty())
  {
    const std::uint64_t id = *pending.begin();
    pending.erase(pending.begin());
    auto it = nodes_.find(id);
    if (it == nodes_.end()) continue;
    findCandidates(it->second.segment, id, candidates, mapMeeting());
    if (candidates.empty()) continue;
    candidates.push_back(id);
    std::sort(candidates.begin(), candidates.end());
    Node& target = nodes_.at(candidates.front());
    for (std::size_t i = 1; i < candidates.size(); ++i)
    {
      auto other = nodes_.find(candidates[i]);
      indexRemove(candidates[i], other->second);
      target.leaves.insert(target.leaves.end(), other->second.leaves.begin(), other->second.leaves.end());
      nodes_.erase(other);
      ++merged;
    }
    refuse(target);
    indexUpdate(candidates.front(), target);
    // The merged segment and its neighbours may now meet the conditions with more segments.
    pending.insert(candidates.front());
    if (params_.spatial_index && !index_stale_)
    {
      // The stored boxes have slack: the segments whose exact boxes meet the target's.
      std::vector<Entry> near;
      const Box exact = paddedBox(target.segment);
      index_.query(bgi::intersects(exact), std::back_inserter(near));
      for (const Entry& e : near)
        if (boost::geometry::intersects(paddedBox(nodes_.at(e.second).segment), exact))
          pending.insert(e.second);
    }
    else
    {
      for (const auto& entry : nodes_) pending.insert(entry.first);
    }
  }
  return merged;
}

AdjustResult CaeRlsm::adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses)
{
  AdjustResult result;
  for (const auto& [index, pose] : poses)
    if (!(std::abs(pose.x) <= kMaxCoordinate && std::abs(pose.y) <= kMaxCoordinate &&
          std::isfinite(pose.theta)))
      throw std::invalid_argument("adjust: pose of keyframe " + std::to_string(index) +
                                  " is not finite or lies beyond " + std::to_string(kMaxCoordinate) + " m");
  tbb::task_arena arena(params_.threads > 0 ? params_.threads : tbb::task_arena::automatic);
  {
    const StepTimes<kStepCount>::Scope timed(steps_, kAdjustPoses);
    moveKeyframes(poses, arena, result);
  }
  if (result.moved == 0) return result;
  if (params_.consistent_adjustment && params_.regroup_on_adjust)
    result.merged = regroup();
  else
  {
    const StepTimes<kStepCount>::Scope timed(steps_, kAdjustRefuse);
    refuseAll(arena, result);
  }
  return result;
}

void CaeRlsm::moveKeyframes(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses,
                            tbb::task_arena& arena, AdjustResult& result)
{
  // Hash lookups and sines are a good part of the work for 1e5+ keyframes: done in parallel too.
  constexpr std::uint32_t kUnknown = UINT32_MAX;
  std::vector<std::uint32_t> slots(poses.size());
  parallelFor(arena, poses.size(), 1024,
              [&](std::size_t i)
              {
                auto it = slot_of_.find(poses[i].first);
                slots[i] = it == slot_of_.end() ? kUnknown : it->second;
              });
  for (std::size_t i = 0; i < poses.size(); ++i)
  {
    if (slots[i] == kUnknown)
    {
      ++result.unknown;
      continue;
    }
    const linemap::Pose2& pose = poses[i].second;
    keyframes_[slots[i]].pose = {pose.x, pose.y, linemap::normalizeAngle(pose.theta)};
    ++result.moved;
  }
  if (result.moved == 0) return;
  parallelFor(arena, keyframes_.size(), 1024,
              [&](std::size_t i)
              {
                const linemap::Pose2& p = keyframes_[i].pose;
                const double c = std::cos(p.theta), s = std::sin(p.theta);
                transforms_[i] << c, -s, p.x, s, c, p.y;
              });
}

void CaeRlsm::refuseAll(tbb::task_arena& arena, AdjustResult& result)
{
  std::vector<Node*> nodes;
  nodes.reserve(nodes_.size());
  for (auto& entry : nodes_) nodes.push_back(&entry.second);
  std::vector<std::vector<std::uint32_t>> split(params_.consistent_adjustment ? nodes.size() : 0);

  parallelFor(arena, nodes.size(), 64,
              [&](std::size_t i)
              {
                refuse(*nodes[i]);
                if (params_.consistent_adjustment) split[i] = splitInconsistentLeaves(*nodes[i]);
              });
  // Every box moved: the index is rebuilt in one go (bulk loading) when next searched.
  index_stale_ = true;
  if (!params_.consistent_adjustment)
  {
    resolveAllCrossings(arena);
    return;
  }

  // Split leaves re-enter in their original (chronological) order, through OTM-ILSM.
  std::vector<std::uint32_t> orphans;
  for (const auto& s : split) orphans.insert(orphans.end(), s.begin(), s.end());
  std::sort(orphans.begin(), orphans.end());
  result.split = orphans.size();
  for (std::uint32_t l : orphans) insertSegment(worldLeaf(l), l);
  result.merged = mergeConsistentSegments(arena);
  resolveAllCrossings(arena);
}

}  // namespace line_map_merging
