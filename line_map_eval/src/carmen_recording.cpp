#include "line_map_eval/carmen_recording.hpp"

#include <algorithm>
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
}  // namespace

Recording fromCarmen(const CarmenLog& raw, const CarmenLog* corrected, const CarmenRecordingOptions& options,
                     CarmenRecordingReport* report)
{
  if (raw.scans.empty()) throw std::runtime_error(raw.path + ": no FLASER or ROBOTLASER1 scans");
  if (!(options.min_stamp_step > 0.0)) throw std::invalid_argument("fromCarmen: min_stamp_step must be > 0");
  CarmenRecordingReport info;
  const CarmenScan& first = raw.scans.front();
  const std::size_t beams = first.ranges.size();
  for (const CarmenScan& s : raw.scans)
  {
    if (s.ranges.size() != beams)
      throw std::runtime_error(raw.path + ":" + std::to_string(s.line) + ": scan has " +
                               std::to_string(s.ranges.size()) + " readings, the log's first scan " +
                               std::to_string(beams));
  }

  Recording rec;
  rec.source = raw.path;
  info.no_return_range = options.no_return_range > 0.0 ? options.no_return_range : carmenNoReturnFloor(raw);
  if (first.type == CarmenScanType::RobotLaser1)
  {
    if (options.no_return_range <= 0.0 && first.max_range > 0.0) info.no_return_range = first.max_range;
    rec.geometry.beam_count = beams;
    rec.geometry.angle_min = first.start_angle;
    rec.geometry.angle_increment = first.angular_resolution > 0.0 || beams < 2
                                       ? first.angular_resolution
                                       : first.field_of_view / static_cast<double>(beams - 1);
    rec.geometry.range_min = options.range_min;
    rec.geometry.range_max = info.no_return_range - 0.005;
  }
  else
  {
    rec.geometry = carmenBeamGeometry(beams, info.no_return_range, options.range_min);
  }
  if (options.max_usable_range > 0.0)
    rec.geometry.range_max = std::min(rec.geometry.range_max, options.max_usable_range);

  // Laser mounting on base_link.
  if (parseOffset(raw, rec.base_to_laser))
    info.mounting_source = "PARAM robot_frontlaser_offset of " + raw.path;
  else if (corrected && parseOffset(*corrected, rec.base_to_laser))
    info.mounting_source = "PARAM robot_frontlaser_offset of " + corrected->path;
  else
  {
    rec.base_to_laser = first.robot_pose.inverse() * first.laser_pose;
    info.mounting_source = "laser pose relative to robot pose of the first scan";
  }
  const Pose2 laser_to_base = rec.base_to_laser.inverse();

  const std::size_t n =
      options.max_scans > 0 ? std::min(options.max_scans, raw.scans.size()) : raw.scans.size();
  const auto moves = [&](auto pose_of)
  {
    for (std::size_t i = 1; i < n; ++i)
      if (!samePose(pose_of(raw.scans[i]), pose_of(raw.scans[0]))) return true;
    return false;
  };
  bool odom_lines_move = false;
  for (const CarmenOdom& o : raw.odometry)
    if (!samePose(o.pose, raw.odometry.front().pose)) odom_lines_move = true;
  std::vector<const CarmenOdom*> odom_sorted;
  enum class Source
  {
    Scan,
    OdomLines,
    Laser
  } source = Source::Scan;
  if (!moves([](const CarmenScan& s) { return s.robot_pose; }))
  {
    if (odom_lines_move)
      source = Source::OdomLines;
    else if (moves([](const CarmenScan& s) { return s.laser_pose; }))
      source = Source::Laser;
  }
  if (source == Source::OdomLines)
  {
    for (const CarmenOdom& o : raw.odometry) odom_sorted.push_back(&o);
    std::stable_sort(odom_sorted.begin(), odom_sorted.end(),
                     [](const CarmenOdom* a, const CarmenOdom* b) { return a->timestamp < b->timestamp; });
  }
  info.odometry_source = source == Source::Scan        ? "scan odometry fields"
                         : source == Source::OdomLines ? "ODOM lines"
                                                       : "scan laser poses";

  rec.scans.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const CarmenScan& s = raw.scans[i];
    RecordedScan& out = rec.scans[i];
    out.ranges = s.ranges;
    double t = s.timestamp;
    if (i > 0 && t < rec.scans[i - 1].stamp + options.min_stamp_step)
    {
      t = rec.scans[i - 1].stamp + options.min_stamp_step;
      ++info.stamps_adjusted;
      info.max_stamp_shift = std::max(info.max_stamp_shift, t - s.timestamp);
    }
    out.stamp = t;
    switch (source)
    {
      case Source::Scan:
        out.odom = s.robot_pose;
        break;
      case Source::OdomLines:
        out.odom = interpolateOdom(odom_sorted, s.timestamp);
        break;
      case Source::Laser:
        out.odom = s.laser_pose * laser_to_base;
        break;
    }
  }

  if (corrected)
  {
    if (!corrected->scans.empty() && corrected->scans.front().ranges.size() != beams)
      throw std::runtime_error(corrected->path + ": keyframes have " +
                               std::to_string(corrected->scans.front().ranges.size()) + " readings, " +
                               raw.path + " has " + std::to_string(beams));
    const std::vector<std::size_t> pairs = pairKeyframes(raw, *corrected);
    for (std::size_t k = 0; k < pairs.size(); ++k)
    {
      if (pairs[k] >= n) break;
      rec.keyframes.push_back({pairs[k], corrected->scans[k].laser_pose * laser_to_base});
    }
  }
  if (report) *report = info;
  return rec;
}

}  // namespace line_map_eval
