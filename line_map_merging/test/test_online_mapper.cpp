// The online mapper without ROS, fed what a real SLAM front and back end send: scans posed through
// a drifting odometry and a jumping map->odom, trajectories whose nodes are not the mapper's
// keyframes, bursts, replays, out-of-order and duplicate stamps.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <unordered_map>

#include "drift_drive.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "linemap/atomic_file.hpp"

using namespace line_map_merging;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

using namespace drift_drive;

namespace
{
OnlineMapperParams params()
{
  OnlineMapperParams p;
  p.gate.distance = 0.19;  // every 4th scan (0, 4, 8, ...): the chord of 4 drifting steps is > 0.19 m
  p.gate.angle = 1.0;
  // The keyframe gate on tf chooses every keyframe: these tests correct keyframes that are no nodes.
  // The nodes choose them in the OnlineMapperNodes tests below.
  p.keyframe_source = KeyframeSource::kTf;
  return p;
}

std::unique_ptr<OnlineMapper> mapper(const OnlineMapperParams& p = params())
{
  return std::make_unique<OnlineMapper>(makeMerger("cae", linemap::ParamSet()), p);
}

int scanOf(const Drive& run, double stamp)
{
  return static_cast<int>(std::find(run.stamps.begin(), run.stamps.end(), stamp) - run.stamps.begin());
}

/// Largest position error [m] and heading error [rad] of the keyframes against the truth.
std::pair<double, double> keyframeError(const Drive& run, const OnlineMapper& m)
{
  double dp = 0.0, da = 0.0;
  for (const KeyframeInfo& k : m.merger().keyframes())
  {
    const Pose2& t = run.truth[scanOf(run, k.stamp)];
    dp = std::max(dp, std::hypot(k.pose.x - t.x, k.pose.y - t.y));
    da = std::max(da, std::abs(linemap::normalizeAngle(k.pose.theta - t.theta)));
  }
  return {dp, da};
}

// Relative odometry over the two scans to the nearest node: heading off by at most 2 kDrift, position
// by at most 0.05 * (kDrift + 2 kDrift) = 1.5 mm.
constexpr double kPosTol = 0.002, kAngleTol = 2.0 * kDrift + 1e-9;

/// Every keyframe of `m` on the truth within kPosTol and kAngleTol.
void expectKeyframesOnTheTruth(const Drive& run, const OnlineMapper& m)
{
  const auto error = keyframeError(run, m);
  EXPECT_LT(error.first, kPosTol);
  EXPECT_LT(error.second, kAngleTol);
}
}  // namespace

TEST(OnlineMapper, KeyframeGateAndCounters)
{
  Drive run;
  auto m = mapper();
  for (int i = 0; i < kScans; ++i) m->addScan(run.scan(i));
  EXPECT_EQ(m->merger().keyframeCount(), static_cast<std::size_t>(kScans / 4));
  for (const KeyframeInfo& k : m->merger().keyframes()) EXPECT_EQ(scanOf(run, k.stamp) % 4, 0);
  EXPECT_EQ(m->counters().scans, static_cast<std::size_t>(kScans));
  EXPECT_EQ(m->counters().below_gate, static_cast<std::size_t>(kScans - kScans / 4));
  EXPECT_GT(m->merger().segmentCount(), 0u);
}

TEST(OnlineMapper, TrajectoryNodesThatAreNoKeyframesCorrectEveryKeyframe)
{
  Drive run;
  auto m = mapper();
  for (int i = 0; i < kScans; ++i) m->addScan(run.scan(i));
  const auto before = keyframeError(run, *m);
  ASSERT_GT(before.first, 1.0);  // the drift the trajectory must remove
  ASSERT_TRUE(m->addTrajectory(run.nodes()));
  EXPECT_EQ(m->counters().unmatched_poses, 0u);
  expectKeyframesOnTheTruth(run, *m);
  // The map lies on the wall y = 1 again.
  for (const MapSegment& s : m->merger().map())
  {
    EXPECT_NEAR(s.segment.start.y(), 1.0, 0.01);
    EXPECT_NEAR(s.segment.end.y(), 1.0, 0.01);
  }
}

