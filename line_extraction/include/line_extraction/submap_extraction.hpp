// Line extraction over a local submap: the points a scan's extractor left unexplained are kept
// for the last few metres of travel, registered by the laser's pose in a fixed frame (odometry),
// and searched for lines there. A wall seen in pieces (through doors, behind furniture, or with
// too few points per scan at long range and coarse beams) gathers enough points over several
// scans; clutter seen from many sides does not line up. ROS-free.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "line_extraction/line_fit.hpp"
#include "line_extraction/residual_lines.hpp"
#include "line_extraction/sensor_model.hpp"
#include "line_extraction/types.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
using linemap::Pose2;

/// Keys of the "submap" block of config/line_extraction.yaml.
struct SubmapParams
{
  bool enabled = false;
  /// Scans enter the window after the laser moved or turned this much since the last one that
  /// did (the merger's keyframe gate by default: one scan of a standing robot is no new view).
  double scan_distance = 0.2;     ///< [m]
  double scan_angle = 0.1745329;  ///< [rad]
  /// Path length the window covers [m]: short enough that odometry registers it within noise.
  double window_distance = 4.0;
  int window_scans = 40;  ///< at most this many scans in the window
  /// The tests of a line ("submap/band_sigmas" ...; the count of scans is "submap/min_scans"): a
  /// blob of clutter has a line through it, but also points beside it; a wall is not seen through.
  ResidualLineParams lines;

  /// Reads the "submap/..." keys; throws linemap::ParameterError naming a bad one.
  static SubmapParams fromParams(const linemap::ParamSet& params);
};

class SubmapExtractor
{
 public:
  SubmapExtractor(const SubmapParams& params, const SensorModel& sensor);

  /// Offers one scan: its prepared points, what the per-scan extractor made of them and the
  /// laser's pose in a fixed frame. Returns the submap segments to publish with this scan, in its
  /// laser frame, oriented with their observers on the left. Segments found when a scan entered
  /// the window are returned again with every following scan until the next one enters, so that
  /// a consumer keeping only some scans (a keyframe gate) still receives them. The result stays
  /// valid until the next call.
  const std::vector<Segment>& update(const PreparedScan& scan, const ExtractionResult& extracted,
                                     const Pose2& laser_pose);

  /// update() for a live scan: appends the submap segments to `result`, which is what the
  /// per-scan extractor made of `scan` (their points are in no scan, so they carry no member
  /// indices). Returns how many were appended.
  std::size_t appendTo(const PreparedScan& scan, ExtractionResult& result, const Pose2& laser_pose);

  /// A live scan's stamp [ns], offered before anything else is done with the scan: the window is
  /// forgotten when it lies before the previous one (the clock jumped back: a bag looped).
  void observeStamp(std::uint64_t stamp_ns);

  /// Forgets the window (a time jump, a new session).
  void reset();

  const SubmapParams& params() const { return params_; }
  std::size_t windowPoints() const { return points_.size(); }
  /// Submap lines found so far.
  std::size_t linesFound() const { return lines_found_; }

 private:
  bool admits(const Pose2& laser) const;
  void addResiduals(const PreparedScan& scan, const ExtractionResult& extracted, const Pose2& laser);
  void dropOldScans();
  void findLines(std::size_t first_new);
  void emit(const Pose2& laser);

  SubmapParams params_;
  SensorModel sensor_;
  std::vector<ResidualSource> scans_;  ///< of the window, oldest first
  std::vector<double> scan_paths_;     ///< path length travelled up to each of scans_ [m]
  std::vector<ResidualPoint> points_;  ///< in scan order
  ResidualLineFinder finder_;
  std::uint32_t next_scan_id_ = 0;
  bool has_last_ = false;
  Pose2 last_admitted_;
  double path_ = 0.0;
  /// Found when the last scan entered, in the fixed frame, with their points.
  std::vector<std::pair<ResidualLine, std::vector<Vec2>>> pending_;
  std::vector<Segment> output_;
  std::size_t lines_found_ = 0;
  std::uint64_t last_stamp_ns_ = 0;
};

}  // namespace line_extraction
