// CAE-RLSM: online one-to-many incremental line segment merging (OTM-ILSM) over a provenance tree,
// and multi-processing global map adjustment (MP-GMA) when an optimised trajectory arrives.
// One class, its parts in src/mergers/cae_rlsm/, a file per part:
//   cae_rlsm.cpp             parameters, addKeyframe, read access to the tree
//   otm_ilsm.cpp             OTM-ILSM: candidate search (R-tree) and insertion of a segment
//   map_merge.cpp            map-level merge (map segment against map segment)
//   regroup.cpp              regroup on adjustment, resumed from a checkpoint where nothing moved
//   crossing_resolution.cpp  no two map segments cross (bent walls into chains, T junctions)
//   mp_gma.cpp               MP-GMA: adjust() to new keyframe poses, the consistency pass
//   see_through.cpp          a later session retires the originals its scans see through
//   map_file.cpp             save() and load(): the map file (YAML)
//
// Provenance tree: root = the map; children = map segments (stable ids); leaves = the original
// segments in their keyframe's laser frame. Leaves are dropped only when a later session sees through
// them (see_through), so the map can always be rebuilt from them under new keyframe poses.
#pragma once

#include <tbb/task_arena.h>

#include <Eigen/Core>
#include <array>
#include <boost/container/flat_set.hpp>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cstdint>
#include <functional>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace YAML
{
class Emitter;
class Node;
}  // namespace YAML

namespace line_map_merging
{
struct CaeParams
{
  FusionParams fusion;
  int threads = 0;                    ///< MP-GMA worker threads; 0 = all cores
  bool consistent_adjustment = true;  ///< split/merge after re-fusing (off = the paper's behaviour)
  bool spatial_index = true;          ///< R-tree candidate search (off = linear reference search)
  /// Map-level merge: after each keyframe's OTM-ILSM, the map segments it touched are merged with
  /// every map segment they meet the fusion conditions with (either way round), until none is left;
  /// the consistency pass after MP-GMA uses the same symmetric test. Off = the paper's behaviour,
  /// where two map segments born apart stay apart unless one scan segment bridges them.
  bool map_merge = true;
  /// With map_merge: a map segment lying wholly inside another's fusion band (liesWithin) is merged
  /// into it even when their headings differ by more than theta_max, as short segments fitted to a
  /// wall's noisy glimpses do. Off = only the three fusion conditions.
  bool absorb_contained = true;
  /// After MP-GMA (with consistent_adjustment): regroup the leaves from scratch, OTM-ILSM over every
  /// leaf in arrival order under the new poses, instead of re-fusing each map segment's own leaves;
  /// ids carry over by the leaves. Groups formed on drifted poses otherwise stay as formed.
  bool regroup_on_adjust = true;
  /// With regroup_on_adjust: when the keyframes the last regroup covered kept their poses bit for bit,
  /// resume from the state it reached instead of starting again (regroup.cpp). The map is the same
  /// either way; off = always from scratch.
  bool incremental_regroup = true;
  /// Crossing resolution (crossing_resolution.cpp): no two map segments may cross (both running on past
  /// their intersection by more than crossing_overhang). A pair crossing at up to crossing_chain_angle
  /// (same facing side) is one bent wall: its originals are split at the bend, each side re-fused
  /// separately, and the two pieces cut at the vertex into a chain. A pair crossing at a larger angle
  /// loses its least supported arm (a T). Off = the paper's behaviour.
  bool resolve_crossings = true;
  double crossing_overhang = 0.01;  ///< [m] overhangs up to this are not crossings; >= 1 mm
  double crossing_chain_angle = 20.0 * linemap::kPi / 180.0;  ///< [rad] largest heading deviation of a chain
  /// A map segment all of whose originals come from one keyframe is withheld from map() while it is
  /// shorter than this [m]: a short piece seen once is no evidence of a wall yet (a person, a chair
  /// leg, noise), while a wall glimpsed in pieces through doors is seen again from other keyframes,
  /// and the first original of another keyframe fused into it admits it. Its originals stay in the
  /// provenance either way. 0 = every map segment is shown (the paper's behaviour).
  double single_view_min_length = 0.6;
  /// A map that follows the building (see_through.cpp): the space between a keyframe's laser and each
  /// segment it extracted is free, so an original of an EARLIER session lying in that space (by more
  /// than see_through_margin from its sides and from the segment) was seen through there: the wall it
  /// stood for is gone. An original is judged by parts (sixteenths of its length): one seen through by
  /// see_through_views keyframes (none seeing it in place since) over half of its parts is retired;
  /// its map segment is re-fused from the rest, or retired with its last original. Within one session nothing
  /// is retired: before a loop closes, the drift alone would make a scan see through the walls it mapped
  /// before.
  bool see_through = true;
  /// [m] Above the disagreement of two sessions' poses and the range noise, below a wall's distance
  /// from the next surface behind it (a door's depth, a room's width).
  double see_through_margin = 0.2;
  int see_through_views = 2;

