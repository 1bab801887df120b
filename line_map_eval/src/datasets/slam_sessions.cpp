#include "line_map_eval/datasets/slam_sessions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "line_map_merging/mergers/cae_rlsm.hpp"

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

namespace
{
bool sameGeometry(const ScanGeometry& a, const ScanGeometry& b)
{
  return a.angle_min == b.angle_min && a.angle_increment == b.angle_increment &&
         a.beam_count == b.beam_count && a.range_min == b.range_min && a.range_max == b.range_max;
}

/// Which run (npos: the saved session) and which of its scans each of a session's scans is.
struct ScanOwner
{
  std::size_t run = static_cast<std::size_t>(-1);
  std::size_t scan = 0;
};

/// Every run's scans and keyframes at their poses in the joined graph `out.session`, by `owners` (one per
/// session scan); the scans of `fresh_run` before its first keyframe are posed in the map frame already.
void poseRunScans(const std::vector<ScanOwner>& owners, std::size_t fresh_run, SessionsRun& out)
{
  const auto& session = out.session;
  const std::size_t n = out.scan_poses.size();
  for (std::size_t k = 0; k < session.scans.size() && k < owners.size(); ++k)
  {
    const auto& scan = session.scans[k];
    const ScanOwner& owner = owners[k];
    std::optional<Pose2> pose;
    if (scan.keyframe < session.nodes.size())
      pose = session.nodes[scan.keyframe] * scan.relative;
    else if (owner.run == fresh_run)
      pose = scan.relative;
    if (owner.run >= n)
      out.saved_scan_poses.push_back(pose.value_or(scan.relative));  // as the SLAM itself reports it
    else if (owner.scan < out.scan_poses[owner.run].size())
      out.scan_poses[owner.run][owner.scan] = pose;
  }
  for (std::size_t k = 0; k < session.keyframes.size(); ++k)
  {
    const std::size_t scan = session.keyframes[k].scan;
    if (scan < owners.size() && owners[scan].run < n)
      out.keyframes[owners[scan].run].push_back({owners[scan].scan, session.nodes[k]});
  }
}
}  // namespace

SessionsRun runSessions(const std::vector<Recording>& runs,
                        const std::optional<line_map_merging::SlamSession>& saved,
                        const line_map_merging::LaserSlamParams& slam_params,
                        const line_map_merging::LocalizerParams& localizer_params, bool use_odometry,
                        const std::vector<std::optional<Pose2>>& starts, std::size_t localize_scans)
{
  SessionsRun out;
  const std::size_t n = runs.size();
  out.scan_poses.resize(n);
  out.keyframes.resize(n);
  out.localized_at.assign(n, std::nullopt);
  out.joined_at.assign(n, std::nullopt);
  out.refused_as_ambiguous.assign(n, 0);
  out.closures_to_earlier.assign(n, 0);
  out.counters.assign(n, {});
  out.slam_cpu_seconds.assign(n, 0.0);
  std::optional<line_map_merging::SlamSession> current = saved;
  std::vector<ScanOwner> owners(saved ? saved->scans.size() : 0);
  std::vector<std::size_t> keyframe_run(saved ? saved->keyframes.size() : 0, static_cast<std::size_t>(-1));
  // The run that started the map: its scans before its first keyframe are posed in the map frame already.
  std::size_t fresh_run = static_cast<std::size_t>(-1);
  for (std::size_t r = 0; r < n; ++r)
  {
    const Recording& run = runs[r];
    out.scan_poses[r].assign(run.scans.size(), std::nullopt);
    std::optional<SlamContinuation> continuation;
    if (current)
      continuation = SlamContinuation{
          *current,      r < starts.size() ? starts[r] : std::nullopt, 0.1, 0.05, localizer_params,
          localize_scans};
    else
      fresh_run = r;
    const SlamRecordingResult result =
        runSlam(run, slam_params, use_odometry, std::nullopt, continuation ? &*continuation : nullptr);
    out.cpu_seconds += result.cpu_seconds;
    out.localized_at[r] = result.placed_at;
    out.joined_at[r] = result.joined_at;
    out.refused_as_ambiguous[r] = result.refused_as_ambiguous;
    if (!result.placed_at && !result.joined_at) continue;  // never found: left out
    out.counters[r] = result.counters;
    out.slam_cpu_seconds[r] = result.cpu_seconds - result.search_cpu_seconds;
    // The run's accepted scans follow the saved ones in the session, in order and with their stamps.
    std::size_t i = 0;
    for (std::size_t k = owners.size(); k < result.session.scans.size(); ++k)
    {
      while (i < run.scans.size() && run.scans[i].stamp != result.session.scans[k].stamp) ++i;
      owners.push_back({r, i < run.scans.size() ? i++ : run.scans.size()});
    }
    keyframe_run.resize(result.session.keyframes.size(), r);
    for (const auto& e : result.session.edges)
      if (e.loop && keyframe_run[e.from] != keyframe_run[e.to] &&
          (keyframe_run[e.from] == r || keyframe_run[e.to] == r))
        ++out.closures_to_earlier[r];
    current = result.session;
  }
  if (!current) return out;
  out.session = std::move(*current);
  poseRunScans(owners, fresh_run, out);
  return out;
}

