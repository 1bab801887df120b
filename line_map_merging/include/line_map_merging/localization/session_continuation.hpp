// Continuing a saved session from an unknown start (ROS-free; the SLAM nodelet's ~session parameter, and
// line_map_eval's runSlam / runSessions offline, so both make the same map): the robot is first found in the
// saved keyframes' surfaces by global localization, scan after scan, the scans held meanwhile. At the first
// pose the localizer accepts that the way the robot came (its scans kept along the odometry) tells from every
// look-alike place (placement_judge.hpp), the SLAM continues the session (LaserSlam::continueFrom) from that
// scan; the
// scans searched before it are not mapped (carried back to them by the odometry, the start would take on the
// odometry's drift over the whole search). A start given up front (an initial pose) skips the search. When no
// pose is accepted within a number of scans the session is given up: the SLAM maps a new map in its own frame
// from the held scans on (none is lost), and the state says so. The search goes on meanwhile, on the SLAM's
// own poses as odometry (afterScan): once the robot is found in the saved map the SLAM joins it
// (LaserSlam::joinSession), in the frame it has been mapping in, once its own map tells the place from every
// look-alike one.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/localization/place_confirmation.hpp"
#include "line_map_merging/localization/placement_judge.hpp"
#include "line_map_merging/map/occupancy_grid.hpp"
#include "line_map_merging/slam/laser_slam.hpp"

namespace line_map_merging
{
/// The saved keyframes' surfaces (scan_surfaces) in the session's map frame: a line map to localize in.
std::vector<linemap::Segment2> sessionSurfaces(const SlamSession& session);

/// The saved keyframes' surfaces, each with the point it was seen from, in the session's map frame (the laser
/// taken at the base: the free-space margin covers the mounting).
std::vector<Sighting> sessionSightings(const SlamSession& session);

class SessionContinuation
{
 public:
  enum class State
  {
    kSearching,  ///< global localization in the saved map under way: the SLAM gets no scans yet
    kPlaced,     ///< the SLAM continues the session
    kGaveUp,     ///< not found in time: the SLAM maps a new map in its own frame, the search goes on
    kJoined,     ///< found later: the SLAM joined the saved session into its own frame
  };

  /// `search_scans`: scans to search before giving up (>= 1). `start`: the first scan's base pose in the
  /// session's map frame, when known (no search). Either is taken as known to `sigma_xy`, `sigma_theta`.
  SessionContinuation(SlamSession session, const LocalizerParams& localizer, std::size_t search_scans,
                      const std::optional<linemap::Pose2>& start = std::nullopt, double sigma_xy = 0.1,
                      double sigma_theta = 0.05);

  /// One scan, before the SLAM sees it: while searching it is localized and held (kSearching: the SLAM must
  /// not get it). At the accepted pose, or with a given start at the first scan, `slam` continues the session
  /// (kPlaced); when the search gives up, `slam` is left as it is (kGaveUp). Either way the caller then gives
  /// `slam` takeHeld() and this scan. Afterwards nothing happens and the state is returned. `sensor`: the
  /// laser's position in the base frame.
  State addScan(const SlamScan& scan, const linemap::Vec2& sensor, LaserSlam& slam);
  /// After the SLAM took `scan` (every scan, whatever the state): while the session is given up, the scan is
  /// searched for in the saved map with the SLAM's front-end pose as its odometry; at the pose accepted the
  /// SLAM joins the saved session (kJoined) once the place has held while the robot drove 5 m on (tracked
  /// throughout, each scan implying the same saved frame within 0.3 m and 0.05 rad) and the SLAM's own
  /// keyframes over the last join_window of path tell it from every look-alike place (PlacementJudge; a
  /// place found elsewhere than tracking held is refined on the last way_window): a place looking like
  /// another would otherwise join two maps for good. Otherwise nothing happens. Returns the state.
  State afterScan(const SlamScan& scan, const linemap::Vec2& sensor, LaserSlam& slam);
  /// A start given while the search is under way (an initial pose: RViz' 2D Pose Estimate): the next scan is
  /// placed at `start`, its base pose in the session's map frame, and the SLAM continues from it as with a
  /// start given up front. Returns false, changing nothing, once the search is over.
  bool giveStart(const linemap::Pose2& start);
  /// The scans held during the search that the SLAM is to take before the current one: after kGaveUp every
  /// scan searched, after kPlaced none; emptied.
  std::vector<SlamScan> takeHeld();

