// Two robots into one map, offline (driveFleet, the merging nodelet's ~robots on recordings): the simulated
// office's drive cut in two overlapping parts, each driven by its own robot, each mapping in its own frame
// (its first pose) with its odometry from zero. The second robot sets out while the first is still driving,
// from where the first passed a little earlier. It must be placed in the first robot's map by its scans
// alone, where the truth puts it, and the joined map must be the map one robot makes driving the whole drive:
// ground-truth coverage and q within 0.5 points (the target). (A second robot setting out where the
// fleet has not been yet may be placed at a look-alike place: the office's ring corridor looks the same half
// a turn away.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "eval_test_helpers.hpp"
#include "line_extraction/line_extractor.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/online/fleet_drive.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;

namespace
{
const std::string kRoot = LINEMAP_SOURCE_DIR;

/// Scans [first, last) of the simulation as a robot of its own: its odometry from zero, its true poses
/// (the keyframes) in its own map frame, which is its first true pose, and its clock shifted by `shift`.
Recording robotPart(const Recording& rec, std::size_t first, std::size_t last, double shift, Pose2& frame)
{
  Recording part = recordingPart(rec, first, last, true);
  frame = rec.keyframes.at(first).pose;
  for (std::size_t i = first; i < last; ++i)
    part.keyframes.push_back({i - first, frame.inverse() * rec.keyframes.at(i).pose});
  for (auto& scan : part.scans) scan.stamp += shift;
  return part;
}

/// Every scan's segments, extracted once.
std::vector<std::vector<linemap::Segment2>> extractAll(const Recording& rec, const linemap::ParamSet& params)
{
  line_extraction::LineExtractor extractor(params);
  std::vector<std::vector<linemap::Segment2>> out;
  for (const RecordedScan& scan : rec.scans)
  {
    std::vector<linemap::Segment2> segments;
    for (const auto& s : extractor.extract(scanInput(rec.geometryOf(scan), scan.ranges)).segments)
      segments.emplace_back(s.start, s.end);
    out.push_back(std::move(segments));
  }
  return out;
}

std::vector<linemap::Segment2> mapIn(const line_map_merging::Merger& merger, const Pose2& to_world)
{
  std::vector<linemap::Segment2> out;
  for (const auto& s : merger.map()) out.push_back(s.segment.transformed(to_world));
  return out;
}
}  // namespace

TEST(Fleet, TwoRobotsMakeTheMapOneRobotMakesOfBothHalves)
{
  std::vector<std::string> files;
  for (const char* name : {"line_extraction.yaml", "line_map_merging.yaml", "line_map_eval.yaml"})
    files.push_back(kRoot + "/config/" + name);
  const linemap::ParamSet params = loadParameterFiles(files);
  const auto mapper_params = line_map_merging::OnlineMapperParams::fromParams(params);
  const SimulationResult sim = simulate(loadWorld(kRoot + "/config/worlds/office.yaml"));
  const Recording& rec = sim.recording;
  const std::size_t n = rec.scans.size(), first_end = 6 * n / 10, second_start = 45 * n / 100;
  const std::size_t every = 50;  // keyframes per trajectory, as linemap_batch's back end stand-in

  // One robot driving both halves.
  const std::vector<std::vector<linemap::Segment2>> lines = extractAll(rec, params);
  line_map_merging::OnlineMapper single(line_map_merging::makeMerger("cae", params), mapper_params);
  driveOnline(single, rec, loopClosureSchedule(rec, every),
              [&](std::size_t i, const Pose2&) { return lines[i]; });

  // Two robots, the second setting out when the first reaches the middle of the drive.
  Pose2 frame_a, frame_b;
  const Recording a = robotPart(rec, 0, first_end, 0.0, frame_a);
  const Recording b =
      robotPart(rec, second_start, n, rec.scans[n / 2].stamp - rec.scans[second_start].stamp, frame_b);
  line_map_merging::OnlineMapper fleet(line_map_merging::makeMerger("cae", params), mapper_params);
  line_map_merging::FleetPlacement placement(line_map_merging::LocalizerParams::fromParams(
      loadParameterFiles({kRoot + "/config/localization.yaml"})));
  const FleetDrive drive =
      driveFleet(fleet, placement,
                 {{&a, loopClosureSchedule(a, every), [&](std::size_t i, const Pose2&) { return lines[i]; }},
                  {&b, loopClosureSchedule(b, every),
                   [&](std::size_t i, const Pose2&) { return lines[second_start + i]; }}});
  ASSERT_TRUE(drive.placements.at(1).has_value()) << "the second robot was never placed";
  const Pose2 truth = frame_a.inverse() * frame_b;
  const Pose2 error = truth.inverse() * *drive.placements[1];
  std::printf("second robot placed at its scan %zu of %zu: %.3f m, %.4f rad from the truth\n",
              *drive.placed_at[1], b.scans.size(), std::hypot(error.x, error.y), error.theta);
  EXPECT_LT(std::hypot(error.x, error.y), 0.1);
  EXPECT_LT(std::fabs(error.theta), 0.02);

  const GroundTruthParams truth_params = GroundTruthParams::fromParams(params);
  const LookupTable table =
      LookupTable::build(registeredScanPoints(rec), LookupTableParams::fromParams(params));
  const QualityParams quality = QualityParams::fromParams(params);
  const std::vector<linemap::Segment2> one = mapIn(single.merger(), Pose2()),
                                       two = mapIn(fleet.merger(), frame_a);
  const double one_coverage = 100.0 * evaluateAgainstGroundTruth(sim.truth, one, truth_params).coverage;
  const double two_coverage = 100.0 * evaluateAgainstGroundTruth(sim.truth, two, truth_params).coverage;
  const double one_q = computeMapQuality(table, one, quality).quality;
  const double two_q = computeMapQuality(table, two, quality).quality;
  std::printf(
      "one robot: %zu keyframes, %zu segments, coverage %.2f %%, q %.2f %%; two robots: %zu keyframes, "
      "%zu segments, coverage %.2f %%, q %.2f %%\n",
      single.merger().keyframeCount(), one.size(), one_coverage, one_q, fleet.merger().keyframeCount(),
      two.size(), two_coverage, two_q);
  EXPECT_GE(two_coverage, one_coverage - 0.5);
  EXPECT_GE(two_q, one_q - 0.5);
  EXPECT_EQ(fleet.counters().unplaced_dropped, 0u);
}