TEST(OnlineMapper, InterpolatedCorrectionsAlsoReachTheTruth)
{
  Drive run;
  OnlineMapperParams p = params();
  p.correction = CorrectionMode::kInterpolate;
  auto m = mapper(p);
  for (int i = 0; i < kScans; ++i) m->addScan(run.scan(i));
  ASSERT_TRUE(m->addTrajectory(run.nodes()));
  EXPECT_LT(keyframeError(run, *m).first, 0.01);
}

TEST(OnlineMapperMapToOdom, JumpsOfMapToOdomDoNotMoveTheCorrectedKeyframes)
{
  // The back end's map->odom jumps at scans 40 and 80 (as a SLAM publishes new estimates); the
  // keyframes are registered through it, but corrected from their odometry: the same result.
  Drive run;
  auto m = mapper();
  for (int i = 0; i < kScans; ++i)
    m->addScan(run.scan(i, i < 40 ? Pose2() : i < 80 ? Pose2(3.0, -2.0, 0.7) : Pose2(-5.0, 4.0, -2.5)));
  ASSERT_TRUE(m->addTrajectory(run.nodes()));
  expectKeyframesOnTheTruth(run, *m);
}

TEST(OnlineMapperBursts, ATrajectoryAfterEveryScanEndsOnTheTruth)
{
  // A back end publishing after every scan the nodes known so far, and tf map -> odom following
  // its latest node: over a hundred adjustments, each from the odometry, none compounding.
  Drive run;
  auto m = mapper();
  Pose2 map_to_odom;
  for (int i = 0; i < kScans; ++i)
  {
    m->addScan(run.scan(i, map_to_odom));
    std::vector<StampedPose> so_far;
    for (const auto& n : run.nodes())
      if (n.first <= run.stamps[i]) so_far.push_back(n);
    if (so_far.empty()) continue;
    m->addTrajectory(so_far);
    const int last = scanOf(run, so_far.back().first);
    map_to_odom = run.truth[last] * run.odom[last].inverse();
  }
  for (int k = 0; k < 5; ++k) m->addTrajectory(run.nodes());
  EXPECT_GT(m->counters().adjustments, 100u);
  EXPECT_GT(m->merger().keyframeCount(), static_cast<std::size_t>(kScans / 5));
  expectKeyframesOnTheTruth(run, *m);
}

TEST(OnlineMapperReplay, AReplayAfterTheClockJumpedBackAddsNothing)
{
  Drive run;
  auto m = mapper();
  for (int i = 0; i < kScans; ++i)
  {
    EXPECT_FALSE(m->observeTime(run.stamps[i], run.stamps[i]));
    m->addScan(run.scan(i));
  }
  const std::size_t keyframes = m->merger().keyframeCount(), segments = m->merger().segmentCount();
  const std::uint64_t revision = m->revision();
  // rosbag play --loop: the clock restarts.
  EXPECT_TRUE(m->observeTime(run.stamps[0], run.stamps[0]));
  EXPECT_EQ(m->counters().time_jumps, 1u);
  for (int i = 0; i < kScans; ++i)
  {
    m->observeTime(run.stamps[i], run.stamps[i]);
    const ScanOutcome o = m->addScan(run.scan(i));
    EXPECT_EQ(o, i % 4 == 0 ? ScanOutcome::kReplayed : ScanOutcome::kBelowGate) << "scan " << i;
  }
  EXPECT_EQ(m->counters().time_jumps, 1u);
  EXPECT_EQ(m->merger().keyframeCount(), keyframes);
  EXPECT_EQ(m->merger().segmentCount(), segments);
  EXPECT_EQ(m->counters().replayed, keyframes);
  EXPECT_EQ(m->revision(), revision);
}

