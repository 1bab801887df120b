// Confirming a place found in another map before two maps are joined for good (ROS-free): a place found by
// global localization in a map with look-alike rooms may be wrong, so it must hold while the robot drives on,
// tracked at every scan, each scan implying the same pose of the other map's frame in the robot's own.
// Shared by a SLAM that joins a saved session after mapping apart (SessionContinuation) and by the placement
// of a fleet's robots in one map (FleetPlacement).
#pragma once

#include "linemap/geometry.hpp"

namespace line_map_merging
{
class PlaceConfirmation
{
 public:
  enum class Verdict
  {
    kHolding,    ///< the place holds so far
    kBroken,     ///< a scan implied another frame: the place is given up (search again)
    kConfirmed,  ///< held over the whole path: implied() is the other map's frame
  };

  /// `path` [m]: how far the robot must drive with the place holding.
  explicit PlaceConfirmation(double path = 5.0) : path_(path) {}

  /// One scan tracked in the other map: `implied` is the other map's frame in the robot's own as this scan
  /// puts it, `travelled` [m] the robot's path so far, `fresh` whether the localizer has just accepted a new
  /// place (it starts the confirmation again).
  Verdict add(const linemap::Pose2& implied, double travelled, bool fresh);
  /// A scan not tracked: the confirmation starts again at the next place.
  void reset() { started_ = false; }
  /// The frame the first scan of the confirmation implied.
  const linemap::Pose2& implied() const { return implied_; }

  /// How far each scan's implied frame may lie from the first's.
  static constexpr double max_xy = 0.3, max_theta = 0.05;

 private:
  double path_;
  bool started_ = false;
  linemap::Pose2 implied_;
  double start_path_ = 0.0;
};

}  // namespace line_map_merging
