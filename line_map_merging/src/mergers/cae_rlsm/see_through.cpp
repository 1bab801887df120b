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

#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_merging
{
namespace
{
namespace bgi = boost::geometry::index;

double cross(const Vec2& a, const Vec2& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// A half-plane h(x) = n.x - c >= 0.
struct HalfPlane
{
  Vec2 n;
  double c;
};

/// The bins of a leaf (CaeRlsm::kSeeThroughBins, by position along it) whose centres lie inside every
/// half-plane (Liang-Barsky clipping), as a bit mask.
std::uint32_t insideBins(const Segment2& s, const HalfPlane* planes, std::size_t count, std::size_t bins)
{
  const Vec2 d = s.end - s.start;
  double lo = 0.0, hi = 1.0;
  for (std::size_t i = 0; i < count && lo < hi; ++i)
  {
    const double at_start = planes[i].n.dot(s.start) - planes[i].c;
    const double slope = planes[i].n.dot(d);
    if (slope == 0.0)
    {
      if (at_start < 0.0) return 0;
      continue;
    }
    const double t = -at_start / slope;
    if (slope > 0.0)
      lo = std::max(lo, t);
    else
      hi = std::min(hi, t);
  }
  std::uint32_t mask = 0;
  for (std::size_t b = 0; b < bins; ++b)
  {
    const double centre = (static_cast<double>(b) + 0.5) / static_cast<double>(bins);
    if (centre >= lo && centre <= hi) mask |= 1u << b;
  }
  return mask;
}

/// What one extracted segment shows: the free triangle before it, and the band along it.
struct Witness
{
  HalfPlane free[3];          // inside both sides' rays and before the segment, each by the margin
  HalfPlane band[4];          // within the rays, and within the margin of the segment's line
  std::array<double, 4> box;  // min x, min y, max x, max y of the triangle
};

/// The witness of `segment` (map frame) seen from `laser`; false when it shows nothing (a segment
/// through the laser, or too short to leave a free triangle after the erosion).
bool makeWitness(const Vec2& laser, Segment2 segment, double margin, Witness& w)
{
  Vec2 a = segment.start - laser, b = segment.end - laser;
  if (cross(a, b) < 0.0) std::swap(a, b);  // counter-clockwise: the inside is left of o->a, right of o->b
  const double na = a.norm(), nb = b.norm(), ab = (b - a).norm();
  if (na == 0.0 || nb == 0.0 || ab <= 2.0 * margin) return false;
  const Vec2 ua = a / na, ub = b / nb;
  // Outward normal of the segment's side (away from the laser) and the laser's distance from its line.
  const Vec2 outward = Vec2((b - a).y(), -(b - a).x()) / ab;
  const double distance = outward.dot(a);
  if (distance <= margin) return false;
  // In laser-relative coordinates x' = x - laser: n.x' - c >= 0  <=>  n.x - (c + n.laser) >= 0.
  const HalfPlane left{Vec2(-ua.y(), ua.x()), 0.0};   // cross(ua, x') >= 0
  const HalfPlane right{Vec2(ub.y(), -ub.x()), 0.0};  // cross(x', ub) >= 0
  const HalfPlane before{-outward, -distance};        // outward.x' <= distance
  const HalfPlane behind{outward, distance};          // outward.x' >= distance
  const auto shifted = [&](const HalfPlane& h, double by) {
    return HalfPlane{h.n, h.c + by + h.n.dot(laser)};
  };
  w.free[0] = shifted(left, margin);
  w.free[1] = shifted(right, margin);
  w.free[2] = shifted(before, margin);
  w.band[0] = shifted(left, 0.0);
  w.band[1] = shifted(right, 0.0);
  w.band[2] = shifted(before, -margin);
  w.band[3] = shifted(behind, -margin);
  w.box = {std::min({laser.x(), segment.start.x(), segment.end.x()}),
           std::min({laser.y(), segment.start.y(), segment.end.y()}),
           std::max({laser.x(), segment.start.x(), segment.end.x()}),
           std::max({laser.y(), segment.start.y(), segment.end.y()})};
  return true;
}

}  // namespace

std::size_t CaeRlsm::retireSeenThrough(std::uint32_t slot, const std::vector<Segment2>& local,
                                       IdQueue& changed)
{
  const Transform& t = transforms_[slot];
  const Vec2 laser = t.col(2);
  std::vector<Witness> witnesses;
  witnesses.reserve(local.size());
  for (const Segment2& s : local)
  {
    if (!isValidSegment(s)) continue;
    const Segment2 world{t.leftCols<2>() * s.start + t.col(2), t.leftCols<2>() * s.end + t.col(2)};
    Witness w;
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
  for (const Witness& w : witnesses)
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