TEST(OnlineMapperStamps, OutOfOrderAndDuplicateNodesGiveTheSameCorrection)
{
  Drive run;
  auto clean = mapper(), messy = mapper();
  for (int i = 0; i < kScans; ++i)
  {
    clean->addScan(run.scan(i));
    messy->addScan(run.scan(i));
  }
  auto nodes = run.nodes();
  clean->addTrajectory(nodes);
  auto shuffled = nodes;
  shuffled.insert(shuffled.end(), nodes.begin(), nodes.end());  // every node twice
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(7));
  messy->addTrajectory(shuffled);
  const auto a = clean->merger().keyframes(), b = messy->merger().keyframes();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_NEAR(a[i].pose.x, b[i].pose.x, 1e-12);
    EXPECT_NEAR(a[i].pose.y, b[i].pose.y, 1e-12);
  }
}

TEST(OnlineMapperStamps, LateScansDuplicatesAndZeroStamps)
{
  Drive run;
  auto m = mapper();
  // Scans 0..7 with scan 6 arriving after 7 (a late scan the tf filter let through).
  for (int i : {0, 1, 2, 3, 4, 5, 7, 6}) m->addScan(run.scan(i));
  EXPECT_EQ(m->merger().keyframeCount(), 2u);  // scans 0 and 4; late 6 is within the gate of 4
  // The same stamp again is a replay of keyframe 4; stamp zero is dropped.
  EXPECT_EQ(m->addScan(run.scan(4)), ScanOutcome::kReplayed);
  StampedScan zero = run.scan(8);
  zero.stamp = 0.0;
  EXPECT_EQ(m->addScan(zero), ScanOutcome::kZeroStamp);
  EXPECT_EQ(m->counters().zero_stamps, 1u);
  // A node at the late scan 6 is found (it was seen) and corrects keyframe 4 by the odometry from 6.
  ASSERT_TRUE(m->addTrajectory({{run.stamps[6], run.truth[6]}}));
  const auto ks = m->merger().keyframes();
  const Pose2 expected = run.truth[6] * run.odom[6].inverse() * run.odom[4];
  EXPECT_NEAR(ks[1].pose.x, expected.x, 1e-9);
  EXPECT_NEAR(ks[1].pose.y, expected.y, 1e-9);
  // A node between two scans (another sensor's stamp) takes the interpolated odometry; one
  // outside the scans seen is unmatched; a non-finite one is counted as bad.
  EXPECT_TRUE(m->addTrajectory({{0.5 * (run.stamps[2] + run.stamps[3]), Pose2(0.125, 0.0, 0.0)},
                                {run.stamps[50], run.truth[50]},
                                {run.stamps[1], Pose2(NAN, 0.0, 0.0)}}));
  EXPECT_EQ(m->counters().unmatched_poses, 1u);
  EXPECT_EQ(m->counters().bad_poses, 1u);
}

TEST(OnlineMapperAutosave, DueOnlyWhenChangedAndThePeriodPassed)
{
  Drive run;
  OnlineMapperParams p = params();
  EXPECT_FALSE(mapper(p)->autosaveDue(1e9));  // off by default
  p.autosave_period = 2.0;
  auto m = mapper(p);
  EXPECT_FALSE(m->autosaveDue(10.0));  // nothing to save
  m->addScan(run.scan(0));
  EXPECT_TRUE(m->autosaveDue(10.0));
  m->autosaved(m->revision(), 10.0, true);
  EXPECT_FALSE(m->autosaveDue(20.0));  // unchanged
  m->addScan(run.scan(4));
  EXPECT_FALSE(m->autosaveDue(11.0));  // changed, but within the period
  EXPECT_TRUE(m->autosaveDue(12.0));
  m->autosaved(m->revision(), 12.0, false);
  EXPECT_EQ(m->counters().autosave_failures, 1u);
  EXPECT_TRUE(m->autosaveDue(14.0));  // still unsaved
  // A change made while a snapshot was being written keeps the map due.
  const std::uint64_t snapshot = m->revision();
  m->addScan(run.scan(8));
  m->autosaved(snapshot, 14.0, true);
  EXPECT_TRUE(m->autosaveDue(16.0));
  EXPECT_EQ(m->counters().autosaves, 2u);
}

