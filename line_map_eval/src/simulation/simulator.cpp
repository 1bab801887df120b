// Scan simulator: ray casting, laser noise, path following and odometry drift.
#include "line_map_eval/simulation/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace line_map_eval
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();

using linemap::cross;
}  // namespace

Random::Random(std::uint32_t seed, std::uint32_t stream)
{
  // seed_seq's mixing is specified by the standard, so streams are portable.
  std::seed_seq seq{seed, stream, 0x6c6d6576u};
  engine_.seed(seq);
}

double Random::uniform()
{
  const std::uint64_t a = engine_() >> 5;                                  // 27 bits
  const std::uint64_t b = engine_() >> 6;                                  // 26 bits
  return static_cast<double>((a << 26) | b) * (1.0 / 9007199254740992.0);  // / 2^53
}

double Random::normal()
{
  if (has_spare_)
  {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform();  // (0, 1]: log stays finite
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double phi = 2.0 * linemap::kPi * u2;
  spare_ = r * std::sin(phi);
  has_spare_ = true;
  return r * std::cos(phi);
}

RayHit castRay(const std::vector<Segment2>& faces, const Vec2& origin, double angle)
{
  const Vec2 u(std::cos(angle), std::sin(angle));
  RayHit best{kInf, -1};
  for (std::size_t i = 0; i < faces.size(); ++i)
  {
    // Solve origin + t u = start + s e for (t, s) by Cramer's rule.
    const Vec2 e = faces[i].end - faces[i].start;
    const double denom = cross(u, e);
    // Seen from the left only: the ray must run against the outward normal, cross(u, e) > 0.
    // Parallel: grazing rays see nothing.
    if (denom <= 1e-12 * e.norm()) continue;
    const Vec2 w = faces[i].start - origin;
    const double t = cross(w, e) / denom;
    const double s = cross(w, u) / denom;
    if (t > 1e-12 && s >= 0.0 && s <= 1.0 && t < best.range) best = {t, static_cast<int>(i)};
  }
  return best;
}

std::vector<RayHit> castScan(const std::vector<Segment2>& faces, const Pose2& laser_pose,
                             const LaserModel& laser)
{
  std::vector<RayHit> hits(laser.beams);
  const double a0 = laser_pose.theta + laser.angleMin(), da = laser.angleIncrement();
  for (std::size_t i = 0; i < laser.beams; ++i)
    hits[i] = castRay(faces, laser_pose.translation(), a0 + static_cast<double>(i) * da);
  return hits;
}

std::vector<double> measureScan(const std::vector<RayHit>& hits, const LaserModel& laser, Random& rng,
                                std::vector<std::uint8_t>* spurious_flags)
{
  std::vector<double> ranges(hits.size());
  if (spurious_flags) spurious_flags->assign(hits.size(), 0);
  for (std::size_t i = 0; i < hits.size(); ++i)
  {
    double r;
    if (laser.spurious > 0.0 && rng.uniform() < laser.spurious)
    {
      r = rng.uniform() * laser.range_max;
      if (spurious_flags) (*spurious_flags)[i] = 1;
    }
    else
    {
      r = hits[i].range;
      const double sigma = std::isfinite(r) ? laser.sigmaAt(r) : 0.0;
      if (sigma > 0.0) r = std::max(0.0, r + sigma * rng.normal());
    }
    ranges[i] = r < laser.range_max ? r : kInf;
  }
  return ranges;
}

PathFollower::PathFollower(const PathModel& path)
{
  const auto& wp = path.waypoints;
  const std::size_t n = wp.size();
  if (n < 2) throw std::invalid_argument("PathFollower: at least 2 waypoints are needed");
  if (!(path.speed > 0.0) || !(path.turn_rate > 0.0))
    throw std::invalid_argument("PathFollower: speed and turn_rate must be > 0");
  std::vector<double> heading(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const Vec2 d = wp[(i + 1) % n] - wp[i];
    heading[i] = std::atan2(d.y(), d.x());
  }
  double t = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const Vec2 d = wp[(i + 1) % n] - wp[i];
    Phase drive;
    drive.t0 = t;
    drive.duration = d.norm() / path.speed;
    drive.from = Pose2(wp[i].x(), wp[i].y(), heading[i]);
    drive.velocity = d / drive.duration;
    phases_.push_back(drive);
    t += drive.duration;

    // Turn in place at the end of the leg towards the next one.
    const double turn = linemap::normalizeAngle(heading[(i + 1) % n] - heading[i]);
    if (turn != 0.0)
    {
      Phase rotate;
      rotate.t0 = t;
      rotate.duration = std::abs(turn) / path.turn_rate;
      const Vec2& p = wp[(i + 1) % n];
      rotate.from = Pose2(p.x(), p.y(), heading[i]);
      rotate.turn = turn;
      phases_.push_back(rotate);
      t += rotate.duration;
    }
  }
  lap_time_ = t;
}

