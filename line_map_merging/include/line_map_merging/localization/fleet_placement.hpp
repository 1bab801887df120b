// Placing a fleet's robots in one map (ROS-free; the merging nodelet's ~robots, and the offline two-robot
// run): every robot maps in its own frame with its own SLAM; the first robot's map frame is the fleet's.
// Each other robot is looked for in the fleet's line map by global localization, scan after scan, its own
// SLAM's poses serving as odometry and its extracted segments, sampled into points, as the scan. Its map
// frame is placed where a found place holds while it drives on (PlaceConfirmation) and where the robot's
// scans so far see through none of the fleet's walls (free_space_witness.hpp): the fleet's map may not yet
// hold the robot's true place, but a look-alike one (a ring corridor half a turn away), and there the scans
// of the way it came see through walls the fleet mapped. Then it is done with.
// Not thread-safe: the caller serialises the calls.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/localization/place_confirmation.hpp"
#include "line_map_merging/localization/placement_judge.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
class FleetPlacement
{
 public:
  /// `confirm_path` [m]: how far a robot must drive with a found place holding before it is placed there;
  /// `point_spacing` [m]: the distance between the points sampled along a segment.
  explicit FleetPlacement(const LocalizerParams& params, double confirm_path = 10.0,
                          double point_spacing = 0.05);

  /// The fleet's map (segments in the fleet's frame) changed: every search goes on in it.
  void setMap(const std::vector<linemap::Segment2>& segments);

  /// One segment set of robot `robot` (not placed yet): `segments` in the laser frame, `laser` the laser's
  /// pose in the robot's own map frame at `stamp`, `mount` base -> laser. Returns the robot's map frame in
  /// the fleet's frame when this scan confirms it (once); nothing otherwise, or for a placed robot.
  std::optional<linemap::Pose2> addScan(std::size_t robot, double stamp,
                                        const std::vector<linemap::Segment2>& segments,
                                        const linemap::Pose2& laser, const linemap::Pose2& mount);

  /// The length [m] of `map` (fleet frame) that `robot`'s scans so far, its map frame placed at `placed`,
  /// see through and nowhere see in place.
  double seenThroughLength(std::size_t robot, const linemap::Pose2& placed,
                           const std::vector<linemap::Segment2>& map) const;

  /// Whether a placement of `robot`'s map frame apart from `placed` explains its scans so far within
  /// min_evidence of as well as `placed` does (against `map`, the fleet's).
  bool ambiguous(std::size_t robot, const linemap::Pose2& placed,
                 const std::vector<linemap::Segment2>& map) const;

  /// Where robot `robot`'s map frame was placed; nothing before.
  std::optional<linemap::Pose2> placement(std::size_t robot) const;
  /// The scans looked for so far of robot `robot`.
  std::size_t searched(std::size_t robot) const;
  /// A sentence per robot for the diagnostics.
  std::vector<std::pair<std::string, std::string>> diagnostics() const;

 private:
  struct Search
  {
    explicit Search(double confirm_path) : way(sight_spacing, sight_turn), confirmation(confirm_path) {}
    Way way;  ///< a sight per sight_spacing of path or sight_turn, the laser in the robot's own map frame
    std::unique_ptr<LineMapLocalizer> localizer;
    PlaceConfirmation confirmation;
    std::optional<linemap::Pose2> last_base;  ///< in the robot's own map frame
    double travelled = 0.0;
    std::size_t scans = 0;
    std::optional<linemap::Pose2> placed;
    std::size_t refused = 0;    ///< confirmed places refused as seeing through the fleet's walls
    std::size_t ambiguous = 0;  ///< confirmed places refused as a rival explained the way about as well
  };
  /// Sights kept every this much path [m] or turn [rad]; the free-space margin [m] (placement and
  /// registration error); the length seen through [m] that refuses a placement.
  static constexpr double sight_spacing = 0.5, sight_turn = 0.5, see_through_margin = 0.3,
                          max_seen_through = 1.0;
  /// [m] of points (at point_spacing) the placement must explain better than every rival placement.
  static constexpr double min_evidence = 1.0;
  double minEvidencePoints() const { return min_evidence / point_spacing_; }

  LocalizerParams params_;
  double confirm_path_, point_spacing_;
  std::vector<linemap::Segment2> map_;
  std::map<std::size_t, Search> searches_;
};

/// Points every `spacing` along each segment (both ends included), moved by `pose`.
std::vector<linemap::Vec2> segmentPoints(const std::vector<linemap::Segment2>& segments,
                                         const linemap::Pose2& pose, double spacing);

}  // namespace line_map_merging
