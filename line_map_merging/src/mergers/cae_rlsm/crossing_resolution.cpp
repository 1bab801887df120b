// Crossing resolution of CAE-RLSM (not in the paper): no two map segments may cross. A wall bent by a
// few degrees fuses piece by piece into chords that run past each other (every piece meets the fusion
// conditions with its neighbour, the far ends do not), and a segment fused across a gap can run through
// another wall. Both are resolved where the map segments are formed, after each keyframe's merge and
// after an adjustment, so the leaves and their provenance stay as they are.
//
// - Small angle, same facing side (a bend): the pair is one bent wall. Its originals are split at the
//   crossing by the side their midpoint lies on, each side is re-fused on its own and the vertex
//   recomputed, until the split settles; the pieces are then cut at their crossing into a chain. Each
//   segment keeps the side its originals support most (over both, the larger total). The re-fused lines
//   fit their own arm, so the vertex lands on the bend rather than where two chords happen to cross.
// - Larger angle, or opposite facing sides: two walls. Only the arm with the least support (length of
//   the originals' projections on it) is cut at the crossing, leaving a T: an overshoot or a fusion
//   across a gap is cut, a wall seen on both sides of the crossing stays whole.
// A cut can leave a segment wholly within another's fusion band: it is merged into it afterwards.
#include <algorithm>
#include <array>
#include <tuple>
#include <unordered_set>
#include <vector>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/mergers/crossing_pairs.hpp"