Pose2 PathFollower::poseAt(double t) const
{
  t = std::fmod(t, lap_time_);
  if (t < 0.0) t += lap_time_;
  // Last phase starting at or before t.
  const auto it = std::upper_bound(phases_.begin(), phases_.end(), t,
                                   [](double value, const Phase& p) { return value < p.t0; });
  const Phase& p = it == phases_.begin() ? phases_.front() : *std::prev(it);
  const double dt = std::clamp(t - p.t0, 0.0, p.duration);
  const Vec2 pos = p.from.translation() + dt * p.velocity;
  return {pos.x(), pos.y(), linemap::normalizeAngle(p.from.theta + p.turn * (dt / p.duration))};
}

std::vector<Pose2> driftOdometry(const std::vector<Pose2>& truth, const OdometryModel& m, Random& rng)
{
  std::vector<Pose2> odom;
  odom.reserve(truth.size());
  if (truth.empty()) return odom;
  odom.push_back(truth.front());
  for (std::size_t k = 1; k < truth.size(); ++k)
  {
    // The true motion in the previous base frame, corrupted like wheel odometry: random walks
    // growing with the square root of distance / rotation, plus a heading bias per metre.
    const Pose2 d = truth[k - 1].inverse() * truth[k];
    const double dist = std::hypot(d.x, d.y);
    const double rot = std::abs(d.theta);
    const double nx = rng.normal(), ny = rng.normal(), nr = rng.normal(), nh = rng.normal();
    const double st = m.translation_noise * std::sqrt(dist);
    const Pose2 noisy(d.x + st * nx, d.y + st * ny,
                      d.theta + m.rotation_noise * std::sqrt(rot) * nr +
                          m.heading_noise * std::sqrt(dist) * nh + m.heading_bias * dist);
    odom.push_back(odom.back() * noisy);
  }
  return odom;
}

std::vector<Pose2> registrationErrors(const std::vector<Pose2>& truth, const RegistrationModel& m,
                                      Random& rng)
{
  std::vector<Pose2> registered;
  registered.reserve(truth.size());
  double ex = 0.0, ey = 0.0, eh = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k)
  {
    // First-order (Ornstein-Uhlenbeck) process over the travelled distance: stationary at the model's
    // stds, and correlated over correlation_length of path.
    double rho = 0.0;
    if (k > 0)
    {
      const Pose2 d = truth[k - 1].inverse() * truth[k];
      rho = std::exp(-(std::hypot(d.x, d.y) + std::abs(d.theta)) / m.correlation_length);
    }
    const double fresh = std::sqrt(1.0 - rho * rho);
    ex = rho * ex + fresh * m.position * rng.normal();
    ey = rho * ey + fresh * m.position * rng.normal();
    eh = rho * eh + fresh * m.heading * rng.normal();
    const Pose2& t = truth[k];
    registered.emplace_back(t.x + ex, t.y + ey, linemap::normalizeAngle(t.theta + eh));
  }
  return registered;
}

World applyOptions(const World& world, const SimulationOptions& o)
{
  World w = world;
  if (o.seed) w.seed = *o.seed;
  if (o.scans)
  {
    if (*o.scans < 1) throw std::invalid_argument("scans must be >= 1");
    w.path.scans = *o.scans;
  }
  if (o.beams)
  {
    if (*o.beams < 2) throw std::invalid_argument("beams must be >= 2");
    w.laser.beams = *o.beams;
  }
  if (o.sigma)
  {
    if (!(*o.sigma >= 0.0) || !std::isfinite(*o.sigma))
      throw std::invalid_argument("noise sigma must be >= 0");
    w.laser.sigma = *o.sigma;
  }
  if (o.spurious)
  {
    if (!(*o.spurious >= 0.0 && *o.spurious <= 1.0))
      throw std::invalid_argument("spurious fraction must be in [0, 1]");
    w.laser.spurious = *o.spurious;
  }
  if (!o.drift) w.odometry = OdometryModel{};
  if (o.registration)
  {
    const RegistrationModel& r = *o.registration;
    if (!(r.position >= 0.0) || !(r.heading >= 0.0) || !(r.correlation_length > 0.0) ||
        !std::isfinite(r.position + r.heading + r.correlation_length))
      throw std::invalid_argument(
          "registration error: position and heading must be >= 0, correlation "
          "length > 0");
    w.registration = r;
  }
  return w;
}