TEST(OnlineMapperFiles, ALoadedMapTakesTheSameTrajectoryLikeTheOriginal)
{
  // Every keyframe a node (the restart case): the loaded keyframes, whose odometry is unknown,
  // end where the original's do.
  Drive run;
  auto original = mapper();
  for (int i = 0; i < kScans; ++i) original->addScan(run.scan(i));
  const std::string path =
      (std::filesystem::temp_directory_path() / ("online_mapper_" + std::to_string(::getpid()) + ".yaml"))
          .string();
  original->merger().save(path);
  auto loaded = mapper();
  loaded->load(path);
  std::filesystem::remove(path);
  std::vector<StampedPose> nodes;
  for (int i = 0; i < kScans; i += 4) nodes.emplace_back(run.stamps[i], run.truth[i]);
  original->addTrajectory(nodes);
  loaded->addTrajectory(nodes);
  const auto a = original->merger().map(), b = loaded->merger().map();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_NEAR(a[i].segment.start.x(), b[i].segment.start.x(), 1e-6);
    EXPECT_NEAR(a[i].segment.end.y(), b[i].segment.end.y(), 1e-6);
  }
  // The loaded keyframes are known: a replay of them adds nothing; reset forgets them.
  EXPECT_EQ(loaded->addScan(run.scan(0)), ScanOutcome::kReplayed);
  loaded->reset();
  EXPECT_EQ(loaded->merger().keyframeCount(), 0u);
  EXPECT_EQ(loaded->addScan(run.scan(0)), ScanOutcome::kKeyframe);
}

using namespace drift_drive;

namespace
{
OnlineMapperParams nodeParams(KeyframeSource source)
{
  OnlineMapperParams p = params();
  p.keyframe_source = source;
  return p;
}

}  // namespace

TEST(OnlineMapperNodes, AfterTheFirstTrajectoryTheNodesAreTheKeyframesAtTheirOwnPoses)
{
  // Scans 0..39 on tf: keyframes 0, 4, ..., 36. The trajectory of nodes 2, 6, ..., 38 adjusts them and
  // from then on only nodes become keyframes, each exactly at its node's pose: nothing interpolated.
  Drive run;
  OnlineMapperParams p = nodeParams(KeyframeSource::kAuto);
  p.keyframe_buffer = 3.0;  // scans 0..8 are no longer held: the tf keyframes stay
  auto m = mapper(p);
  // A trajectory that names no scan seen (here: before any) leaves the choice to the tf gate.
  EXPECT_FALSE(m->addTrajectory({{run.stamps[2], run.truth[2]}}));
  EXPECT_FALSE(m->nodesChoose());
  for (int i = 0; i < 40; ++i) m->addScan(run.scan(i));
  EXPECT_FALSE(m->nodesChoose());
  EXPECT_EQ(m->merger().keyframeCount(), 10u);
  m->addTrajectory(nodesUpTo(run, 39));
  EXPECT_TRUE(m->nodesChoose());
  // Node 38 is 0.1 m past keyframe 36: below the gate, not merged.
  EXPECT_EQ(m->merger().keyframeCount(), 10u);
  Pose2 map_to_odom = run.truth[38] * run.odom[38].inverse();
  for (int i = 40; i < kScans; ++i)
  {
    const ScanOutcome o = m->addScan(run.scan(i, map_to_odom));
    EXPECT_EQ(o, ScanOutcome::kHeld) << "scan " << i;  // no trajectory names it yet
    if (i % 20 != 19) continue;
    m->addTrajectory(nodesUpTo(run, i));
    map_to_odom = run.truth[i - 1] * run.odom[i - 1].inverse();
  }
  // Nodes 42, 46, ..., 118 are 0.2 m apart (> the 0.19 m gate): every one a keyframe.
  EXPECT_EQ(m->merger().keyframeCount(), 10u + 20u);
  EXPECT_EQ(m->counters().rebuilds, 0u);
  EXPECT_EQ(m->counters().node_keyframes, 20u);
  for (const KeyframeInfo& k : m->merger().keyframes())
  {
    const int i = scanOf(run, k.stamp);
    if (i < 40) continue;
    EXPECT_EQ(i % 4, 2) << "keyframe at scan " << i << " is no node";
    EXPECT_NEAR(k.pose.x, run.truth[i].x, 1e-9);
    EXPECT_NEAR(k.pose.y, run.truth[i].y, 1e-9);
    EXPECT_NEAR(k.pose.theta, run.truth[i].theta, 1e-9);
  }
  for (const MapSegment& s : m->merger().map())
  {
    EXPECT_NEAR(s.segment.start.y(), 1.0, 0.01);
    EXPECT_NEAR(s.segment.end.y(), 1.0, 0.01);
  }
}

