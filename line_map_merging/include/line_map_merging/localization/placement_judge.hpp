// Judging where a robot is in another map by the whole way it came (ROS-free): one scan rarely tells a place
// from a look-alike one (a ring corridor half a turn away, a symmetric atrium), the scans kept along the way,
// in the robot's own frame, often do. Two kinds of evidence: the points a place explains, and the free space
// the scans saw, which at a wrong place runs through the map's walls (free_space_witness.hpp). The placement
// of a fleet's robots in one map (FleetPlacement) judges by it, and so does a SLAM looking for itself in a
// saved session (SessionContinuation: the way along the odometry while searching, the SLAM's own keyframes
// before a join after mapping apart).
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/map/occupancy_grid.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
/// A scan kept along the way: the laser's pose in the robot's own frame, its points and the chords of the
/// space its beams crossed (in the laser frame; the triangle between the laser and a chord was seen free).
struct Sight
{
  linemap::Pose2 laser;
  std::vector<linemap::Vec2> points;
  std::vector<linemap::Segment2> free;
};

/// A sight from extracted segments: points every `spacing` along them; each segment's triangle is free.
Sight segmentSight(const linemap::Pose2& laser, const std::vector<linemap::Segment2>& segments,
                   double spacing);
/// A sight from a scan's returns in beam order (laser frame): the points thinned to `spacing` apart; the
/// beams grouped into fans of at most `fan` [rad] without a gap of `gap` [rad] (no return: unknown), each
/// fan's chord at its nearest return free.
Sight scanSight(const linemap::Pose2& laser, const std::vector<linemap::Vec2>& returns, double spacing,
                double fan = 0.3, double gap = 0.05);

/// The way a robot came: a sight per `spacing` [m] of path or `turn` [rad], over the last `window` [m] of
/// path (its own frame drifts: odometry over a long search).
class Way
{
 public:
  explicit Way(double spacing = 0.5, double turn = 0.5, double window = 1e9);

  /// The robot's laser moved to `laser` (its own frame): true when a sight is due there.
  bool move(const linemap::Pose2& laser);
  void add(Sight sight);
  /// Every sight's points in the robot's own frame.
  std::vector<linemap::Vec2> points() const;
  const std::deque<Sight>& sights() const { return sights_; }
  void clear();

 private:
  double spacing_, turn_, window_;
  std::deque<Sight> sights_;
  std::deque<double> sight_paths_;  ///< [m] the path up to each sight
  std::optional<linemap::Pose2> last_;
  double path_ = 0.0;
};

class PlacementJudge
{
 public:
  enum class Outcome
  {
    kPlaced,       ///< one place explains the way best and no other is near: place()
    kSeenThrough,  ///< every place that explains the way sees through the map's walls
    kAmbiguous,    ///< another place, its free space not contradicted either, explains the way about as well
  };
  struct Verdict
  {
    Outcome outcome = Outcome::kSeenThrough;
    linemap::Pose2 place;                ///< the robot's frame in the map's (kPlaced; kAmbiguous: the best)
    std::vector<linemap::Pose2> rivals;  ///< kAmbiguous: the places that left it open
  };

  /// `map`: the other map's segments; `params`: the localizer's (matching, global search, index cell).
  /// `margin` [m]: the free-space erosion (placement and registration error); `max_seen_through` [m]: the
  /// length of wall a place's sights may see through.
  PlacementJudge(const std::vector<linemap::Segment2>& map, const LocalizerParams& params,
                 double margin = 0.3, double max_seen_through = 1.0);