std::vector<double> followInTime(std::vector<Recording>& runs, double not_before)
{
  std::vector<double> shifts(runs.size(), 0.0);
  double last = not_before;
  for (std::size_t r = 0; r < runs.size(); ++r)
  {
    if (runs[r].scans.empty()) continue;
    const double first = runs[r].scans.front().stamp;
    if (first <= last) shifts[r] = last + 1.0 - first;
    for (auto& scan : runs[r].scans) scan.stamp += shifts[r];
    last = runs[r].scans.back().stamp;
  }
  return shifts;
}

Recording joinedRecording(const std::vector<Recording>& runs, const SessionsRun& run, bool odometry)
{
  Recording out;
  bool first = true;
  for (std::size_t r = 0; r < runs.size() && r < run.scan_poses.size(); ++r)
  {
    const Recording& part = runs[r];
    const auto posed = std::find_if(run.scan_poses[r].begin(), run.scan_poses[r].end(),
                                    [](const std::optional<Pose2>& p) { return p.has_value(); });
    if ((!run.localized_at[r] && !run.joined_at[r]) || posed == run.scan_poses[r].end() || part.scans.empty())
      continue;
    if (first)
    {
      out.geometry = part.geometry;
      out.base_to_laser = part.base_to_laser;
      out.source = part.source;
      first = false;
    }
    else
    {
      const Pose2 d = out.base_to_laser.inverse() * part.base_to_laser;
      if (std::hypot(d.x, d.y) > 1e-6 || std::abs(d.theta) > 1e-6)
        throw std::invalid_argument("run " + std::to_string(r + 1) + " (" + part.source +
                                    "): its laser is mounted differently from the first run's; runs of "
                                    "one map must share the mounting");
      out.source += " + " + part.source;
    }
    const std::size_t at = static_cast<std::size_t>(posed - run.scan_poses[r].begin());
    const Pose2 to_map = **posed * part.scans[at].odom.inverse();
    const std::size_t offset = out.scans.size();
    Pose2 held = **posed;
    for (std::size_t i = 0; i < part.scans.size(); ++i)
    {
      const RecordedScan& scan = part.scans[i];
      RecordedScan s = scan;
      if (run.scan_poses[r][i]) held = *run.scan_poses[r][i];
      s.odom = odometry ? to_map * scan.odom : held;
      if (!s.geometry && !sameGeometry(part.geometry, out.geometry)) s.geometry = part.geometry;
      out.scans.push_back(std::move(s));
    }
    for (const CorrectedKeyframe& k : run.keyframes[r])
      out.keyframes.push_back({offset + k.scan_index, k.pose});
  }
  return out;
}

BatchDataset::SavedMap continuedMap(const line_map_merging::Session& loaded,
                                    const line_map_merging::SlamSession& joined, const std::string& origin,
                                    const Pose2& to_world)
{
  BatchDataset::SavedMap out;
  out.text = loaded.line_map;
  out.origin = origin;
  if (out.text.empty())
    throw std::runtime_error(origin +
                             ": the session holds no line map (it was saved without the cae merger), "
                             "so there is no map to continue");
  line_map_merging::CaeRlsm map;
  map.loadText(out.text, origin);
  std::unordered_set<double> in_map;
  for (const auto& k : map.keyframes()) in_map.insert(k.stamp);
  const auto& saved = loaded.slam.keyframes;
  for (std::size_t k = 0; k < saved.size() && k < joined.nodes.size(); ++k)
  {
    const Pose2 pose = to_world * joined.nodes[k];
    out.keyframe_poses.emplace_back(saved[k].stamp, pose);
    // The evaluation measures against the scans of the map's own keyframes, as for the new runs.
    if (in_map.count(saved[k].stamp))
      for (const auto& p : saved[k].points) out.points.push_back(pose.apply(p));
  }
  return out;
}

TwoSessionRun runTwoSessions(const Recording& recording, std::size_t cut,
                             const line_map_merging::LaserSlamParams& slam_params,
                             const line_map_merging::LocalizerParams& localizer_params, bool use_odometry,
                             const std::optional<Pose2>& start, std::size_t localize_scans)
{
  TwoSessionRun out;
  out.cut = std::min(cut, recording.scans.size());
  const std::vector<Recording> parts{recordingPart(recording, 0, out.cut, false),
                                     recordingPart(recording, out.cut, recording.scans.size(), true)};
  const SessionsRun run = runSessions(parts, std::nullopt, slam_params, localizer_params, use_odometry,
                                      {std::nullopt, start}, localize_scans);
  out.scan_poses = run.scan_poses[0];
  out.scan_poses.insert(out.scan_poses.end(), run.scan_poses[1].begin(), run.scan_poses[1].end());
  out.localized_at = run.localized_at[1];
  out.joined_at = run.joined_at[1];
  out.refused_as_ambiguous = run.refused_as_ambiguous[1];
  out.closures_between = run.closures_to_earlier[1];
  out.first_counters = run.counters[0];
  out.second_counters = run.counters[1];
  out.cpu_seconds = run.cpu_seconds;
  return out;
}

}  // namespace line_map_eval