TEST(OnlineMapperNodes, WhileEveryScanIsHeldTheFirstTrajectoryRebuildsTheMapFromItsNodes)
{
  // Scans 0..39 on tf (keyframes 0, 4, ..., 36), all still held: the first trajectory makes the map
  // again from its nodes 2, 6, ..., 38, each at its own pose, as if the nodes had chosen from the start.
  Drive run;
  auto m = mapper(nodeParams(KeyframeSource::kAuto));
  auto only_nodes = mapper(nodeParams(KeyframeSource::kTrajectory));
  for (int i = 0; i < 40; ++i)
  {
    m->addScan(run.scan(i));
    only_nodes->addScan(run.scan(i));
  }
  EXPECT_EQ(m->merger().keyframeCount(), 10u);
  EXPECT_TRUE(m->addTrajectory(nodesUpTo(run, 39)));
  only_nodes->addTrajectory(nodesUpTo(run, 39));
  EXPECT_EQ(m->counters().rebuilds, 1u);
  EXPECT_EQ(m->merger().keyframeCount(), 10u);
  for (const KeyframeInfo& k : m->merger().keyframes())
  {
    const int i = scanOf(run, k.stamp);
    EXPECT_EQ(i % 4, 2) << "keyframe at scan " << i << " is no node";
    EXPECT_NEAR(k.pose.x, run.truth[i].x, 1e-9);
    EXPECT_NEAR(k.pose.y, run.truth[i].y, 1e-9);
  }
  expectSameMap(*m, *only_nodes, false);  // m gated scans on tf before
}

TEST(OnlineMapperNodes, ANodeWaitsForItsScanSoTheOrderOfArrivalDoesNotMatter)
{
  // Scans first and then each trajectory, against each trajectory first (its newest nodes' scans
  // still in the extraction or the tf filter): the same keyframes, the same map.
  Drive run;
  auto scans_first = mapper(nodeParams(KeyframeSource::kTrajectory));
  auto nodes_first = mapper(nodeParams(KeyframeSource::kTrajectory));
  EXPECT_TRUE(scans_first->nodesChoose());
  for (int block = 0; block < kScans / 20; ++block)
  {
    const int last = block * 20 + 19;
    for (int i = block * 20; i <= last; ++i) EXPECT_EQ(scans_first->addScan(run.scan(i)), ScanOutcome::kHeld);
    scans_first->addTrajectory(nodesUpTo(run, last));
    nodes_first->addTrajectory(nodesUpTo(run, last));
    for (int i = block * 20; i <= last; ++i)
      EXPECT_EQ(nodes_first->addScan(run.scan(i)), i % 4 == 2 ? ScanOutcome::kKeyframe : ScanOutcome::kHeld)
          << "scan " << i;
  }
  EXPECT_EQ(scans_first->merger().keyframeCount(), static_cast<std::size_t>(kScans / 4));
  expectSameMap(*scans_first, *nodes_first);
}

