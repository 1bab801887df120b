// Turns a raw CARMEN log (and optionally its corrected keyframe log) into a
// Recording: monotonic stamps, odometry of base_link, the laser mounting and
// corrected keyframe poses of base_link.
#pragma once

#include <cstddef>
#include <string>

#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/recording.hpp"

namespace line_map_eval
{
struct CarmenRecordingOptions
{
  /// Stamps are made strictly increasing: t_i = max(t_i, t_{i-1} + min_stamp_step) [s].
  double min_stamp_step = 1e-3;
  /// Value the sensor writes for "no return" [m]; 0 = found in the log (carmenNoReturnFloor: the
  /// largest reading and the codes printed within a few centimetres below it).
  /// range_max is set 5 mm below it (see carmenBeamGeometry).
  double no_return_range = 0.0;
  /// Readings beyond this are invalid too [m] (0 = no such limit).
  double max_usable_range = 0.0;
  /// Readings below this are invalid [m].
  double range_min = 0.0;
  /// Keep only the first this many scans (0 = all); keyframes beyond are dropped.
  std::size_t max_scans = 0;
  /// The scans' odometry from the ODOM lines even where their pose fields move: a corrected log, whose
  /// pose fields are the corrected poses and whose ODOM lines are the robot's odometry.
  bool odometry_from_odom_lines = false;
  /// [s] ODOM lines are interpolated at each scan's stamp plus this (fitOdometryDelay).
  double odometry_delay = 0.0;
};

/// What the conversion decided, for the tools' summaries.
struct CarmenRecordingReport
{
  std::size_t stamps_adjusted = 0;  ///< scans whose stamp was moved to keep time increasing
  double max_stamp_shift = 0.0;     ///< largest such move [s]
  std::string odometry_source;      ///< "scan odometry fields", "ODOM lines" or "scan laser poses"
  std::string mounting_source;      ///< where base_link->laser came from
  double no_return_range = 0.0;     ///< lowest value taken as "no return"
  std::size_t geometries = 0;       ///< distinct beam geometries among the scans
  /// Largest difference between a scan's own laser-vs-robot pose and the mounting taken from the
  /// first scan (translation [m], rotation [rad]); 0 unless the mounting came from the scan poses.
  double max_mounting_shift = 0.0, max_mounting_turn = 0.0;
};

/// Every raw scan becomes a RecordedScan (stamp, ranges, odometry of base_link).
///  - geometry: each scan's own (carmenScanGeometry); Recording::geometry is the first scan's, and
///    a scan whose geometry differs carries it in RecordedScan::geometry. No return: for FLASER
///    carmenNoReturnFloor of the log, for ROBOTLASER1/RAWLASER the line's maximum_range, unless
///    options.no_return_range is set.
///  - odometry: the FLASER odom fields / ROBOTLASER1 robot pose (robot_x/y/theta; the laser pose
///    is that pose composed with the mounting); when those are constant over the log but ODOM
///    lines move, ODOM interpolated at the scan stamps; with neither, the laser pose fields
///    composed with the inverse mounting. RAWLASER lines carry no pose: ODOM interpolated at the
///    scan stamp (the identity without ODOM lines). A log holding two RAWLASER sensors is refused.
///  - base_link->laser: for the front laser (FLASER, ROBOTLASER1, RAWLASER1) PARAM
///    robot_frontlaser_offset (forward offset in metres) of the raw log, else of the corrected log;
///    else laser pose relative to robot pose on the first line with both (robot^-1 * laser; the
///    largest deviation of the other lines is reported); else the identity.
///  - keyframes (when `corrected` is given): paired to raw scans by their ranges
///    (pairKeyframes); pose = corrected laser pose * (base_link->laser)^-1.
Recording fromCarmen(const CarmenLog& raw, const CarmenLog* corrected,
                     const CarmenRecordingOptions& options = {}, CarmenRecordingReport* report = nullptr);

/// A corrected log with ODOM lines: the delay (a multiple of `step` within +-max_delay seconds) at which
/// the ODOM lines' motion between consecutive scans best agrees with the motion of their pose fields (the
/// mean distance between the two). Logs of keyframes stamp their scans and the odometry with different
/// latencies; the odometry of a scan taken at its bare stamp is then off by the robot's speed times the
/// difference. 0 when the log has fewer than two scans or no ODOM lines.
double fitOdometryDelay(const CarmenLog& log, double max_delay = 0.5, double step = 0.01);

}  // namespace line_map_eval