  State state() const { return state_; }
  /// Places the localizer accepted that the way the robot came did not tell from a rival place.
  std::size_t refusedAsAmbiguous() const { return ambiguous_; }
  /// Places the localizer accepted where, as at every rival place, the way contradicted the saved map's free
  /// space: taken all the same while no look-alike place was left open before (see judgedFrame()).
  std::size_t refusedAsSeenThrough() const { return seen_through_; }
  /// Scans searched so far (the one placed at included).
  std::size_t searched() const { return searched_; }
  /// Scans searched after giving up, up to the one the SLAM joined at (kJoined).
  std::size_t searchedApart() const { return searched_apart_; }
  /// The saved map frame's pose in the SLAM's map frame (kJoined).
  const std::optional<linemap::Pose2>& joinedAt() const { return joined_; }
  /// The accepted pose, of the scan placed at (searched() - 1), which the SLAM continued from (kPlaced).
  const std::optional<linemap::Pose2>& found() const { return found_; }
  const SlamSession& session() const { return session_; }
  /// A sentence for the diagnostics.
  std::string summary() const;

 private:
  /// The scan at `own` (base pose in the robot's own frame) kept on the way when one is due.
  void keep(const SlamScan& scan, const linemap::Vec2& sensor, const linemap::Pose2& own);
  /// The base pose `pose` the localizer gives in the saved map, `own` the same scan's in the robot's own
  /// frame: the base pose in the saved map at the place the whole way kept is judged to be
  /// (PlacementJudge), or nothing when it is not told from a look-alike place. When every place contradicts
  /// the saved map's free space, the localizer's pose.
  std::optional<linemap::Pose2> judged(const linemap::Pose2& pose, const linemap::Pose2& own);
  /// The same for `frame`, the robot's own frame in the saved map's as tracking put it, judged by `way` (kept
  /// in that own frame): the frame judged to be right, or nothing when it is not told from a look-alike
  /// place.
  std::optional<linemap::Pose2> judgedFrame(const Way& way, const linemap::Pose2& frame);
  /// A place confirmed after giving up (`implied`: the saved frame's pose in the SLAM's map frame), judged by
  /// the SLAM's own keyframes over the last join_window of path: the saved frame's pose to join at, or
  /// nothing.
  std::optional<linemap::Pose2> judgedJoin(const LaserSlam& slam, const linemap::Pose2& implied,
                                           const linemap::Vec2& sensor);

  /// [m]: the points of a sight thinned to this spacing; the way kept over this much path (the robot's own
  /// frame drifts: raw odometry during the search); points [m of wall at point_spacing] a place must explain
  /// better than every rival place.
  static constexpr double point_spacing = 0.1, way_window = 10.0, min_evidence = 1.0;
  /// [m], [rad]: a sight kept per this much path or turn. [m]: the SLAM's own path a join is judged over.
  static constexpr double sight_path = 0.5, sight_turn = 0.5, join_window = 50.0;
  /// The share of the best place's explained points an uncontradicted rival place needs to leave it open
  /// (PlacementJudge::judge).
  static constexpr double rival_share = 0.5;

  SlamSession session_;
  std::unique_ptr<LineMapLocalizer> localizer_;  ///< null with a given start
  std::unique_ptr<PlacementJudge> judge_;        ///< made at the first place found
  Way way_{sight_path, sight_turn, way_window};  ///< the robot's, in the frame the localizer's odometry is in
  std::size_t ambiguous_ = 0, seen_through_ = 0;
  std::vector<linemap::Pose2> rivals_;  ///< the places the last ambiguous verdict weighed
  std::size_t search_scans_;
  std::optional<linemap::Pose2> given_start_, found_;
  std::vector<SlamScan> held_;
  double sigma_xy_, sigma_theta_;
  PlaceConfirmation confirmation_;  ///< of a place found after giving up
  State state_ = State::kSearching;
  std::size_t searched_ = 0, searched_apart_ = 0;
  std::optional<linemap::Pose2> joined_;
};

}  // namespace line_map_merging