TEST(OnlineMapperNodes, AReplayAddsNothingAndTheBufferIsBounded)
{
  Drive run;
  OnlineMapperParams p = nodeParams(KeyframeSource::kTrajectory);
  p.keyframe_buffer = 1.0;  // 10 scans
  auto m = mapper(p);
  for (int i = 0; i < 60; ++i) m->addScan(run.scan(i));
  // Scans older than the buffer are gone: nodes 2..46 (stamps before scan 49) find none.
  const auto diag = [&](const std::string& key)
  {
    for (const auto& [k, v] : m->diagnostics())
      if (k == key) return std::stoul(v);
    return 9999ul;
  };
  EXPECT_LE(diag("scans held for a trajectory"), 11u);
  m->addTrajectory(nodesUpTo(run, 59));
  EXPECT_EQ(diag("nodes without a scan"), 12u);
  EXPECT_EQ(m->merger().keyframeCount(), 3u);          // nodes 50, 54, 58
  EXPECT_EQ(diag("scans held for a trajectory"), 1u);  // scan 59, after the newest node
  // rosbag play --loop: the same scans and trajectory again add nothing.
  const std::uint64_t keyframes = m->merger().keyframeCount();
  m->observeTime(run.stamps[0], run.stamps[0]);
  for (int i = 0; i < 60; ++i) m->addScan(run.scan(i));
  m->addTrajectory(nodesUpTo(run, 59));
  EXPECT_EQ(m->merger().keyframeCount(), keyframes);
  EXPECT_EQ(diag("nodes without a scan"), 12u);
}

TEST(TrajectoryAnchor, HistoryAndCorrections)
{
  OdometryHistory h;
  h.add(1.0, Pose2(0.0, 0.0, 0.0));
  h.add(2.0, Pose2(1.0, 0.0, 0.2));
  h.add(2.0, Pose2(9.0, 9.0, 0.0));  // a replayed stamp keeps the first pose
  EXPECT_NEAR(h.at(2.004, 0.01, 1.0)->x, 1.0, 1e-12);
  EXPECT_NEAR(h.at(1.25, 0.01, 1.0)->x, 0.25, 1e-12);  // interpolated
  EXPECT_NEAR(h.at(1.25, 0.01, 1.0)->theta, 0.05, 1e-12);
  EXPECT_FALSE(h.at(1.25, 0.01, 0.5).has_value());  // scans too far apart
  EXPECT_FALSE(h.at(2.5, 0.01, 1.0).has_value());   // after the last scan
  const std::vector<std::pair<double, Pose2>> c{{1.0, Pose2(1.0, 0.0, 0.0)}, {2.0, Pose2(3.0, 0.0, 0.0)}};
  EXPECT_NEAR(correctionAt(c, 1.4, CorrectionMode::kNearest).x, 1.0, 1e-12);
  EXPECT_NEAR(correctionAt(c, 1.6, CorrectionMode::kNearest).x, 3.0, 1e-12);
  EXPECT_NEAR(correctionAt(c, 1.25, CorrectionMode::kInterpolate).x, 1.5, 1e-12);
  EXPECT_NEAR(correctionAt(c, 0.0, CorrectionMode::kInterpolate).x, 1.0, 1e-12);
  EXPECT_NEAR(correctionAt(c, 9.0, CorrectionMode::kNearest).x, 3.0, 1e-12);
  EXPECT_THROW(correctionModeFromString("trajectory_correction", "spline"), linemap::ParameterError);
}

