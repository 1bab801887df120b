#include "line_map_eval/online/bag_replay.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iomanip>
#include <stdexcept>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "line_map_eval/online/online_evaluator.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
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
  BackEndSchedule schedule{options.trajectories ? bag.trajectory : std::vector<TrajectoryEmission>{},
                           bag.map_to_odom};
  auto segments = [&](std::size_t i, const Pose2& odom)
  {
    const RecordedScan& scan = rec.scans[i];
    std::vector<linemap::Segment2> out;
    for (const auto& seg : extractor.extract(scanInput(rec.geometryOf(scan), scan.ranges)).segments)
      out.emplace_back(seg.start, seg.end);
    // As the extraction nodelet: registered in the odometry frame.
    for (const auto& seg : submap.update(extractor.preparedScan(), extractor.lastResult(), odom))
      out.emplace_back(seg.start, seg.end);
    return out;
  };
  OnlineDriveHooks hooks;
  // The evaluator nodelet receives the scan and the extractor's segments as the merger does.
  hooks.scan = [&](std::size_t i, const line_map_merging::StampedScan& s)
  {
    const RecordedScan& scan = rec.scans[i];
    const ScanGeometry& g = rec.geometryOf(scan);
    const ScanRanges ranges{g.angle_min, g.angle_increment, g.range_min, g.range_max, scan.ranges};
    evaluator.addScan(scan.stamp, ranges, s.laser, *s.odom);
    evaluator.addSegments(scan.stamp, s.segments, s.laser, *s.odom);
  };
  hooks.trajectory = [&](std::size_t, const TrajectoryEmission& t)
  {
    std::vector<std::pair<double, Pose2>> laser_poses;
    for (const auto& [stamp, base] : t.poses) laser_poses.emplace_back(stamp, base * mount);
    evaluator.addTrajectory(laser_poses);
  };
  ReplayResult out;
  out.trajectories = driveOnline(mapper, rec, schedule, segments, hooks);
  out.scans = rec.scans.size();
  out.keyframe_stamps = mapper.keyframeStamps();  // tf-gated ones and those trajectory nodes chose
  out.map = mapper.merger().map();
  out.leaves = mapper.merger().leafCount();
  out.counters = mapper.counters();
  std::vector<linemap::Segment2> segments_of_map;
  for (const auto& m : out.map) segments_of_map.push_back(m.segment);
  evaluator.setMap(segments_of_map, rec.scans.empty() ? 0.0 : rec.scans.back().stamp);
  out.metrics = evaluator.evaluateIfDue(0.0, true);
  out.evaluator_scans = evaluator.evaluator().scanCount();
  out.wall_ms = linemap::millisecondsSince(start);
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