  /// Reads the fusion block plus "threads", "consistent_adjustment", "spatial_index", "map_merge",
  /// "absorb_contained", "regroup_on_adjust", "incremental_regroup", "resolve_crossings",
  /// "crossing_overhang", "crossing_chain_angle", "single_view_min_length", "see_through",
  /// "see_through_margin", "see_through_views".
  static CaeParams fromParams(const linemap::ParamSet& params);
  /// Throws linemap::ParameterError naming the key for an out-of-range value.
  void validate() const;
};

class CaeRlsm : public Merger
{
 public:
  explicit CaeRlsm(const CaeParams& params = CaeParams());

  const char* name() const override { return "cae"; }
  AddResult addKeyframe(const Keyframe& keyframe) override;
  AddResult addOriginals(std::uint64_t keyframe, const std::vector<linemap::Segment2>& segments) override;
  AdjustResult adjust(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses) override;
  bool supportsAdjustment() const override { return true; }
  std::vector<MapSegment> map() const override;
  std::vector<KeyframeInfo> keyframes() const override;
  std::vector<Leaf> leaves(std::uint64_t id) const override;
  bool hasProvenance() const override { return true; }
  std::size_t keyframeCount() const override { return keyframes_.size(); }
  std::size_t leafCount() const override { return leaves_.size(); }
  /// Map segments map() shows (see single_view_min_length).
  std::size_t segmentCount() const override;
  void reset() override;
  std::unique_ptr<Merger> clone() const override { return std::make_unique<CaeRlsm>(*this); }
  void save(const std::string& path) const override;
  void load(const std::string& path) override;
  /// What save() writes: the map file's text (a session file carries it).
  std::string mapText() const;
  void loadText(const std::string& text, const std::string& origin) override;

  const CaeParams& params() const { return params_; }
  std::uint64_t nextId() const { return next_id_; }
  /// The session new keyframes join (KeyframeInfo::session).
  std::uint32_t session() const { return session_; }
  /// Originals and map segments retired as seen through (see_through) since construction or load.
  std::size_t retiredLeaves() const { return retired_leaves_; }
  std::size_t retiredSegments() const { return retired_segments_; }

  /// The steps of a keyframe (OTM-ILSM, map merge, crossing resolution) and of an adjustment.
  enum Step : std::size_t
  {
    kKeyframeOtm,
    kKeyframeMapMerge,
    kKeyframeCrossings,
    kAdjustPoses,
    kAdjustOtm,  ///< regroup: the keyframe steps again, counted apart
    kAdjustMapMerge,
    kAdjustCrossings,
    kAdjustIds,           ///< regroup: ids carried over, index rebuilt
    kAdjustRefuse,        ///< without regroup: re-fusing, the consistency pass, crossings
    kKeyframeSeeThrough,  ///< a continued session's keyframe: originals it sees through retired
    kStepCount
  };
  /// Regroups that resumed from the last one's state (incremental_regroup) since construction.
  std::size_t resumedRegroups() const { return checkpoint_.resumed; }
  void timeSteps(bool on) override { steps_.enable(on); }
  std::vector<StepTime> stepTimes() const override { return steps_.totals(); }

 private:
  using Point = boost::geometry::model::point<double, 2, boost::geometry::cs::cartesian>;
  using Box = boost::geometry::model::box<Point>;
  using Entry = std::pair<Box, std::uint64_t>;
  using RTree = boost::geometry::index::rtree<Entry, boost::geometry::index::quadratic<8>>;
  using Transform = Eigen::Matrix<double, 2, 3>;  // [R | t] of a keyframe pose
  /// Map segment ids to visit, smallest first, each once. Sorted downwards so the smallest leaves from
  /// the back: these sets hold a handful of ids, and a tree would allocate for each.
  using IdQueue = boost::container::flat_set<std::uint64_t, std::greater<std::uint64_t>>;
  static std::uint64_t popSmallest(IdQueue& queue)
  {
    const std::uint64_t id = *std::prev(queue.end());
    queue.erase(std::prev(queue.end()));
    return id;
  }

  /// An original is judged by parts (see_through): a keyframe sees through some of them, another the rest.
  static constexpr std::size_t kSeeThroughBins = 16;
  struct LeafRecord
  {
    std::uint32_t slot = 0;  // into keyframes_
    Segment2 local;
  };

  struct Node
  {
    Segment2 segment;
    FusionMoments moments;
    std::vector<std::uint32_t> leaves;  // into leaves_
    Box box;                            // as stored in the index
  };

