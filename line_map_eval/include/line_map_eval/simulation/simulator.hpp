// Scan simulator (ROS-free): exact ray casting against the wall faces of a World, a
// laser with Gaussian noise and spurious readings, a robot driving the world's
// closed path and drifting odometry. Deterministic for a given seed on every
// toolchain: std::mt19937 (fully specified) with our own uniform and normal draws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"

namespace line_map_eval
{
/// Random numbers that do not depend on the standard library's distributions.
/// `stream` separates independent sequences of one seed (laser, odometry).
class Random
{
 public:
  Random(std::uint32_t seed, std::uint32_t stream);
  double uniform();  ///< [0, 1), 53 random bits
  double normal();   ///< standard normal (Box-Muller)

 private:
  std::mt19937 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

/// Where one ray ends: the nearest face crossing in front of the origin.
struct RayHit
{
  double range = 0.0;  ///< +inf when the ray hits no face
  int face = -1;       ///< index into the faces, -1 for none
};

/// Exact nearest intersection of the ray origin + t (cos angle, sin angle), t > 0, with the
/// faces (wallFaces(): directed, free side on the left). A face is seen only from its left, as
/// the surface of a solid is only seen from outside: this is what makes the two coincident faces
/// of a thin wall each visible from one side only. Rays parallel to a face do not hit it.
RayHit castRay(const std::vector<linemap::Segment2>& faces, const linemap::Vec2& origin, double angle);

/// Noiseless hits of every beam of `laser` at `laser_pose` (map frame), no range limit.
std::vector<RayHit> castScan(const std::vector<linemap::Segment2>& faces, const linemap::Pose2& laser_pose,
                             const LaserModel& laser);

/// Measured ranges from true hits. Each beam is, with probability `laser.spurious`, a
/// reading uniform in [0, range_max); otherwise the true range r plus N(0, laser.sigmaAt(r)^2).
/// A beam whose result is no hit or >= range_max reads +inf (REP 117: no return; it is
/// also > range_max, so LaserScan consumers discard it). `spurious_flags` (optional)
/// receives 1 for the beams made spurious.
std::vector<double> measureScan(const std::vector<RayHit>& hits, const LaserModel& laser, Random& rng,
                                std::vector<std::uint8_t>* spurious_flags = nullptr);

/// The robot's true motion along the closed path of a world.
class PathFollower
{
 public:
  explicit PathFollower(const PathModel& path);
  double lapTime() const { return lap_time_; }
  /// True base_link pose at time t (seconds from the start, wraps around every lap).
  linemap::Pose2 poseAt(double t) const;

 private:
  struct Phase
  {
    double t0 = 0.0;  ///< start time of the phase
    double duration = 0.0;
    linemap::Pose2 from;  ///< pose at t0
    linemap::Vec2 velocity = linemap::Vec2::Zero();
    double turn = 0.0;  ///< signed heading change over the phase
  };
  std::vector<Phase> phases_;
  double lap_time_ = 0.0;
};

/// Odometry poses: the true per-scan relative motions with noise added by `model`, composed
/// from the true first pose (so odom and map coincide at the start).
std::vector<linemap::Pose2> driftOdometry(const std::vector<linemap::Pose2>& truth,
                                          const OdometryModel& model, Random& rng);

/// Registered keyframe poses: `truth` with the error of `model` (RegistrationModel), one draw per pose.
std::vector<linemap::Pose2> registrationErrors(const std::vector<linemap::Pose2>& truth,
                                               const RegistrationModel& model, Random& rng);

/// Overrides of the world's settings (the simulate_world command line).
struct SimulationOptions
{
  std::optional<std::uint32_t> seed;
  std::optional<std::size_t> scans;  ///< N scans spread evenly over one lap
  std::optional<std::size_t> beams;  ///< keeps the field of view
  std::optional<double> sigma;
  std::optional<double> spurious;
  std::optional<RegistrationModel> registration;  ///< replaces the world's `registration`
  bool drift = true;                              ///< false: odometry equals the true motion
  double start_time = 1.0;  ///< stamp of the first scan [s] (0 would mean "unset" to ROS)
  /// Called after each scan with (scans done, total), e.g. for a progress bar.
  std::function<void(std::size_t, std::size_t)> on_scan;
};

struct SimulationResult
{
  World world;  ///< the world with the options applied
  /// Scans with drifting odometry in `odom`, and every scan as a keyframe with its true base pose
  /// (with the world's registration error, when it has one).
  Recording recording;
  GroundTruth truth;
  double path_length = 0.0;  ///< of one lap [m]
};

/// The world with `options` applied (throws std::invalid_argument for impossible values).
World applyOptions(const World& world, const SimulationOptions& options);

/// Simulates one lap of the world's path.
SimulationResult simulate(const World& world, const SimulationOptions& options = {});

}  // namespace line_map_eval
