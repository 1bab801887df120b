// A map that follows the building: a keyframe of a later session that sees through an original of an
// earlier one votes to retire it. The witness is the keyframe's own segments: every beam that hit a
// segment crossed the triangle between the laser and that segment, so that triangle, eroded by the
// margin on its three sides, is free space. The parts of an original lying there were seen through by
// the keyframe; the parts lying along a segment (within the margin) were seen in place, which clears
// their votes. Parts, because one keyframe seldom sees a whole wall through: a wall gone from the middle
// of a room is seen through piece by piece as the robot drives past. Only originals of earlier sessions are
// judged: within a session, drift before a loop closes would see through the walls it mapped itself.
#include <algorithm>
#include <array>
#include <unordered_map>
#include <vector>

#include "line_map_merging/map/free_space_witness.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
namespace
{
namespace bgi = boost::geometry::index;
}  // namespace

std::size_t CaeRlsm::retireSeenThrough(std::uint32_t slot, const std::vector<Segment2>& local,
                                       IdQueue& changed)
{
  const Transform& t = transforms_[slot];
  const Vec2 laser = t.col(2);
  std::vector<FreeSpaceWitness> witnesses;
  witnesses.reserve(local.size());
  for (const Segment2& s : local)
  {
    if (!isValidSegment(s)) continue;
    const Segment2 world{t.leftCols<2>() * s.start + t.col(2), t.leftCols<2>() * s.end + t.col(2)};
    FreeSpaceWitness w;
    if (makeWitness(laser, world, params_.see_through_margin, w)) witnesses.push_back(w);
  }
  if (witnesses.empty()) return 0;

  // Per original of an earlier session near the witnesses: its bins seen through and seen in place.
  struct Seen
  {
    std::uint32_t through = 0, in_place = 0;
  };
  std::unordered_map<std::uint32_t, Seen> seen;
  std::vector<std::uint64_t> near;
  for (const FreeSpaceWitness& w : witnesses)
  {
    near.clear();
    if (params_.spatial_index)
    {
      if (index_stale_) rebuildIndex();
      hits_.clear();
      index_.query(bgi::intersects(Box(Point(w.box[0], w.box[1]), Point(w.box[2], w.box[3]))),
                   std::back_inserter(hits_));
      for (const Entry& e : hits_) near.push_back(e.second);
    }
    else
    {
      for (const auto& entry : nodes_) near.push_back(entry.first);
    }
    for (std::uint64_t id : near)
      for (std::uint32_t l : nodes_.at(id).leaves)
      {
        if (keyframes_[leaves_[l].slot].session >= session_) continue;
        const Segment2 world = worldLeaf(l);
        const std::uint32_t through = insideBins(world, w.free, 3, kSeeThroughBins);
        const std::uint32_t in_place = insideBins(world, w.band, 4, kSeeThroughBins);
        if (through == 0 && in_place == 0) continue;
        Seen& s = seen[l];
        s.through |= through;
        s.in_place |= in_place;
      }
  }

  std::vector<std::uint32_t> retired;
  const auto views = static_cast<std::uint8_t>(std::min(params_.see_through_views, 255));
  for (const auto& [l, s] : seen)
  {
    if (s.through == 0 && !see_through_votes_.count(l)) continue;  // seen in place, nothing to clear
    auto& bins = see_through_votes_[l];
    std::size_t gone = 0;
    for (std::size_t b = 0; b < kSeeThroughBins; ++b)
    {
      std::uint8_t& votes = bins[b];
      if (s.in_place & (1u << b))
        votes = 0;
      else if ((s.through & (1u << b)) && votes < 255)
        ++votes;
      gone += votes >= views;
    }
    if (2 * gone >= kSeeThroughBins) retired.push_back(l);
  }
  if (retired.empty()) return 0;
  std::sort(retired.begin(), retired.end());
  dropLeaves(retired, changed);
  return retired.size();
}

void CaeRlsm::dropLeaves(const std::vector<std::uint32_t>& retired, IdQueue& changed)
{
  // Renumber the leaves that stay, in order, so the arrival order a regroup replays is kept.
  std::vector<std::uint32_t> renumbered(leaves_.size(), UINT32_MAX);
  std::vector<LeafRecord> kept;
  kept.reserve(leaves_.size() - retired.size());
  auto next_retired = retired.begin();
  for (std::uint32_t l = 0; l < leaves_.size(); ++l)
  {
    if (next_retired != retired.end() && *next_retired == l)
    {
      ++next_retired;
      continue;
    }
    renumbered[l] = static_cast<std::uint32_t>(kept.size());
    kept.push_back(leaves_[l]);
  }
  leaves_ = std::move(kept);
  retired_leaves_ += retired.size();
  std::unordered_map<std::uint32_t, std::array<std::uint8_t, kSeeThroughBins>> votes;
  for (const auto& [l, bins] : see_through_votes_)
    if (renumbered[l] != UINT32_MAX) votes.emplace(renumbered[l], bins);
  see_through_votes_ = std::move(votes);

  std::vector<std::uint64_t> emptied;
  for (auto& [id, node] : nodes_)
  {
    const std::size_t before = node.leaves.size();
    std::vector<std::uint32_t> leaves;
    leaves.reserve(before);
    for (std::uint32_t l : node.leaves)
      if (renumbered[l] != UINT32_MAX) leaves.push_back(renumbered[l]);
    node.leaves = std::move(leaves);
    if (node.leaves.empty())
      emptied.push_back(id);
    else if (node.leaves.size() != before)
    {
      refuse(node);
      indexUpdate(id, node);
      changed.insert(id);
    }
  }
  for (std::uint64_t id : emptied)
  {
    indexRemove(id, nodes_.at(id));
    nodes_.erase(id);
  }
  retired_segments_ += emptied.size();
  // The regroup checkpoint names leaves by their old numbers.
  checkpoint_ = RegroupCheckpoint{false, {}, 0, {}, 0, checkpoint_.resumed};
}

}  // namespace line_map_merging
