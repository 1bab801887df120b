#include "line_map_eval/datasets/carmen_recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace line_map_eval
{
namespace
{
bool samePose(const Pose2& a, const Pose2& b)
{
  return a.x == b.x && a.y == b.y && a.theta == b.theta;
}

bool parseOffset(const CarmenLog& log, Pose2& mount)
{
  const auto it = log.params.find("robot_frontlaser_offset");
  if (it == log.params.end()) return false;
  char* end = nullptr;
  const double offset = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0')
    throw std::runtime_error(log.path + ": PARAM robot_frontlaser_offset is not a number: '" + it->second +
                             "'");
  mount = Pose2(offset, 0.0, 0.0);
  return true;
}

/// Odometry at time t from ODOM lines sorted by timestamp (clamped at both ends).
Pose2 interpolateOdom(const std::vector<const CarmenOdom*>& odom, double t)
{
  const auto it = std::lower_bound(odom.begin(), odom.end(), t,
                                   [](const CarmenOdom* o, double time) { return o->timestamp < time; });
  if (it == odom.begin()) return odom.front()->pose;
  if (it == odom.end()) return odom.back()->pose;
  const CarmenOdom& b = **it;
  const CarmenOdom& a = **(it - 1);
  const double dt = b.timestamp - a.timestamp;
  return dt > 0.0 ? linemap::interpolate(a.pose, b.pose, (t - a.timestamp) / dt) : b.pose;
}

/// The log's ODOM lines in time order.
std::vector<const CarmenOdom*> sortedOdometry(const CarmenLog& log)
{
  std::vector<const CarmenOdom*> odom;
  for (const CarmenOdom& o : log.odometry) odom.push_back(&o);
  std::stable_sort(odom.begin(), odom.end(),
                   [](const CarmenOdom* a, const CarmenOdom* b) { return a->timestamp < b->timestamp; });
  return odom;
}

bool sameGeometry(const ScanGeometry& a, const ScanGeometry& b)
{
  return a.angle_min == b.angle_min && a.angle_increment == b.angle_increment &&
         a.beam_count == b.beam_count && a.range_min == b.range_min && a.range_max == b.range_max;
}

bool hasPose(const CarmenScan& s)
{
  return s.type != CarmenScanType::RawLaser;
}
/// The one RAWLASER sensor among the first n scans (0: none); two of them are refused.
int singleRawLaser(const CarmenLog& raw, std::size_t n)
{
  // RAWLASER1..4 are four different sensors.
  int raw_laser = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const CarmenScan& s = raw.scans[i];
    if (s.type != CarmenScanType::RawLaser) continue;
    if (raw_laser != 0 && s.raw_laser != raw_laser)
      throw std::runtime_error(raw.path + ":" + std::to_string(s.line) + ": RAWLASER" +
                               std::to_string(s.raw_laser) + " after RAWLASER" + std::to_string(raw_laser) +
                               ": a recording holds the scans of one laser");
    raw_laser = s.raw_laser;
  }
  return raw_laser;
}

/// The laser's mounting on base_link (fromCarmen's rule), where it came from in `info`.
Pose2 laserMounting(const CarmenLog& raw, const CarmenLog* corrected, std::size_t n, bool front_laser,
                    const CarmenScan* posed, CarmenRecordingReport& info)
{
  Pose2 mount;
  if (front_laser && parseOffset(raw, mount))
    info.mounting_source = "PARAM robot_frontlaser_offset of " + raw.path;
  else if (front_laser && corrected && parseOffset(*corrected, mount))
    info.mounting_source = "PARAM robot_frontlaser_offset of " + corrected->path;
  else if (posed)
  {
    mount = posed->robot_pose.inverse() * posed->laser_pose;
    info.mounting_source = "laser pose relative to robot pose of the first scan";
    for (std::size_t i = 0; i < n; ++i)
    {
      const CarmenScan& s = raw.scans[i];
      if (!hasPose(s)) continue;
      const Pose2 d = mount.inverse() * (s.robot_pose.inverse() * s.laser_pose);
      info.max_mounting_shift = std::max(info.max_mounting_shift, std::hypot(d.x, d.y));
      info.max_mounting_turn = std::max(info.max_mounting_turn, std::abs(linemap::normalizeAngle(d.theta)));
    }
  }
  else
    info.mounting_source = "none (identity): RAWLASER lines carry no pose";
  return mount;
}

enum class Source
{
  Scan,
  OdomLines,
  Laser
};

/// Odometry of the scans with poses: their robot pose unless it never changes (or `prefer_odom_lines`).
Source odometrySource(const CarmenLog& raw, std::size_t n, const CarmenScan* posed, bool prefer_odom_lines)
{
  const auto moves = [&](auto pose_of)
  {
    for (std::size_t i = 0; i < n; ++i)
      if (hasPose(raw.scans[i]) && !samePose(pose_of(raw.scans[i]), pose_of(*posed))) return true;
    return false;
  };
  bool odom_lines_move = false;
  for (const CarmenOdom& o : raw.odometry)
    if (!samePose(o.pose, raw.odometry.front().pose)) odom_lines_move = true;
  if (prefer_odom_lines && odom_lines_move) return Source::OdomLines;
  if (posed && !moves([](const CarmenScan& s) { return s.robot_pose; }))
  {
    if (odom_lines_move) return Source::OdomLines;
    if (moves([](const CarmenScan& s) { return s.laser_pose; })) return Source::Laser;
  }
  return Source::Scan;
}

/// The corrected log's keyframes paired to the first n raw scans, as base_link poses.
std::vector<CorrectedKeyframe> correctedKeyframes(const CarmenLog& raw, const CarmenLog& corrected,
                                                  std::size_t n, const Pose2& laser_to_base)
{
  if (!corrected.scans.empty())
  {
    const std::size_t beams = corrected.scans.front().ranges.size();
    if (std::none_of(raw.scans.begin(), raw.scans.end(),
                     [&](const CarmenScan& s) { return s.ranges.size() == beams; }))
      throw std::runtime_error(corrected.path + ": keyframes have " + std::to_string(beams) +
                               " readings, no scan of " + raw.path + " has as many");
  }
  std::vector<CorrectedKeyframe> keyframes;
  const std::vector<std::size_t> pairs = pairKeyframes(raw, corrected);
  for (std::size_t k = 0; k < pairs.size(); ++k)
  {
    if (pairs[k] >= n) break;
    keyframes.push_back({pairs[k], corrected.scans[k].laser_pose * laser_to_base});
  }
  return keyframes;
}
}  // namespace