namespace line_map_merging
{
namespace bgi = boost::geometry::index;

namespace
{
struct Arms
{
  double before = 0.0;  ///< [m] support of the part from the start to the crossing
  double after = 0.0;   ///< [m] from the crossing to the end
};

/// Length of the leaves' projections onto s that falls on each side of x (a point of s), within s.
Arms armSupport(const Segment2& s, const std::vector<Segment2>& leaves, const Vec2& x)
{
  Arms arms;
  const Vec2 d = s.end - s.start;
  const double length = d.norm();
  if (!(length > 0.0)) return arms;
  const Vec2 u = d / length;
  const double tx = (x - s.start).dot(u);
  for (const Segment2& l : leaves)
  {
    const double a = (l.start - s.start).dot(u), b = (l.end - s.start).dot(u);
    const double lo = std::max(std::min(a, b), 0.0), hi = std::min(std::max(a, b), length);
    arms.before += std::max(0.0, std::min(hi, tx) - lo);
    arms.after += std::max(0.0, hi - std::max(lo, tx));
  }
  return arms;
}

/// Intersection of the infinite lines through a and b; false when they are (nearly) parallel.
bool lineIntersection(const Segment2& a, const Segment2& b, Vec2* x)
{
  const Vec2 r = a.end - a.start, s = b.end - b.start;
  const double denom = r.x() * s.y() - r.y() * s.x();
  if (!(std::abs(denom) > 1e-12 * r.norm() * s.norm())) return false;
  const Vec2 q = b.start - a.start;
  *x = a.start + ((q.x() * s.y() - q.y() * s.x()) / denom) * r;
  return x->allFinite();
}

/// The part of s before (start to x) or after (x to end) the point x of s.
Segment2 cut(const Segment2& s, const Vec2& x, bool keep_before)
{
  return keep_before ? Segment2(s.start, x) : Segment2(x, s.end);
}

/// Two walls crossing at x: the least supported of the four arms is cut off; on equal support the
/// shorter one.
void cutWeakestArm(Segment2& sa, Segment2& sb, const Arms& arms_a, const Arms& arms_b, const Vec2& x)
{
  struct Arm
  {
    double support, length;
    bool is_a, before;
  };
  const std::array<Arm, 4> candidates = {{{arms_a.before, (x - sa.start).norm(), true, true},
                                          {arms_a.after, (sa.end - x).norm(), true, false},
                                          {arms_b.before, (x - sb.start).norm(), false, true},
                                          {arms_b.after, (sb.end - x).norm(), false, false}}};
  const Arm& weakest =
      *std::min_element(candidates.begin(), candidates.end(),
                        [](const Arm& p, const Arm& q)
                        { return std::tie(p.support, p.length) < std::tie(q.support, q.length); });
  Segment2& s = weakest.is_a ? sa : sb;
  s = cut(s, x, !weakest.before);
}
}  // namespace

void CaeRlsm::absorbNode(std::uint64_t into, std::uint64_t from)
{
  Node& target = nodes_.at(into);
  const auto other = nodes_.find(from);
  indexRemove(from, other->second);
  target.leaves.insert(target.leaves.end(), other->second.leaves.begin(), other->second.leaves.end());
  nodes_.erase(other);
  refuse(target);
  indexUpdate(into, target);
}

void CaeRlsm::resolvePair(std::uint64_t a, std::uint64_t b, const Vec2& x, bool trim_only, IdQueue& pending)
{
  Node& na = nodes_.at(a);
  Node& nb = nodes_.at(b);
  const Segment2 sa = na.segment, sb = nb.segment;
  const auto world = [this](const Node& n)
  {
    std::vector<Segment2> w;
    w.reserve(n.leaves.size());
    for (std::uint32_t l : n.leaves) w.push_back(worldLeaf(l));
    return w;
  };
  const Arms arms_a = armSupport(sa, world(na), x), arms_b = armSupport(sb, world(nb), x);
  pending.insert(a);
  pending.insert(b);

  if (headingDeviation(sa, sb) > params_.crossing_chain_angle)
    cutWeakestArm(na.segment, nb.segment, arms_a, arms_b, x);
  else
  {
    // One bent wall, along a's direction (b runs the same way: same facing side). a keeps the side
    // before the crossing or after it, whichever gives the pair more support.
    const bool a_before = arms_a.before + arms_b.after >= arms_a.after + arms_b.before;
    if (!trim_only) splitAtBend(na, nb, x, a_before);
    // The pieces (or, unsplit, the chords) still run past each other by up to a leaf: cut both at
    // their crossing, each keeping its side.
    Vec2 y;
    if (segmentsCross(na.segment, nb.segment, params_.crossing_overhang, &y))
    {
      na.segment = cut(na.segment, y, a_before);
      nb.segment = cut(nb.segment, y, !a_before);
    }
    // Pieces short enough to meet the fusion conditions are one segment within the tolerance.
    if (!trim_only && params_.map_merge && candidateMeets(na.segment, nb.segment, Meeting::kEitherWay))
    {
      indexUpdate(a, na);
      indexUpdate(b, nb);
      absorbNode(a, b);
      pending.erase(b);
      return;
    }
  }
  indexUpdate(a, na);
  indexUpdate(b, nb);
}

void CaeRlsm::splitAtBend(Node& na, Node& nb, const Vec2& x, bool a_before)
{
  const Vec2 u = (na.segment.end - na.segment.start).normalized();
  std::vector<std::uint32_t> pool = na.leaves;
  pool.insert(pool.end(), nb.leaves.begin(), nb.leaves.end());
  std::sort(pool.begin(), pool.end());
  // The leaves in the map frame once, for every round.
  std::vector<Segment2> pool_world;
  pool_world.reserve(pool.size());
  for (std::uint32_t l : pool) pool_world.push_back(worldLeaf(l));
  std::vector<std::uint32_t> before, after, last_before;
  std::vector<Segment2> world_before, world_after;
  Node piece_before, piece_after;
  Vec2 vertex = x;
  bool settled = false;
  // The split moves the vertex, the vertex moves the split: a few rounds settle it.
  for (int round = 0; round < 8 && !settled; ++round)
  {
    before.clear();
    after.clear();
    world_before.clear();
    world_after.clear();
    for (std::size_t i = 0; i < pool.size(); ++i)
    {
      const bool is_after = (pool_world[i].midpoint() - vertex).dot(u) > 0.0;
      (is_after ? after : before).push_back(pool[i]);
      (is_after ? world_after : world_before).push_back(pool_world[i]);
    }
    if (before.empty() || after.empty()) break;
    settled = before == last_before;
    last_before = before;
    piece_before.leaves = before;
    piece_after.leaves = after;
    fuseWorld(piece_before, world_before);
    fuseWorld(piece_after, world_after);
    Vec2 next;
    if (!lineIntersection(piece_before.segment, piece_after.segment, &next)) break;
    vertex = next;
  }
  if (!settled) return;
  Node& keeps_before = a_before ? na : nb;
  Node& keeps_after = a_before ? nb : na;
  keeps_before.leaves = std::move(piece_before.leaves);
  keeps_before.moments = piece_before.moments;
  keeps_before.segment = piece_before.segment;
  keeps_after.leaves = std::move(piece_after.leaves);
  keeps_after.moments = piece_after.moments;
  keeps_after.segment = piece_after.segment;
}

std::size_t CaeRlsm::resolveCrossings(IdQueue pending, std::unordered_set<std::uint64_t>* suspects,
                                      IdQueue* cut)
{
  std::size_t resolved = 0;
  // Splitting and merging can lengthen segments; past this many pairs only cutting, which only
  // shortens, is done, so the loop ends.
  const std::size_t budget = 4 * pending.size() + 64;
  std::vector<std::uint64_t> near;
  while (!pending.empty())
  {
    const std::uint64_t id = popSmallest(pending);
    if (suspects && !suspects->count(id)) continue;  // crossed nothing, and nothing near it changed since
    const auto it = nodes_.find(id);
    if (it == nodes_.end()) continue;
    const Segment2& s = it->second.segment;
    near.clear();
    if (params_.spatial_index)
    {
      if (index_stale_) rebuildIndex();
      hits_.clear();
      // Crossing segments intersect, so their (padded) boxes do.
      index_.query(bgi::intersects(boundingBox(s)), std::back_inserter(hits_));
      for (const Entry& e : hits_) near.push_back(e.second);
    }
    else
    {
      for (const auto& entry : nodes_) near.push_back(entry.first);
    }
    std::sort(near.begin(), near.end());
    for (std::uint64_t other : near)
    {
      Vec2 x;
      if (other == id || !segmentsCross(s, nodes_.at(other).segment, params_.crossing_overhang, &x)) continue;
      resolvePair(std::min(id, other), std::max(id, other), x, resolved >= budget, pending);
      ++resolved;
      if (cut)
      {
        cut->insert(id);
        cut->insert(other);
      }
      if (suspects)
      {
        // Whatever the changed pair may cross now is a suspect again (the index is fresh after a pair).
        for (const std::uint64_t changed : {id, other})
        {
          const auto c = nodes_.find(changed);
          if (c == nodes_.end()) continue;
          suspects->insert(changed);
          hits_.clear();
          index_.query(bgi::intersects(boundingBox(c->second.segment)), std::back_inserter(hits_));
          for (const Entry& e : hits_) suspects->insert(e.second);
        }
      }
      break;  // id is queued again: its next partner is found with its new segment
    }
  }
  return resolved;
}

void CaeRlsm::mergeCutSegments(IdQueue cut)
{
  // A cut moves an end along its segment, which can leave the segment wholly within another's fusion
  // band: two chords of one bent wall, each cut at its own crossing, may end up along one line, one on
  // the other. Only such containment: pieces that merely meet the fusion conditions (overlapping chords
  // of a curved wall, left to the next keyframes' crossing resolution) would fuse a curve into a chord.
  // A segment that absorbed another grew as after a keyframe's merge: it is map-merged and resolved the
  // same way. A few rounds settle what is left.
  constexpr int kRounds = 3;
  for (int round = 0; round < kRounds && params_.map_merge && params_.absorb_contained && !cut.empty();
       ++round)
  {
    IdQueue absorbed;
    if (mergeMapSegments(std::move(cut), &absorbed, Meeting::kContained) == 0) return;
    IdQueue changed = absorbed;
    mergeMapSegments(std::move(absorbed), &changed, Meeting::kEitherWay);
    cut.clear();
    resolveCrossings(std::move(changed), nullptr, &cut);
  }
}

}  // namespace line_map_merging