TEST(TrajectoryAnchor, ScansAndNodesOutOfOrder)
{
  // A scan that arrives late goes in its place in time; a stamp seen before keeps its first pose.
  OdometryHistory h;
  h.add(3.0, Pose2(3.0, 0.0, 0.0));
  h.add(1.0, Pose2(1.0, 0.0, 0.0));
  h.add(2.0, Pose2(2.0, 0.0, 0.0));
  h.add(1.0, Pose2(7.0, 0.0, 0.0));
  EXPECT_EQ(h.size(), 3u);
  EXPECT_NEAR(h.at(1.5, 0.01, 1.0)->x, 1.5, 1e-12);
  EXPECT_NEAR(h.at(2.75, 0.01, 1.0)->x, 2.75, 1e-12);
  EXPECT_NEAR(h.at(1.0, 0.01, 1.0)->x, 1.0, 1e-12);

  // Nodes in any order come out in stamp order; a stamp named twice takes its last pose. The
  // correction is node * odometry^-1: here a shift of x by (node x - odometry x).
  const std::vector<std::pair<double, Pose2>> nodes{{3.0, Pose2(3.5, 0.0, 0.0)},
                                                    {1.0, Pose2(1.1, 0.0, 0.0)},
                                                    {3.0, Pose2(3.2, 0.0, 0.0)},
                                                    {2.0, Pose2(2.3, 0.0, 0.0)},
                                                    {9.0, Pose2()}};
  const NodeCorrections nc = nodeCorrections(h, nodes, 0.01, 1.0);
  EXPECT_EQ(nc.unmatched, 1u);  // 9.0 lies after the last scan
  ASSERT_EQ(nc.corrections.size(), 3u);
  const double stamps[] = {1.0, 2.0, 3.0}, shifts[] = {0.1, 0.3, 0.2};
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_EQ(nc.corrections[i].first, stamps[i]);
    EXPECT_NEAR(nc.corrections[i].second.x, shifts[i], 1e-12);
  }
}

// A saved map joined by a run that mapped apart in another frame (OnlineMapper::appendText): the first half
// of the drive mapped and saved; the second half mapped in a frame `moved` from the first's. Appended at
// `moved`, the saved keyframes lie where the second run's frame has them (at once, before any trajectory),
// and a trajectory of both halves in that frame (naming the saved keyframes by stamp) puts every keyframe on
// the truth there. A file that cannot be read changes nothing.
TEST(OnlineMapperFiles, AnAppendedMapJoinsAtThePlaceGivenAndMovesWithTheTrajectory)
{
  Drive run;
  const int half = kScans / 2;
  auto first = mapper();
  for (int i = 0; i < half; ++i) first->addScan(run.scan(i));
  const std::string path =
      (std::filesystem::temp_directory_path() / ("online_append_" + std::to_string(::getpid()) + ".yaml"))
          .string();
  first->merger().save(path);
  const std::string text = linemap::readWholeFile(path, "map file");
  std::filesystem::remove(path);
  const std::size_t saved_keyframes = first->merger().keyframeCount();

  const Pose2 moved(3.0, -1.0, 0.5);  // the first run's map frame in the second's
  auto second = mapper();
  for (int i = half; i < kScans; ++i) second->addScan(run.scan(i, moved));
  const std::size_t own_keyframes = second->merger().keyframeCount();
  EXPECT_THROW(second->appendText(text.substr(0, text.size() / 2), "cut", moved), MapFileError);
  EXPECT_EQ(second->merger().keyframeCount(), own_keyframes);

  EXPECT_EQ(second->appendText(text, "saved", moved), saved_keyframes);
  EXPECT_EQ(second->merger().keyframeCount(), saved_keyframes + own_keyframes);
  EXPECT_EQ(second->appendText(text, "saved", moved), 0u) << "keyframes it has are skipped";
  std::unordered_map<double, Pose2> saved_pose;
  for (const KeyframeInfo& k : first->merger().keyframes()) saved_pose.emplace(k.stamp, k.pose);
  std::size_t placed = 0;
  for (const KeyframeInfo& k : second->merger().keyframes())
    if (const auto it = saved_pose.find(k.stamp); it != saved_pose.end())
    {
      const Pose2 expected = moved * it->second;
      EXPECT_NEAR(k.pose.x, expected.x, 1e-9);
      EXPECT_NEAR(k.pose.y, expected.y, 1e-9);
      EXPECT_NEAR(linemap::normalizeAngle(k.pose.theta - expected.theta), 0.0, 1e-9);
      ++placed;
    }
  EXPECT_EQ(placed, saved_keyframes);
  std::vector<StampedPose> nodes;
  for (int i = 0; i < kScans; i += 2) nodes.emplace_back(run.stamps[i], moved * run.truth[i]);
  second->addTrajectory(nodes);
  double worst = 0.0;
  for (const KeyframeInfo& k : second->merger().keyframes())
  {
    const Pose2 t = moved * run.truth[scanOf(run, k.stamp)];
    worst = std::max(worst, std::hypot(k.pose.x - t.x, k.pose.y - t.y));
  }
  EXPECT_LT(worst, kPosTol);
  // The saved originals are in the map: the wall reaches back to where the first half began seeing it.
  const Vec2 wall_start = moved.apply(Vec2(-1.0, 1.0));
  double nearest = 1e9;
  for (const MapSegment& m : second->merger().map())
    nearest = std::min({nearest, (m.segment.start - wall_start).norm(), (m.segment.end - wall_start).norm()});
  EXPECT_LT(nearest, 0.01);
}