Recording fromCarmen(const CarmenLog& raw, const CarmenLog* corrected, const CarmenRecordingOptions& options,
                     CarmenRecordingReport* report)
{
  if (raw.scans.empty()) throw std::runtime_error(raw.path + ": no FLASER, ROBOTLASER1 or RAWLASER scans");
  if (!(options.min_stamp_step > 0.0)) throw std::invalid_argument("fromCarmen: min_stamp_step must be > 0");
  CarmenRecordingReport info;
  const std::size_t n =
      options.max_scans > 0 ? std::min(options.max_scans, raw.scans.size()) : raw.scans.size();

  const int raw_laser = singleRawLaser(raw, n);

  // Beam geometry, scan by scan: ROBOTLASER1/RAWLASER lines state theirs (and their maximum range,
  // the no-return value), FLASER's follows from its beam count.
  bool need_floor = options.no_return_range <= 0.0;
  if (need_floor)
  {
    need_floor = false;
    for (std::size_t i = 0; i < n && !need_floor; ++i)
      need_floor = raw.scans[i].type == CarmenScanType::FLaser || !(raw.scans[i].max_range > 0.0);
  }
  const double floor = need_floor ? carmenNoReturnFloor(raw) : 0.0;
  const auto geometryOf = [&](const CarmenScan& s)
  {
    double no_return = options.no_return_range;
    if (!(no_return > 0.0))
      no_return = s.type != CarmenScanType::FLaser && s.max_range > 0.0 ? s.max_range : floor;
    if (!(no_return > 0.0))
      throw std::runtime_error(raw.path + ":" + std::to_string(s.line) +
                               ": no no-return value (no positive reading in the log)");
    ScanGeometry g;
    try
    {
      g = carmenScanGeometry(s, no_return, options.range_min);
    }
    catch (const std::invalid_argument& e)
    {
      throw std::runtime_error(raw.path + ":" + std::to_string(s.line) + ": " + e.what());
    }
    if (options.max_usable_range > 0.0) g.range_max = std::min(g.range_max, options.max_usable_range);
    info.no_return_range = info.no_return_range > 0.0 ? std::min(info.no_return_range, no_return) : no_return;
    return g;
  };

  Recording rec;
  rec.source = raw.path;
  rec.geometry = geometryOf(raw.scans.front());
  std::vector<ScanGeometry> distinct{rec.geometry};

  const CarmenScan* posed = nullptr;  // the first scan with a laser and a robot pose
  for (std::size_t i = 0; i < n && !posed; ++i)
    if (hasPose(raw.scans[i])) posed = &raw.scans[i];
  rec.base_to_laser = laserMounting(raw, corrected, n, raw_laser <= 1, posed, info);
  const Pose2 laser_to_base = rec.base_to_laser.inverse();
  const Source source = odometrySource(raw, n, posed, options.odometry_from_odom_lines);
  // RAWLASER scans: ODOM lines interpolated at the scan stamp, like FLASER's odometry.
  const bool raw_scans = raw_laser > 0;
  std::vector<const CarmenOdom*> odom_sorted;
  if (source == Source::OdomLines || raw_scans) odom_sorted = sortedOdometry(raw);
  const std::string raw_source = odom_sorted.empty() ? "none (no ODOM lines)" : "ODOM lines";
  if (posed)
    info.odometry_source = source == Source::Scan        ? "scan odometry fields"
                           : source == Source::OdomLines ? "ODOM lines"
                                                         : "scan laser poses";
  if (raw_scans) info.odometry_source += (posed ? "; RAWLASER scans: " : "") + raw_source;

  rec.scans.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const CarmenScan& s = raw.scans[i];
    RecordedScan& out = rec.scans[i];
    out.ranges = s.ranges;
    if (i > 0)
    {
      const ScanGeometry g = geometryOf(s);
      if (!sameGeometry(g, rec.geometry)) out.geometry = g;
      if (std::none_of(distinct.begin(), distinct.end(),
                       [&](const ScanGeometry& d) { return sameGeometry(d, g); }))
        distinct.push_back(g);
    }
    double t = s.timestamp;
    if (i > 0 && t < rec.scans[i - 1].stamp + options.min_stamp_step)
    {
      t = rec.scans[i - 1].stamp + options.min_stamp_step;
      ++info.stamps_adjusted;
      info.max_stamp_shift = std::max(info.max_stamp_shift, t - s.timestamp);
    }
    out.stamp = t;
    if (!hasPose(s))
      out.odom = odom_sorted.empty() ? Pose2() : interpolateOdom(odom_sorted, s.timestamp);
    else if (source == Source::Scan)
      out.odom = s.robot_pose;
    else if (source == Source::OdomLines)
      out.odom = interpolateOdom(odom_sorted, s.timestamp + options.odometry_delay);
    else
      out.odom = s.laser_pose * laser_to_base;
  }
  info.geometries = distinct.size();

  if (corrected) rec.keyframes = correctedKeyframes(raw, *corrected, n, laser_to_base);
  if (report) *report = info;
  return rec;
}

double fitOdometryDelay(const CarmenLog& log, double max_delay, double step)
{
  const std::vector<const CarmenOdom*> odom = sortedOdometry(log);
  if (odom.empty() || log.scans.size() < 2 || !(step > 0.0)) return 0.0;
  const auto disagreement = [&](double delay)
  {
    double sum = 0.0;
    for (std::size_t i = 1; i < log.scans.size(); ++i)
    {
      const CarmenScan &a = log.scans[i - 1], &b = log.scans[i];
      const Pose2 posed = a.robot_pose.inverse() * b.robot_pose;
      const Pose2 odometry =
          interpolateOdom(odom, a.timestamp + delay).inverse() * interpolateOdom(odom, b.timestamp + delay);
      sum += std::hypot(posed.x - odometry.x, posed.y - odometry.y);
    }
    return sum;
  };
  const int steps = static_cast<int>(std::floor(max_delay / step + 1e-9));
  double best_delay = 0.0, best = disagreement(0.0);
  for (int k = -steps; k <= steps; ++k)
    if (const double d = disagreement(k * step); d < best)
    {
      best = d;
      best_delay = k * step;
    }
  return best_delay;
}

}  // namespace line_map_eval
