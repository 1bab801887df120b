#include "line_map_eval/online/online_drive.hpp"

#include <algorithm>
#include <memory>

namespace line_map_eval
{
BackEndSchedule loopClosureSchedule(const Recording& rec, std::size_t every)
{
  BackEndSchedule out;
  TrajectoryEmission path;
  Pose2 map_to_odom;  // identity until the first emission
  std::size_t next = 0;
  for (const RecordedScan& scan : rec.scans)
  {
    const std::size_t index = static_cast<std::size_t>(&scan - rec.scans.data());
    bool emit = false;
    if (next < rec.keyframes.size() && rec.keyframes[next].scan_index == index)
    {
      const CorrectedKeyframe& kf = rec.keyframes[next];
      path.poses.emplace_back(scan.stamp, kf.pose);
      ++next;
      emit = (every > 0 && next % every == 0) || next == rec.keyframes.size();
      if (emit) map_to_odom = kf.pose * scan.odom.inverse();
    }
    out.map_to_odom.emplace_back(scan.stamp, map_to_odom);
    if (emit)
    {
      path.stamp = scan.stamp;
      out.trajectories.push_back(path);
    }
  }
  return out;
}

BackEndSchedule fixedPoseSchedule(const Recording& rec)
{
  BackEndSchedule out;
  for (const CorrectedKeyframe& kf : rec.keyframes)
  {
    const RecordedScan& scan = rec.scans.at(kf.scan_index);
    out.map_to_odom.emplace_back(scan.stamp, kf.pose * scan.odom.inverse());
  }
  return out;
}

Pose2 sampleAt(const std::vector<std::pair<double, Pose2>>& samples, double t)
{
  const auto after = std::lower_bound(samples.begin(), samples.end(), t,
                                      [](const auto& s, double v) { return s.first < v; });
  if (after == samples.end()) return samples.back().second;
  if (after == samples.begin() || after->first == t) return after->second;
  const auto& before = *(after - 1);
  return linemap::interpolate(before.second, after->second,
                              (t - before.first) / (after->first - before.first));
}

std::shared_ptr<const line_map_merging::KeyframeScan> keyframeScan(const Recording& rec, std::size_t index)
{
  const RecordedScan& scan = rec.scans.at(index);
  return line_map_merging::makeKeyframeScan(rec.geometryOf(scan), scan.ranges);
}

line_map_merging::StampedScan stampedScan(const Recording& rec, const BackEndSchedule& schedule,
                                          const SegmentSource& segments, std::size_t index)
{
  const Pose2& mount = rec.base_to_laser;
  const RecordedScan& scan = rec.scans.at(index);
  line_map_merging::StampedScan s;
  s.stamp = scan.stamp;
  s.odom = scan.odom * mount;
  s.laser = schedule.map_to_odom.empty() ? *s.odom : sampleAt(schedule.map_to_odom, scan.stamp) * *s.odom;
  s.mount = mount;
  s.segments = segments(index, *s.odom);
  s.beams = keyframeScan(rec, index);
  return s;
}

std::size_t driveOnline(line_map_merging::OnlineMapper& mapper, const Recording& rec,
                        const BackEndSchedule& schedule, const SegmentSource& segments,
                        const OnlineDriveHooks& hooks)
{
  std::size_t next = 0;
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
  {
    const line_map_merging::StampedScan s = stampedScan(rec, schedule, segments, i);
    mapper.addScan(s);
    if (hooks.scan) hooks.scan(i, s);
    for (; next < schedule.trajectories.size() && schedule.trajectories[next].stamp <= s.stamp; ++next)
    {
      if (hooks.before_trajectory) hooks.before_trajectory(next);
      mapper.addTrajectory(schedule.trajectories[next].poses);
      if (hooks.trajectory) hooks.trajectory(next, schedule.trajectories[next]);
    }
  }
  return next;
}

}  // namespace line_map_eval