  // OTM-ILSM (otm_ilsm.cpp).
  /// Returns the id of the map segment that now holds the leaf.
  std::uint64_t insertSegment(const Segment2& world, std::uint32_t leaf);
  /// Which map segments a segment is merged with.
  enum class Meeting
  {
    kAsScan,     ///< the fusion conditions with the segment as S (OTM-ILSM)
    kEitherWay,  ///< with either as M (map segment against map segment); with absorb_contained also
                 ///< either lying within the other
    kContained,  ///< either lying within the other (liesWithin) only
  };
  /// Map segments but `exclude` that `scan` meets by `rule`; in id order.
  void findCandidates(const Segment2& scan, std::uint64_t exclude, std::vector<std::uint64_t>& out,
                      Meeting rule = Meeting::kAsScan);
  /// Read-only, thread-safe: whether findCandidates would find any. Needs a fresh index (or the
  /// linear search); `hits` is the caller's scratch.
  bool hasCandidate(const Segment2& scan, std::uint64_t exclude, std::vector<Entry>& hits,
                    Meeting rule = Meeting::kAsScan) const;
  bool candidateMeets(const Segment2& map, const Segment2& scan, Meeting rule) const;
  /// The rule of the map-level merges: either way with map_merge, else as OTM-ILSM.
  Meeting mapMeeting() const { return params_.map_merge ? Meeting::kEitherWay : Meeting::kAsScan; }
  /// Map-level merge (map_merge.cpp): merges each pending map segment with the map segments it meets
  /// by `rule`, re-queueing the result, until none is left; the smallest id survives and takes the
  /// others' leaves. Returns how many map segments were merged away.
  /// `changed` (optional) receives the ids of the surviving segments that a merge changed.
  std::size_t mergeMapSegments(IdQueue pending, IdQueue* changed = nullptr,
                               Meeting rule = Meeting::kEitherWay);
  /// The segments (laser frame) of the keyframe in `slot` as new leaves, placed at its pose.
  void insertOriginals(std::uint32_t slot, const std::vector<Segment2>& segments, AddResult& result,
                       IdQueue& touched);
  /// After a keyframe's originals are in (addKeyframe, regroup): the map merge and crossing resolution
  /// of what they touched. `offset` is the step of kKeyframeOtm to count the steps at.
  void finishKeyframe(const IdQueue& touched, std::size_t offset);
  /// Crossing resolution (crossing_resolution.cpp): resolves every crossing of the pending map segments,
  /// re-queueing what it changes, until none of them crosses another. Returns how many pairs it resolved.
  /// With `suspects` (resolveAllCrossings): a pending segment not among them is skipped, and every
  /// segment near a resolved pair joins them. `cut` (optional) receives the ids of the resolved pairs.
  std::size_t resolveCrossings(IdQueue pending, std::unordered_set<std::uint64_t>* suspects = nullptr,
                               IdQueue* cut = nullptr);
  /// With map_merge and absorb_contained: the segments crossing resolution changed (`cut`) merged with
  /// those they lie within or that lie within them, and the crossing resolution of what that merge
  /// changed, in turn for a few rounds (crossing_resolution.cpp).
  void mergeCutSegments(IdQueue cut);
  /// One crossing pair at `x`, a < b. `trim_only`: cut, never move originals or merge.
  void resolvePair(std::uint64_t a, std::uint64_t b, const Vec2& x, bool trim_only, IdQueue& pending);
  /// A bent wall's pair: their originals split at the bend (the vertex moved with the split until it
  /// settles) and re-fused, `na` keeping the side before the bend when `a_before`; unchanged when the
  /// split does not settle.
  void splitAtBend(Node& na, Node& nb, const Vec2& x, bool a_before);
  /// Merges map segment `from` into `into` (leaves, re-fused); the caller re-queues `into`.
  void absorbNode(std::uint64_t into, std::uint64_t from);
  /// Rebuilds the map from the leaves under the current poses (regroup.cpp); each new map segment
  /// keeps the smallest old id among its leaves' not taken by a segment before it. Returns the count.
  std::size_t regroup();
  /// Whether the keyframes the checkpoint covers still have its transforms, bit for bit.
  bool checkpointStillHolds() const;
  /// After regroup(): the map segments renamed by their leaves' old ids (`old_id` by leaf), fresh ids
  /// from `first_fresh`.
  void keepOldIds(const std::vector<std::uint64_t>& old_id, std::uint64_t first_fresh);
  Box paddedBox(const Segment2& s) const;  // padded by the fusion conditions' reach
  /// The box a segment is stored under in the index: paddedBox with kIndexSlack to spare, so the
  /// entry outlives small changes of the segment (searches filter their hits exactly).
  Box indexedBox(const Segment2& s) const;
  static constexpr double kIndexSlack = 0.25;  ///< [m]
  static Box boundingBox(const Segment2& s, double pad = 0.0);
  /// A new map segment into the index; indexUpdate after it changed (re-stored only when it left its
  /// stored box); indexRemove before it is erased.
  void indexInsert(std::uint64_t id, Node& node);
  void indexUpdate(std::uint64_t id, Node& node);
  void indexRemove(std::uint64_t id, const Node& node);

