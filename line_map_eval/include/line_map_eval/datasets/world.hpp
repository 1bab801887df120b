// A simulated world (ROS-free): true walls, the closed path the robot drives,
// its laser and its odometry error model, read from config/worlds/*.yaml.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "line_map_eval/simulation/wall_faces.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
/// The laser: `beams` beams spread evenly over `fov` (centred on the laser's x axis).
struct LaserModel
{
  std::size_t beams = 361;
  double fov = linemap::kPi;               ///< [rad]; YAML key fov_deg in degrees
  double range_min = 0.02;                 ///< [m]
  double range_max = 30.0;                 ///< [m]
  double sigma = 0.01;                     ///< Gaussian range noise at range 0 [m]
  double sigma_slope = 0.0;                ///< growth of the noise std with range [m per m]
  double spurious = 0.0;                   ///< fraction of readings replaced by uniform [0, range_max]
  linemap::Pose2 mounting{0.1, 0.0, 0.0};  ///< base_link -> laser

  double angleMin() const { return -0.5 * fov; }
  double angleIncrement() const { return beams > 1 ? fov / static_cast<double>(beams - 1) : 0.0; }
  /// Std of the range noise of a reading at true range r: sigma + sigma_slope r (spot size and
  /// return energy degrade with distance, so far readings scatter more).
  double sigmaAt(double r) const { return sigma + sigma_slope * r; }
};

/// Odometry error accumulated per scan step (random walks plus a systematic curve).
struct OdometryModel
{
  double translation_noise = 0.0;  ///< [m / sqrt(m)] std of x and y error after 1 m
  double rotation_noise = 0.0;     ///< [rad / sqrt(rad)] std of heading error after turning 1 rad
  double heading_noise = 0.0;      ///< [rad / sqrt(m)] std of heading error after driving 1 m
  double heading_bias = 0.0;       ///< [rad / m] systematic heading error (unequal wheels)

  bool isZero() const
  {
    return translation_noise == 0.0 && rotation_noise == 0.0 && heading_noise == 0.0 && heading_bias == 0.0;
  }
};

/// Error of the keyframes' registered ("corrected") poses, as a SLAM back end or a corrected log leaves
/// it: a stationary random process along the path (first order, correlation length in metres of
/// travel), so neighbouring keyframes agree and distant ones do not, and a wall seen from many of them
/// is smeared across by their disagreement. The scans, the odometry and the ground truth are unchanged.
struct RegistrationModel
{
  double position = 0.0;             ///< [m] std of x and of y
  double heading = 0.0;              ///< [rad] std; YAML key heading_deg in degrees
  double correlation_length = 10.0;  ///< [m] of path (a turn in place counts 1 m per rad)

  bool isZero() const { return position == 0.0 && heading == 0.0; }
};

/// The closed path: the robot starts at waypoints[0] facing waypoints[1], drives each leg
/// straight at `speed`, turns in place at `turn_rate` at each waypoint, and after the last
/// waypoint drives back to the first. A scan is taken every `scan_period` over one lap.
struct PathModel
{
  std::vector<linemap::Vec2> waypoints;
  double speed = 0.5;        ///< [m/s]
  double turn_rate = 0.8;    ///< [rad/s]
  double scan_period = 0.2;  ///< [s]
  std::size_t scans = 0;     ///< 0: one lap at scan_period; N: N scans spread evenly over one lap
  double clearance = 0.2;    ///< [m] minimum distance of the path from every wall (checked on load)
};

/// Thickness of a wall whose entry gives none, when the world file has no `wall_thickness` [m]:
/// an interior partition (drywall on studs) is 10-15 cm; the laser then sees both faces of a wall
/// as two lines 10 cm apart, as in a real building.
inline constexpr double kDefaultWallThickness = 0.10;

/// Largest sagitta of an arc's pieces when the world file has no `arc_sagitta` [m]: the range noise
/// std of our finest sensor profile at range 0, so no laser tells the chain from the true arc,
/// while the pieces stay tens of centimetres long on radii of metres.
inline constexpr double kDefaultArcSagitta = 0.005;

struct World
{
  std::string name;    ///< YAML `name`, else the file's base name
  std::string source;  ///< the file it came from (for messages)
  std::vector<Wall> walls;
  /// A world `based_on` another (the same building at a later session): the base file as resolved
  /// (relative to this file's directory), the base's walls its `changes` took out, in the order of
  /// `changes.remove`, and the walls it put in, in the order of `changes.add` (an arc's pieces in
  /// turn); `walls` is the base's walls less the removed ones, in the base's order, then the added
  /// ones. Empty for a world of its own (and relative to the direct base in a chain of them).
  std::string based_on;
  std::vector<Wall> removed_walls;
  std::vector<Wall> added_walls;
  double wall_thickness = kDefaultWallThickness;  ///< YAML `wall_thickness`: of walls without their own [m]
  double arc_sagitta = kDefaultArcSagitta;        ///< YAML `arc_sagitta`: bound of the arcs' pieces [m]
  PathModel path;
  LaserModel laser;
  OdometryModel odometry;
  RegistrationModel registration;
  /// A face is listed as visible in a scan when hit by this many beams: 1, every glimpse, so that the
  /// ground truth can accumulate sightings over scans (the evaluator decides what counts as seen).
  std::size_t min_visible_beams = 1;
  std::uint32_t seed = 1;
};

/// Reads a world file. Throws std::runtime_error naming the file, the key and the line
/// for a missing key, a malformed value or a path that runs into a wall.
///
/// A file with `based_on: FILE` (relative to its own directory) is the base world changed: its
/// `changes: {remove: [[x1, y1, x2, y2], ...], add: [WALL, ...]}` take out the base's walls with
/// those centre lines (to 1e-6 m, either direction; one that matches none is an error) and add walls
/// written as in `walls`. Its other top-level keys replace the base's whole (`name`, `seed`,
/// `min_visible_beams`, `path`, `laser`, `odometry`, `registration`); `walls`, `wall_thickness` and
/// `arc_sagitta` are refused. Bases may be based_on others in turn; a cycle is an error.
World loadWorld(const std::string& path);

/// Same from YAML text; `source` names it in error messages and, when it is a file, a relative
/// `based_on` is relative to its directory (else to the current directory).
World parseWorld(const std::string& yaml_text, const std::string& source);

/// A sensor profile (config/sensors/*.yaml): an optional `name` and a `laser` block with the keys
/// of a world's `laser` block, which replace those of `base` key by key (a key it omits keeps the
/// world's value). Throws std::runtime_error naming the file, the key and the line.
struct SensorProfile
{
  std::string name;  ///< YAML `name`, else the file's base name
  LaserModel laser;
};
SensorProfile loadSensorProfile(const std::string& path, const LaserModel& base = {});
SensorProfile parseSensorProfile(const std::string& yaml_text, const std::string& source,
                                 const LaserModel& base = {});

/// `world` seen with the sensor of `profile_path`: its laser replaced, its name "<world> / <profile>".
World withSensorProfile(const World& world, const std::string& profile_path);

/// The value of a `--pose-noise POSITION,HEADING_DEG[,CORRELATION_LENGTH]` option (metres, degrees,
/// metres); throws std::invalid_argument naming `option` for a malformed or negative value.
RegistrationModel parseRegistrationOption(const std::string& option, const std::string& value);

/// Checks the values and that every leg of the path keeps `clearance` from every wall's surface
/// (its centre line less half its thickness); throws std::runtime_error naming `world.source`
/// and the offending key.
void validateWorld(const World& world);

/// Length of the closed path [m] (including the leg back to the start).
double pathLength(const PathModel& path);

}  // namespace line_map_eval
