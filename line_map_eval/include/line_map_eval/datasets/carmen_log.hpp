// ROS-free reader for CARMEN log files (plain, gzip or bzip2, detected by their
// magic bytes). Understands FLASER, ROBOTLASER1, RAWLASER1..4, ODOM and PARAM lines;
// comment lines (#), NEFF and every other message type are skipped.
//
//   FLASER n r_1..r_n x y theta odom_x odom_y odom_theta timestamp hostname logger_timestamp
//   ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy remission_mode
//               n r_1..r_n m rem_1..rem_m laser_x laser_y laser_theta robot_x robot_y robot_theta
//               tv rv forward_safety_dist side_safety_dist turn_axis timestamp hostname logger_timestamp
//   RAWLASERx   laser_type start_angle fov angular_resolution max_range accuracy remission_mode
//               n r_1..r_n m rem_1..rem_m timestamp hostname logger_timestamp      (x = 1..4, no pose)
//   ODOM x y theta tv rv accel timestamp hostname logger_timestamp
//   PARAM name value [timestamp hostname logger_timestamp]
//
// ROBOTLASER1 and RAWLASERx state their beam geometry on every line, and it may change from line
// to line: each scan keeps its own (carmenScanGeometry). Their n beams, angular_resolution apart,
// must span field_of_view to within half a beam, fov - res/2 <= n*res and (n-1)*res <= fov + res/2
// (n = fov/res, or fov/res + 1 with a beam at both ends); other counts make the line malformed.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"

namespace line_map_eval
{
enum class CarmenScanType
{
  FLaser,
  RobotLaser1,
  RawLaser  ///< RAWLASER1..4: no pose on the line
};

struct CarmenScan
{
  CarmenScanType type = CarmenScanType::FLaser;
  std::vector<float> ranges;  ///< [m], as written (no-return readings carry the sensor maximum)
  Pose2 laser_pose;           ///< FLASER x y theta; ROBOTLASER1 laser pose; RAWLASER none (identity)
  Pose2 robot_pose;           ///< FLASER odom_x odom_y odom_theta; ROBOTLASER1 robot pose; RAWLASER none
  double timestamp = 0.0;
  double logger_timestamp = 0.0;
  std::size_t line = 0;  ///< 1-based line number in the file

  // ROBOTLASER1 and RAWLASER only (left at their defaults for FLASER).
  int raw_laser = 0;  ///< x of RAWLASERx (1..4), 0 for the other types
  int laser_type = -1;
  double start_angle = 0.0;
  double field_of_view = 0.0;
  double angular_resolution = 0.0;
  double max_range = 0.0;
  double accuracy = 0.0;
  int remission_mode = 0;
  std::vector<float> remissions;
  // ROBOTLASER1 only.
  double tv = 0.0, rv = 0.0;
  double forward_safety_dist = 0.0, side_safety_dist = 0.0, turn_axis = 0.0;
};

struct CarmenOdom
{
  Pose2 pose;
  double tv = 0.0, rv = 0.0, accel = 0.0;
  double timestamp = 0.0;
  double logger_timestamp = 0.0;
  std::size_t line = 0;
};

struct CarmenLog
{
  std::string path;  ///< as given to the reader, used in messages
  std::vector<CarmenScan> scans;
  std::vector<CarmenOdom> odometry;
  std::map<std::string, std::string> params;  ///< PARAM name -> first value token (last one wins)
  std::size_t lines = 0;                      ///< lines read
  std::size_t skipped_unknown = 0;            ///< comments, NEFF and other message types
  std::size_t skipped_bad = 0;                ///< lenient mode: malformed lines dropped
  std::vector<std::string> problems;          ///< lenient mode: the first messages about dropped lines
};

struct CarmenReadOptions
{
  /// false: the first malformed line throws std::runtime_error("<file>:<line>: ...").
  /// true: malformed lines are dropped and counted in CarmenLog::skipped_bad.
  bool lenient = false;
  /// Lines longer than this are malformed (a 361-beam FLASER line is about 3 kB).
  std::size_t max_line_length = 1 << 16;
  /// Stop after this many scans (0 = read everything).
  std::size_t max_scans = 0;
};

/// Reads a CARMEN log file; throws std::runtime_error naming the file (and line) on failure.
CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options = {});

/// Parses an already decompressed log held in memory; `name` is used in messages.
CarmenLog parseCarmenLog(const std::string& text, const std::string& name,
                         const CarmenReadOptions& options = {});

/// The whole content of a plain, gzip or bzip2 file (by magic bytes), decompressed.
std::string readMaybeCompressedFile(const std::string& path);

/// For each scan of `corrected` (keyframes of a corrected log), the index of the raw
/// scan with identical range values. Pairs are strictly increasing: the keyframes
/// appear in the same order in both logs. Throws std::runtime_error naming the
/// corrected file and line when a keyframe has no match after the previous one.
std::vector<std::size_t> pairKeyframes(const CarmenLog& raw, const CarmenLog& corrected);

/// Beam geometry of an n-beam CARMEN scan spanning 180 degrees centred on the heading:
/// increment pi/n for even n, pi/(n-1) for odd n, angle_min = -(n-1)*increment/2.
/// `no_return` is the value written for beams without a return; range_max is set
/// half a centimetre (half the logs' print resolution) below it, so that a reading
/// r is valid iff range_min <= r <= range_max (sensor_msgs/LaserScan semantics).
ScanGeometry carmenBeamGeometry(std::size_t beam_count, double no_return, double range_min = 0.0);

/// The beam geometry a scan's line states. ROBOTLASER1/RAWLASER: angle_min = start_angle,
/// angle_increment = angular_resolution (field_of_view / (n - 1) when that is not positive);
/// FLASER: carmenBeamGeometry(n). range_max is 5 mm below `no_return`, or, when that is not
/// positive, below the line's maximum_range (ROBOTLASER1/RAWLASER; FLASER needs `no_return`).
ScanGeometry carmenScanGeometry(const CarmenScan& scan, double no_return, double range_min = 0.0);

/// Readings within this fraction below the largest reading of a log may be no-return codes.
constexpr double kNoReturnSpan = 0.01;
/// Largest step between neighbouring distinct no-return codes [m]: logs print the sensor maximum
/// with a jitter of a few centimetres (81.87, 81.89 and 81.91 m in one log).
constexpr double kNoReturnStep = 0.05;

/// The lowest value a log writes for "no return" (0 when it holds no reading). Sensors write their
/// maximum for beams without a return, not always exactly the same value: the distinct readings
/// from the largest one downwards, each within kNoReturnStep of the next larger one and all within
/// kNoReturnSpan of the largest, are taken as no-return codes. A real reading stands apart (ACES:
/// 50.0 written for no return, real readings up to 49.91 m) and stays valid.
double carmenNoReturnFloor(const CarmenLog& log);

}  // namespace line_map_eval