  // See-through retirement (see_through.cpp).
  /// Votes with the keyframe at `slot` on the originals of earlier sessions in the free space before
  /// its segments (`local`, its laser frame), retires those seen through often enough and re-fuses
  /// or retires their map segments; the ids of map segments changed go to `changed`. Returns the
  /// number of originals retired.
  std::size_t retireSeenThrough(std::uint32_t slot, const std::vector<Segment2>& local, IdQueue& changed);
  /// Drops the `retired` leaves (sorted) from leaves_ and their map segments.
  void dropLeaves(const std::vector<std::uint32_t>& retired, IdQueue& changed);

  // MP-GMA (mp_gma.cpp).
  /// The keyframes' new poses and transforms (counted in `result`: moved, unknown).
  void moveKeyframes(const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses,
                     tbb::task_arena& arena, AdjustResult& result);
  /// Every map segment re-fused from its leaves under the new poses, then (consistent_adjustment) the
  /// consistency pass; crossings resolved.
  void refuseAll(tbb::task_arena& arena, AdjustResult& result);
  Segment2 worldLeaf(std::uint32_t leaf) const;
  void updateTransforms();
  void refuse(Node& node) const;
  /// refuse() from the node's leaves already in the map frame (`world`, in the order of node.leaves).
  void fuseWorld(Node& node, const std::vector<Segment2>& world) const;
  std::vector<std::uint32_t> splitInconsistentLeaves(Node& node) const;
  /// The map segments that have a merge partner (read-only, in parallel; needs a fresh index).
  std::set<std::uint64_t> segmentsWithPartners(tbb::task_arena& arena) const;
  std::size_t mergeConsistentSegments(tbb::task_arena& arena);
  void rebuildIndex();
  /// resolveCrossings over every map segment (with resolve_crossings), after re-fusing.
  void resolveAllCrossings(tbb::task_arena& arena);

  // The parts of load() (map_file.cpp), on a fresh state; each throws MapFileError naming the field.
  /// The map file's "segments": every node with its leaves, by id.
  void emitSegments(YAML::Emitter& out) const;
  void loadKeyframes(const std::string& path, const YAML::Node& root);
  void loadSegments(const std::string& path, const YAML::Node& root);
  LeafRecord readLeaf(const std::string& path, const YAML::Node& leaf) const;
  /// Puts the leaves in keyframe order, as they arrived (the file lists them by segment).
  void sortLeavesByKeyframe();

  CaeParams params_;
  std::vector<KeyframeInfo> keyframes_;  // by slot, in arrival order
  std::vector<Transform> transforms_;    // by slot
  std::unordered_map<std::uint64_t, std::uint32_t> slot_of_;
  std::vector<LeafRecord> leaves_;
  /// Whether map() shows the node (single_view_min_length).
  bool shown(const Node& node) const;

  std::unordered_map<std::uint64_t, Node> nodes_;
  /// The state the last regroup's pass reached, before its segments took their ids back.
  struct RegroupCheckpoint
  {
    bool valid = false;
    std::vector<Transform> transforms;  ///< of the keyframes it covers (slots 0..size-1)
    std::uint32_t leaves = 0;           ///< the leaves of those keyframes: 0..leaves-1
    std::unordered_map<std::uint64_t, Node> nodes;
    std::uint64_t next_id = 0;
    std::size_t resumed = 0;
  };
  RegroupCheckpoint checkpoint_;
  RTree index_;
  bool index_stale_ = false;  // set by adjust(): rebuilt in one go by the next search
  std::uint64_t next_id_ = 0;
  std::uint32_t session_ = 0;
  /// Per original a keyframe of a later session saw through, by leaf, per bin along it: keyframes that saw
  /// that part through since one saw it in place. Apart from the leaves: most never get a vote.
  std::unordered_map<std::uint32_t, std::array<std::uint8_t, kSeeThroughBins>> see_through_votes_;
  std::size_t retired_leaves_ = 0, retired_segments_ = 0;
  StepTimes<kStepCount> steps_{{"keyframe: OTM-ILSM", "keyframe: map merge", "keyframe: crossings",
                                "adjust: poses", "adjust: OTM-ILSM", "adjust: map merge", "adjust: crossings",
                                "adjust: ids and index", "adjust: re-fuse", "keyframe: see-through"}};
  mutable std::vector<std::uint64_t> candidates_;  // scratch
  mutable std::vector<Entry> hits_;                // scratch
};

}  // namespace line_map_merging