  /// Among `placed` (the robot's frame in the map's, as tracking put it) and every place the way's points
  /// are found at over the whole map (each refined by matching every point at once), the one that explains
  /// most points without its sights seeing through more than max_seen_through, and whether it leads every
  /// other such place by `min_evidence` points. Evidence is counted in points, not as a share: what tells
  /// look-alike places apart is a few pieces of furniture among metres of walls.
  /// `rival_share`: with the map's free space known (setMapFreeSpace), points in unknown space neither
  /// support nor contradict a place: a place at the map's edge explains less of the way than a look-alike
  /// inside it without being wrong. Then an uncontradicted rival explaining this share of the best's points
  /// leaves the place open too.
  /// A place that puts more of the way's points in the map's free space than twice another place does plus
  /// kContradictionShare of the points (and at least min_evidence) yields to that place when it explains
  /// `rival_share` of as much (the way may run out of the map there) and is not contradicted itself.
  /// `also`: the places of an earlier ambiguous verdict. Each stays a rival until contradicted, however
  /// little it explains: the way may since have run out of the map there, which is no evidence against it.
  Verdict judge(const Way& way, const linemap::Pose2& placed, double min_evidence, double rival_share = 1.0,
                const std::vector<linemap::Pose2>& also = {}) const;

  /// The way's points in the map's free space beyond what registration error and passers-by leave.
  static constexpr double kContradictionShare = 0.02;

  /// The space the map's own scans proved empty (its surfaces and the points they were seen from: a saved
  /// SLAM's keyframes), less a margin along every wall. Unknown space contradicts nothing; a place that puts
  /// the way's points in that free space is contradicted by them.
  void setMapFreeSpace(const std::vector<Sighting>& sightings);
  /// How many of `points` (the robot's frame at `placed`) lie where the map's scans saw free space.
  std::size_t pointsInFreeSpace(const std::vector<linemap::Vec2>& points, const linemap::Pose2& placed) const;

  /// `placed` refined by matching every point at once: unchanged when the match fails or slides farther
  /// than a place found by tracking can be off (PlaceConfirmation's bounds).
  linemap::Pose2 refined(const std::vector<linemap::Vec2>& points, const linemap::Pose2& placed) const;
  /// How many of `points` `pose` explains (the match score times their number).
  double explained(const std::vector<linemap::Vec2>& points, const linemap::Pose2& pose) const;
  /// The length [m] of the map that the sights, the robot's frame at `placed`, see through and nowhere see
  /// in place.
  double seenThroughLength(const Way& way, const linemap::Pose2& placed) const;
  /// Whether two places are distinct (the global search's separation).
  bool apart(const linemap::Pose2& a, const linemap::Pose2& b) const;

 private:
  /// What speaks against a place.
  struct Contradiction
  {
    double seen_through = 0.0;  ///< [m] seenThroughLength
    std::size_t in_free = 0;    ///< pointsInFreeSpace
  };
  struct Place
  {
    double score;  ///< points explained
    linemap::Pose2 pose;
    bool kept;  ///< one of `also`: a rival until contradicted, however little of the way it explains
    /// Weighed once, when first asked (contradictionOf).
    mutable std::optional<Contradiction> contradiction{};
  };
  /// The place's contradiction, weighed on first use: best() and judge() ask for many places twice.
  const Contradiction& contradictionOf(const Way& way, const std::vector<linemap::Vec2>& points,
                                       const Place& place) const;
  /// The best of `places` (judge()): not contradicted, and yielding to no other; null when none.
  const Place* best(const Way& way, const std::vector<linemap::Vec2>& points,
                    const std::vector<Place>& places, double min_evidence, double rival_share) const;
  SegmentMatch match(const std::vector<linemap::Vec2>& points, const linemap::Pose2& from) const;
  /// `placed` refined, `also` and the global search's candidates, each refined and scored, best first.
  std::vector<Place> weigh(const std::vector<linemap::Vec2>& points, const linemap::Pose2& placed,
                           const std::vector<linemap::Pose2>& also) const;

  std::vector<linemap::Segment2> map_;
  OccupancyGrid map_free_;  ///< kFree: seen free beyond the margin from every wall; empty without
  LocalizerParams params_;
  double margin_, max_seen_through_;
  LocalizationSegmentIndex index_;
  LocalizationGlobalSearch global_;
};

}  // namespace line_map_merging
