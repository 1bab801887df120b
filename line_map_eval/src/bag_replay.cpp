#include "line_map_eval/bag_replay.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iomanip>
#include <stdexcept>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "line_map_eval/online_evaluator.hpp"

namespace line_map_eval
{
namespace
{
/// Pose at `t` from samples sorted by time: interpolated between the two around it, clamped at the
/// ends (tf would wait for a later sample; the bags carry one at every scan).
linemap::Pose2 sampleAt(const std::vector<std::pair<double, Pose2>>& samples, double t)
{
  const auto after = std::lower_bound(samples.begin(), samples.end(), t,
                                      [](const auto& s, double v) { return s.first < v; });
  if (after == samples.end()) return samples.back().second;
  if (after == samples.begin() || after->first == t) return after->second;
  const auto& before = *(after - 1);
  return linemap::interpolate(before.second, after->second,
                              (t - before.first) / (after->first - before.first));
}
}  // namespace

ReplayResult replayBag(const BagContents& bag, const ReplayOptions& options)
{
  const auto start = std::chrono::steady_clock::now();
  const Recording& rec = bag.recording;
  line_extraction::LineExtractor extractor(options.params);
  line_extraction::SubmapExtractor submap(line_extraction::SubmapParams::fromParams(options.params),
                                          extractor.params().sensor);
  line_map_merging::OnlineMapper mapper(line_map_merging::makeMerger(options.method, options.params),
                                        line_map_merging::OnlineMapperParams::fromParams(options.params));
  OnlineEvaluator evaluator(OnlineEvaluatorParams::fromParams(options.params));
  const Pose2& mount = rec.base_to_laser;
  ReplayResult out;
  std::size_t next_trajectory = 0;
  for (const RecordedScan& scan : rec.scans)
  {
    ++out.scans;
    const Pose2 odom = scan.odom * mount;
    const Pose2 laser = bag.map_to_odom.empty() ? odom : sampleAt(bag.map_to_odom, scan.stamp) * odom;
    line_map_merging::StampedScan s;
    s.stamp = scan.stamp;
    s.laser = laser;
    s.odom = odom;
    s.mount = mount;
    const ScanGeometry& g = rec.geometryOf(scan);
    for (const auto& seg : extractor.extract(scanInput(g, scan.ranges)).segments)
      s.segments.emplace_back(seg.start, seg.end);
    // As the extraction nodelet: registered in the odometry frame.
    for (const auto& seg : submap.update(extractor.preparedScan(), extractor.lastResult(), odom))
      s.segments.emplace_back(seg.start, seg.end);
    // The evaluator nodelet receives the scan and the extractor's segments as the merger does.
    const ScanRanges ranges{g.angle_min, g.angle_increment, g.range_min, g.range_max, scan.ranges};
    evaluator.addScan(scan.stamp, ranges, laser, odom);
    evaluator.addSegments(scan.stamp, s.segments, laser, odom);
    mapper.addScan(s);
    for (; options.trajectories && next_trajectory < bag.trajectory.size() &&
           bag.trajectory[next_trajectory].stamp <= scan.stamp;
         ++next_trajectory)
    {
      const auto& nodes = bag.trajectory[next_trajectory].poses;
      mapper.addTrajectory(nodes);
      std::vector<std::pair<double, Pose2>> laser_poses;
      for (const auto& [stamp, base] : nodes) laser_poses.emplace_back(stamp, base * mount);
      evaluator.addTrajectory(laser_poses);
      ++out.trajectories;
    }
  }
  out.keyframe_stamps = mapper.keyframeStamps();  // tf-gated ones and those trajectory nodes chose
  out.map = mapper.merger().map();
  out.leaves = mapper.merger().leafCount();
  out.counters = mapper.counters();
  std::vector<linemap::Segment2> segments;
  for (const auto& m : out.map) segments.push_back(m.segment);
  evaluator.setMap(segments, rec.scans.empty() ? 0.0 : rec.scans.back().stamp);
  out.metrics = evaluator.evaluateIfDue(0.0, true);
  out.evaluator_scans = evaluator.evaluator().scanCount();
  out.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

void writeReplayJson(const ReplayResult& r, const std::string& path)
{
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write the replay result");
  f << std::setprecision(17) << "{\n  \"scans\": " << r.scans << ",\n  \"trajectories\": " << r.trajectories
    << ",\n  \"leaves\": " << r.leaves << ",\n  \"evaluator_scans\": " << r.evaluator_scans
    << ",\n  \"adjustments\": " << r.counters.adjustments
    << ",\n  \"unmatched_poses\": " << r.counters.unmatched_poses;
  if (r.metrics)
    f << ",\n  \"quality\": " << r.metrics->quality.quality
      << ",\n  \"error\": " << r.metrics->error.mean_error;
  f << ",\n  \"keyframe_stamps\": [";
  for (std::size_t i = 0; i < r.keyframe_stamps.size(); ++i) f << (i ? ", " : "") << r.keyframe_stamps[i];
  f << "],\n  \"segments\": [";
  for (std::size_t i = 0; i < r.map.size(); ++i)
  {
    const auto& s = r.map[i].segment;
    f << (i ? ",\n    " : "\n    ") << "[" << r.map[i].id << ", " << s.start.x() << ", " << s.start.y()
      << ", " << s.end.x() << ", " << s.end.y() << "]";
  }
  f << "]\n}\n";
  if (!f) throw std::runtime_error(path + ": write failed");
}

}  // namespace line_map_eval