// Two robots into one map (lanes): both drive the same drive at the same stamps, the second in its own map
// frame, which lies at `placed` in the first's. Until it is placed its scans and trajectory wait; placed, its
// scans become keyframes of their own (the same stamps as the first robot's keyframes, yet no replay) and
// its trajectory, in its own frame, puts them on the truth; each robot's trajectory moves its keyframes only.
TEST(OnlineMapperLanes, ASecondRobotWaitsForItsPlacementAndKeepsItsOwnKeyframes)
{
  Drive run;
  const Pose2 placed(2.0, -1.0, 0.7);  // the second robot's map frame in the first's
  auto m = mapper();
  for (int i = 0; i < kScans; ++i)
  {
    m->addScan(run.scan(i));
    StampedScan second = run.scan(i, placed.inverse());
    second.lane = 1;
    EXPECT_EQ(m->addScan(second), ScanOutcome::kHeld);
  }
  const std::size_t first_keyframes = static_cast<std::size_t>(kScans / 4);
  EXPECT_EQ(m->merger().keyframeCount(), first_keyframes);
  EXPECT_FALSE(m->lanePlacement(1).has_value());
  std::vector<StampedPose> own_nodes;
  for (const auto& [stamp, pose] : run.nodes()) own_nodes.emplace_back(stamp, placed.inverse() * pose);
  EXPECT_FALSE(m->addTrajectory(own_nodes, 1)) << "a trajectory of a robot not placed waits";
  EXPECT_EQ(m->merger().keyframeCount(), first_keyframes);

  ASSERT_TRUE(m->placeLane(1, placed));
  EXPECT_EQ(m->merger().keyframeCount(), 2 * first_keyframes);
  EXPECT_EQ(m->counters().replayed, 0u);
  std::unordered_map<std::uint64_t, Pose2> second_robot;  // its keyframes: on the truth after its trajectory
  for (const KeyframeInfo& k : m->merger().keyframes())
    if (k.index >= first_keyframes)
    {
      const Pose2& t = run.truth[scanOf(run, k.stamp)];
      EXPECT_NEAR(std::hypot(k.pose.x - t.x, k.pose.y - t.y), 0.0, kPosTol);
      second_robot.emplace(k.index, k.pose);
    }
  EXPECT_EQ(second_robot.size(), first_keyframes);
  EXPECT_GT(keyframeError(run, *m).first, 1.0) << "the first robot's keyframes are still on its odometry";

  ASSERT_TRUE(m->addTrajectory(run.nodes(), 0));
  expectKeyframesOnTheTruth(run, *m);
  for (const KeyframeInfo& k : m->merger().keyframes())
    if (const auto it = second_robot.find(k.index); it != second_robot.end())
    {
      EXPECT_EQ(k.pose.x, it->second.x);
      EXPECT_EQ(k.pose.y, it->second.y);
    }

  // Placed again 0.1 m further along x: the second robot's keyframes move by that, the first's stay.
  const Pose2 nudge(0.1, 0.0, 0.0);
  ASSERT_TRUE(m->placeLane(1, nudge * placed));
  for (const KeyframeInfo& k : m->merger().keyframes())
  {
    const Pose2& t = run.truth[scanOf(run, k.stamp)];
    const double expected_dx = k.index >= first_keyframes ? 0.1 : 0.0;
    EXPECT_NEAR(k.pose.x - t.x, expected_dx, kPosTol);
  }
}
