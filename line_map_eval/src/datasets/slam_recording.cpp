#include "line_map_eval/datasets/slam_recording.hpp"

#include <time.h>

#include <chrono>
#include <cmath>

#include "line_map_merging/localization/session_continuation.hpp"

namespace line_map_eval
{
line_map_merging::SlamScan slamScan(const Recording& recording, std::size_t index, bool use_odometry)
{
  const RecordedScan& s = recording.scans[index];
  const ScanGeometry& g = recording.geometryOf(s);  // a scan's own where the sensor changes it
  line_map_merging::SlamScan scan;
  scan.stamp = s.stamp;
  if (use_odometry) scan.odom = s.odom;
  scan.points.reserve(s.ranges.size());
  for (std::size_t b = 0; b < s.ranges.size(); ++b)
  {
    const double r = s.ranges[b];
    if (!(r >= g.range_min && r <= g.range_max) || r <= 0.0) continue;
    const double a = g.angle_min + static_cast<double>(b) * g.angle_increment;
    scan.points.push_back(recording.base_to_laser.apply({r * std::cos(a), r * std::sin(a)}));
  }
  return scan;
}

namespace
{
/// What the SLAM made of the run: the poses of the scans it accepted (`accepted`: their recording indices,
/// in order) and of a continued session's saved scans, its new keyframes, closures, counters and session.
void collectRun(const line_map_merging::LaserSlam& slam, std::size_t scans,
                const SlamContinuation* continuation, const std::vector<std::size_t>& accepted,
                SlamRecordingResult& result)
{
  // A run mapped apart and never joined holds no saved scans or keyframes.
  const bool holds_saved = continuation && (result.placed_at || result.joined_at);
  const std::size_t saved_scans = holds_saved ? continuation->session.scans.size() : 0;
  const auto poses = slam.scanPoses();
  result.scan_poses.assign(scans, Pose2());
  for (std::size_t k = 0; k < saved_scans && k < poses.size(); ++k)
    result.continued_scan_poses.push_back(poses[k].second);
  for (std::size_t k = saved_scans; k < poses.size() && k - saved_scans < accepted.size(); ++k)
    result.scan_poses[accepted[k - saved_scans]] = poses[k].second;
  const std::size_t saved_keyframes = holds_saved ? continuation->session.keyframes.size() : 0;
  for (std::size_t k = saved_keyframes; k < slam.keyframes().size(); ++k)
    result.keyframes.push_back({accepted[slam.keyframes()[k].scan - saved_scans], slam.graph().node(k)});
  result.closures = slam.closureAttempts();
  for (const auto& e : slam.graph().edges())
    if (e.loop) result.loop_edges.push_back(e);
  result.counters = slam.counters();
  result.session = slam.session();
}
}  // namespace

SlamRecordingResult runSlam(const Recording& recording, const line_map_merging::LaserSlamParams& params,
                            bool use_odometry, const std::optional<FrontEndSlip>& slip,
                            const SlamContinuation* continuation)
{
  SlamRecordingResult result;
  const auto start = std::chrono::steady_clock::now();
  auto cpu = []
  {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  };
  const double cpu_start = cpu();
  line_map_merging::LaserSlam slam(params);
  std::optional<line_map_merging::SessionContinuation> search;
  if (continuation)
    search.emplace(continuation->session, continuation->localizer, continuation->search_scans,
                   continuation->start, continuation->sigma_xy, continuation->sigma_theta);
  std::vector<std::size_t> accepted;  // recording index of each scan the SLAM accepted
  std::vector<std::size_t> held;      // recording index of each scan held by the search
  const auto add = [&](const line_map_merging::SlamScan& scan, std::size_t i)
  {
    if (slam.addScan(scan) != line_map_merging::SlamOutcome::kRejected) accepted.push_back(i);
    if (search && !result.joined_at &&
        search->afterScan(scan, recording.base_to_laser.translation(), slam) ==
            line_map_merging::SessionContinuation::State::kJoined)
      result.joined_at = i;
  };
  for (std::size_t i = 0; i < recording.scans.size(); ++i)
  {
    if (slip && slip->scan == i) slam.injectFrontEndSlip(slip->slip);
    const line_map_merging::SlamScan scan = slamScan(recording, i, use_odometry);
    if (search && search->state() == line_map_merging::SessionContinuation::State::kSearching)
    {
      const double search_start = cpu();
      const auto state = search->addScan(scan, recording.base_to_laser.translation(), slam);
      result.search_cpu_seconds += cpu() - search_start;
      if (state == line_map_merging::SessionContinuation::State::kSearching)
      {
        held.push_back(i);
        continue;
      }
      // Given up, the run is mapped apart from its first scan searched, and joined when found later.
      if (state == line_map_merging::SessionContinuation::State::kGaveUp)
        result.placed_at = std::nullopt;
      else
        result.placed_at = i;
      const auto replay = search->takeHeld();  // all the held scans, or none
      for (std::size_t k = 0; k < replay.size(); ++k) add(replay[k], held[held.size() - replay.size() + k]);
    }
    add(scan, i);
  }
  if (search) result.refused_as_ambiguous = search->refusedAsAmbiguous();
  result.cpu_seconds = cpu() - cpu_start;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  collectRun(slam, recording.scans.size(), continuation, accepted, result);
  return result;
}

Recording withSlamKeyframes(Recording recording, const SlamRecordingResult& slam)
{
  recording.keyframes = slam.keyframes;
  recording.source += " + laser SLAM";
  return recording;
}

}  // namespace line_map_eval
