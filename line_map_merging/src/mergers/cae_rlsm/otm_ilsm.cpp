// OTM-ILSM (Algorithm 1 of CAE-RLSM): a new segment is fused with EVERY map segment that meets the
// fusion conditions with it, so one segment can bridge several map segments (e.g. the two ends
// of a wall seen at the start and the end of a loop). The group keeps the smallest id.
#include <algorithm>

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
namespace bgi = boost::geometry::index;

CaeRlsm::Box CaeRlsm::boundingBox(const Segment2& s, double pad)
{
  return Box(Point(std::min(s.start.x(), s.end.x()) - pad, std::min(s.start.y(), s.end.y()) - pad),
             Point(std::max(s.start.x(), s.end.x()) + pad, std::max(s.start.y(), s.end.y()) + pad));
}

CaeRlsm::Box CaeRlsm::paddedBox(const Segment2& s) const
{
  return boundingBox(s, params_.fusion.searchPadding());
}

CaeRlsm::Box CaeRlsm::indexedBox(const Segment2& s) const
{
  return boundingBox(s, params_.fusion.searchPadding() + kIndexSlack);
}

void CaeRlsm::indexInsert(std::uint64_t id, Node& node)
{
  if (!params_.spatial_index || index_stale_) return;
  node.box = indexedBox(node.segment);
  index_.insert(Entry(node.box, id));
}

void CaeRlsm::indexUpdate(std::uint64_t id, Node& node)
{
  if (!params_.spatial_index || index_stale_) return;
  // A segment that grew or moved a little still lies within its stored box: every search filters its
  // hits by the exact test, so the entry stays (most merges only lengthen a segment by a few cm).
  if (boost::geometry::covered_by(paddedBox(node.segment), node.box)) return;
  index_.remove(Entry(node.box, id));
  indexInsert(id, node);
}

void CaeRlsm::indexRemove(std::uint64_t id, const Node& node)
{
  if (!params_.spatial_index || index_stale_) return;
  index_.remove(Entry(node.box, id));
}

bool CaeRlsm::candidateMeets(const Segment2& map, const Segment2& scan, Meeting rule) const
{
  const auto contained = [&]
  { return liesWithin(map, scan, params_.fusion) || liesWithin(scan, map, params_.fusion); };
  switch (rule)
  {
    case Meeting::kAsScan:
      return meetsFusionConditions(map, scan, params_.fusion);
    case Meeting::kEitherWay:
      return meetEachOther(map, scan, params_.fusion) || (params_.absorb_contained && contained());
    case Meeting::kContained:
      return contained();
  }
  return false;
}

void CaeRlsm::findCandidates(const Segment2& scan, std::uint64_t exclude, std::vector<std::uint64_t>& out,
                             Meeting rule)
{
  out.clear();
  if (params_.spatial_index)
  {
    if (index_stale_) rebuildIndex();
    // Every map segment meeting the conditions has a point of `scan` inside its padded box; one
    // that `scan` meets as M has a point within the padding of `scan`'s box: the same test.
    const Box query = boundingBox(scan);
    hits_.clear();
    index_.query(bgi::intersects(query), std::back_inserter(hits_));
    for (const Entry& e : hits_)
      if (e.second != exclude && candidateMeets(nodes_.at(e.second).segment, scan, rule))
        out.push_back(e.second);
  }
  else
  {
    for (const auto& [id, node] : nodes_)
      if (id != exclude && candidateMeets(node.segment, scan, rule)) out.push_back(id);
  }
  // Fusing in id order makes the result independent of the search structure.
  std::sort(out.begin(), out.end());
}

bool CaeRlsm::hasCandidate(const Segment2& scan, std::uint64_t exclude, std::vector<Entry>& hits,
                           Meeting rule) const
{
  if (!params_.spatial_index)
  {
    for (const auto& [id, node] : nodes_)
      if (id != exclude && candidateMeets(node.segment, scan, rule)) return true;
    return false;
  }
  const Box query = boundingBox(scan);
  hits.clear();
  index_.query(bgi::intersects(query), std::back_inserter(hits));
  for (const Entry& e : hits)
    if (e.second != exclude && candidateMeets(nodes_.at(e.second).segment, scan, rule)) return true;
  return false;
}

std::uint64_t CaeRlsm::insertSegment(const Segment2& world, std::uint32_t leaf)
{
  std::vector<std::uint64_t>& candidates = candidates_;
  findCandidates(world, UINT64_MAX, candidates);
  if (candidates.empty())
  {
    const std::uint64_t id = next_id_++;
    Node& node = nodes_[id];
    node.segment = world;
    node.moments.add(world);
    node.leaves.push_back(leaf);
    indexInsert(id, node);
    return id;
  }

  Node& target = nodes_.at(candidates.front());
  FusionMoments moments = target.moments;
  for (std::size_t i = 1; i < candidates.size(); ++i) moments.add(nodes_.at(candidates[i]).moments);
  moments.add(world);

  FusedLine line(moments, params_.fusion.weighting);
  line.include(target.segment);
  line.include(world);
  for (std::size_t i = 1; i < candidates.size(); ++i)
  {
    auto it = nodes_.find(candidates[i]);
    Node& other = it->second;
    line.include(other.segment);
    indexRemove(candidates[i], other);
    target.leaves.insert(target.leaves.end(), other.leaves.begin(), other.leaves.end());
    nodes_.erase(it);
  }
  target.leaves.push_back(leaf);
  target.moments = moments;
  target.segment = line.segment();
  indexUpdate(candidates.front(), target);
  return candidates.front();
}

}  // namespace line_map_merging
