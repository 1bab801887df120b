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

std::size_t CaeRlsm::mergeMapSegments(IdQueue pending, IdQueue* changed, Meeting rule)
{
  std::size_t merged = 0;
  std::vector<std::uint64_t> candidates;
  while (!pending.empty())
  {
    const std::uint64_t id = popSmallest(pending);
    const auto it = nodes_.find(id);
    if (it == nodes_.end()) continue;  // merged away meanwhile
    findCandidates(it->second.segment, id, candidates, rule);
    if (candidates.empty()) continue;
    candidates.push_back(id);
    std::sort(candidates.begin(), candidates.end());
    // As in OTM-ILSM: the smallest id survives, takes the others' leaves and their summed moments.
    Node& target = nodes_.at(candidates.front());
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
    indexUpdate(candidates.front(), target);
    if (changed) changed->insert(candidates.front());
    // The fused segment moved and grew: it may now meet others.
    pending.insert(candidates.front());
  }
  return merged;
}

}  // namespace line_map_merging