namespace
{
/// The recording's sensor geometry, mounting and source, before any scan.
void beginRecording(const World& w, Recording& rec)
{
  const LaserModel& laser = w.laser;
  rec.geometry.angle_min = laser.angleMin();
  rec.geometry.angle_increment = laser.angleIncrement();
  rec.geometry.beam_count = laser.beams;
  rec.geometry.range_min = laser.range_min;
  rec.geometry.range_max = laser.range_max;
  rec.base_to_laser = laser.mounting;
  rec.source = "simulated world " + w.name + " (" + w.source + "), seed " + std::to_string(w.seed);
}

/// The ground truth's sensor, solids, faces and curves, before any scan.
void beginTruth(const World& w, GroundTruth& gt)
{
  const LaserModel& laser = w.laser;
  gt.world = w.name;
  gt.laser = {laser.beams,     laser.angleMin(), laser.angleIncrement(), laser.range_min,
              laser.range_max, laser.sigma,      laser.spurious,         laser.sigma_slope};
  gt.base_to_laser = laser.mounting;
  gt.min_beams = w.min_visible_beams;
  gt.solids = w.walls;
  const std::vector<WallFace> faces = wallFaces(w.walls);
  gt.walls = faceSegments(faces);
  gt.curves = curveFaces(w.walls, faces);
}

/// The faces one scan sees. Visibility is geometric: beams whose noiseless reading would be valid.
std::vector<VisibleWall> visibleFaces(const std::vector<RayHit>& hits, const Pose2& laser_pose,
                                      const World& w, const GroundTruth& gt)
{
  const LaserModel& laser = w.laser;
  std::vector<int> hit_wall(laser.beams);
  std::vector<double> hit_range(laser.beams);
  for (std::size_t i = 0; i < laser.beams; ++i)
  {
    const bool valid =
        hits[i].face >= 0 && hits[i].range >= laser.range_min && hits[i].range < laser.range_max;
    hit_wall[i] = valid ? hits[i].face : -1;
    hit_range[i] = hits[i].range;
  }
  return visibleWallPieces(gt.walls, laser_pose, laser.angleMin(), laser.angleIncrement(), hit_wall,
                           hit_range, w.min_visible_beams, gt.curves);
}
}  // namespace

SimulationResult simulate(const World& input, const SimulationOptions& options)
{
  SimulationResult res;
  res.world = applyOptions(input, options);
  const World& w = res.world;
  const LaserModel& laser = w.laser;
  const PathFollower follower(w.path);
  res.path_length = pathLength(w.path);

  // One lap: either every scan_period, or the requested count spread evenly.
  const double lap = follower.lapTime();
  const std::size_t count =
      w.path.scans > 0
          ? w.path.scans
          : std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(lap / w.path.scan_period + 1e-9)));
  const double period = w.path.scans > 0 ? lap / static_cast<double>(count) : w.path.scan_period;

  std::vector<Pose2> truth_base(count);
  for (std::size_t k = 0; k < count; ++k) truth_base[k] = follower.poseAt(static_cast<double>(k) * period);
  Random odom_rng(w.seed, 2);
  const std::vector<Pose2> odom = driftOdometry(truth_base, w.odometry, odom_rng);
  Random registration_rng(w.seed, 3);
  const std::vector<Pose2> registered =
      w.registration.isZero() ? truth_base : registrationErrors(truth_base, w.registration, registration_rng);

  Recording& rec = res.recording;
  GroundTruth& gt = res.truth;
  beginRecording(w, rec);
  beginTruth(w, gt);
  gt.registration_position = w.registration.position;
  gt.registration_heading = w.registration.heading;

  Random laser_rng(w.seed, 1);
  for (std::size_t k = 0; k < count; ++k)
  {
    const double stamp = options.start_time + static_cast<double>(k) * period;
    const Pose2 laser_pose = truth_base[k] * laser.mounting;
    const std::vector<RayHit> hits = castScan(gt.walls, laser_pose, laser);
    const std::vector<double> ranges = measureScan(hits, laser, laser_rng);

    RecordedScan scan;
    scan.stamp = stamp;
    scan.ranges.assign(ranges.begin(), ranges.end());
    scan.odom = odom[k];
    rec.scans.push_back(std::move(scan));
    rec.keyframes.push_back({k, registered[k]});
    gt.scans.push_back({stamp, laser_pose, visibleFaces(hits, laser_pose, w, gt)});
    if (options.on_scan) options.on_scan(k + 1, count);
  }
  return res;
}

}  // namespace line_map_eval
