#include "line_map_eval/datasets/slam_sessions.hpp"

#include <algorithm>

#include "line_map_eval/datasets/localization_recording.hpp"

namespace line_map_eval
{
Recording recordingPart(const Recording& recording, std::size_t first, std::size_t last, bool rezero)
{
  Recording part = recording;
  part.keyframes.clear();
  last = std::min(last, recording.scans.size());
  first = std::min(first, last);
  part.scans.assign(recording.scans.begin() + static_cast<std::ptrdiff_t>(first),
                    recording.scans.begin() + static_cast<std::ptrdiff_t>(last));
  if (rezero && !part.scans.empty())
  {
    const Pose2 zero = part.scans.front().odom.inverse();
    for (auto& s : part.scans) s.odom = zero * s.odom;
  }
  return part;
}

std::vector<linemap::Segment2> sessionSurfaces(const line_map_merging::SlamSession& session)
{
  std::vector<linemap::Segment2> out;
  for (std::size_t k = 0; k < session.keyframes.size() && k < session.nodes.size(); ++k)
    for (const auto& s : session.keyframes[k].joins)
      out.emplace_back(session.nodes[k].apply(s.start), session.nodes[k].apply(s.end));
  return out;
}

TwoSessionRun runTwoSessions(const Recording& recording, std::size_t cut,
                             const line_map_merging::LaserSlamParams& slam_params,
                             const line_map_merging::LocalizerParams& localizer_params, bool use_odometry,
                             const std::optional<Pose2>& start, std::size_t localize_scans)
{
  TwoSessionRun out;
  out.cut = std::min(cut, recording.scans.size());
  out.scan_poses.assign(recording.scans.size(), std::nullopt);
  const Recording first = recordingPart(recording, 0, out.cut, false);
  const Recording second = recordingPart(recording, out.cut, recording.scans.size(), true);
  const SlamRecordingResult a = runSlam(first, slam_params, use_odometry);
  out.first_counters = a.counters;
  out.cpu_seconds = a.cpu_seconds;
  for (std::size_t i = 0; i < out.cut; ++i) out.scan_poses[i] = a.scan_poses[i];
  SlamContinuation continuation{a.session, start.value_or(Pose2()), 0.1, 0.05};
  if (start)
    out.localized_at = 0;
  else
  {
    // Where the second part starts, with no start pose given: global localization on the saved surfaces;
    // the localizer carries the accepted pose back to the part's first scan by the odometry.
    const LocalizationRunResult found =
        runLocalization(second, sessionSurfaces(a.session), localizer_params, std::nullopt, 0,
                        std::min(localize_scans, second.scans.size()));
    out.cpu_seconds += found.cpu_seconds;
    if (!found.recovered_at || found.scan_poses.empty()) return out;
    out.localized_at = found.recovered_at;
    continuation.start = found.scan_poses.front();
  }
  const SlamRecordingResult b = runSlam(second, slam_params, use_odometry, std::nullopt, &continuation);
  out.second_counters = b.counters;
  out.cpu_seconds += b.cpu_seconds;
  // The first part's scans as the joined graph left them: the session's scans are the accepted ones, in
  // order, stamped as the recording's.
  std::size_t k = 0;
  for (std::size_t i = 0; i < out.cut && k < b.continued_scan_poses.size(); ++i)
    if (a.session.scans[k].stamp == first.scans[i].stamp) out.scan_poses[i] = b.continued_scan_poses[k++];
  for (std::size_t i = 0; i < second.scans.size(); ++i) out.scan_poses[out.cut + i] = b.scan_poses[i];
  const std::size_t saved = a.session.keyframes.size();
  for (const auto& e : b.session.edges)
    out.closures_between += e.loop && std::min(e.from, e.to) < saved && std::max(e.from, e.to) >= saved;
  return out;
}

}  // namespace line_map_eval
