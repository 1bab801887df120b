#include "line_map_eval/datasets/localization_recording.hpp"

#include <time.h>

#include <cmath>

namespace line_map_eval
{
namespace
{
double threadCpuSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

LocalizationRunResult runOnce(const Recording& recording, line_map_merging::LineMapLocalizer& localizer,
                              std::size_t first, std::size_t last, bool stop_when_recovered)
{
  LocalizationRunResult r;
  const double cpu = threadCpuSeconds();
  for (std::size_t i = first; i < last; ++i)
  {
    const auto result = localizer.addScan(localizerScan(recording, i));
    r.scan_poses.push_back(result.pose);
    r.scan_ms.push_back(localizer.counters().last_ms);
    r.localized.push_back(result.localized);
    if (result.outcome == line_map_merging::LocalizerOutcome::kRecovered && !r.recovered_at)
    {
      r.recovered_at = i;
      if (stop_when_recovered) break;
    }
  }
  r.cpu_seconds = threadCpuSeconds() - cpu;
  r.counters = localizer.counters();
  return r;
}
}  // namespace

line_map_merging::LocalizerScan localizerScan(const Recording& recording, std::size_t index)
{
  const RecordedScan& s = recording.scans[index];
  const ScanGeometry& g = recording.geometryOf(s);
  line_map_merging::LocalizerScan scan;
  scan.stamp = s.stamp;
  scan.odom = s.odom;
  scan.sensor = recording.base_to_laser.translation();
  scan.points.reserve(s.ranges.size());
  for (std::size_t b = 0; b < s.ranges.size(); ++b)
  {
    const double range = s.ranges[b];
    if (!(range >= g.range_min && range < g.range_max) || range <= 0.0) continue;
    const double a = g.angle_min + static_cast<double>(b) * g.angle_increment;
    scan.points.push_back(recording.base_to_laser.apply({range * std::cos(a), range * std::sin(a)}));
  }
  return scan;
}

LocalizationRunResult runLocalization(const Recording& recording,
                                      const std::vector<linemap::Segment2>& map_segments,
                                      const line_map_merging::LocalizerParams& params,
                                      const std::optional<Pose2>& initial, std::size_t first,
                                      std::size_t last)
{
  if (last == 0 || last > recording.scans.size()) last = recording.scans.size();
  if (first >= last) return {};
  line_map_merging::LineMapLocalizer localizer(map_segments, params);
  if (initial) localizer.setPose(*initial);
  LocalizationRunResult r = runOnce(recording, localizer, first, last, !initial);
  if (initial || !r.recovered_at) return r;
  // Global localization found the pose at scan k: scan `first` was there, by the odometry between.
  const std::size_t k = *r.recovered_at;
  const Pose2 start = r.scan_poses.back() * (recording.scans[k].odom.inverse() * recording.scans[first].odom);
  line_map_merging::LineMapLocalizer again(map_segments, params);
  again.setPose(start);
  LocalizationRunResult full = runOnce(recording, again, first, last, false);
  full.recovered_at = k;
  full.cpu_seconds += r.cpu_seconds;
  return full;
}

}  // namespace line_map_eval
