// The online evaluator: gating, re-registration on a trajectory, and scoring.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "line_map_eval/online/map_evaluator.hpp"

using line_map_eval::EvaluatorParams;
using line_map_eval::MapEvaluator;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
// The four walls of the square |x|, |y| <= 2.
const std::vector<Segment2> kWalls{{Vec2(-2, -2), Vec2(2, -2)},
                                   {Vec2(2, -2), Vec2(2, 2)},
                                   {Vec2(2, 2), Vec2(-2, 2)},
                                   {Vec2(-2, 2), Vec2(-2, -2)}};

// Wall points seen from `laser` (world), expressed in the laser frame: 1 cm spacing.
std::vector<Vec2> wallPointsInLaserFrame(const Pose2& laser)
{
  std::vector<Vec2> points;
  const Pose2 inv = laser.inverse();
  for (const Segment2& w : kWalls)
    for (double t = 0.0; t < 1.0; t += 0.0025) points.push_back(inv.apply(w.start + t * (w.end - w.start)));
  return points;
}

std::vector<Segment2> wallsInLaserFrame(const Pose2& laser)
{
  std::vector<Segment2> out;
  for (const Segment2& w : kWalls) out.push_back(w.transformed(laser.inverse()));
  return out;
}
}  // namespace

TEST(MapEvaluator, GateKeepsOnlyKeyframes)
{
  MapEvaluator eval(EvaluatorParams{});
  EXPECT_TRUE(eval.addScan(0.0, Pose2(0, 0, 0), wallPointsInLaserFrame(Pose2(0, 0, 0))));
  EXPECT_FALSE(eval.addScan(0.1, Pose2(0.05, 0, 0), {}));  // 5 cm < 0.2 m gate
  EXPECT_TRUE(eval.addScan(0.2, Pose2(0.25, 0, 0), {}));
  EXPECT_EQ(eval.scanCount(), 2u);
}

// A bag replayed with --loop sends the same scans (same stamps) again, from anywhere in the gate's
// eyes: they are not stored twice, so memory stays flat over replays.
TEST(MapEvaluator, ReplayedStampsAreStoredOnce)
{
  MapEvaluator eval(EvaluatorParams{});
  const std::vector<linemap::Segment2> segs{{linemap::Vec2(1, 0), linemap::Vec2(1, 1)}};
  EXPECT_TRUE(eval.addScan(5.0, Pose2(0, 0, 0), wallPointsInLaserFrame(Pose2(0, 0, 0))));
  EXPECT_TRUE(eval.addSegments(5.0, Pose2(0, 0, 0), segs));
  EXPECT_TRUE(eval.addScan(6.0, Pose2(3, 0, 0), {}));
  EXPECT_FALSE(eval.addScan(5.0, Pose2(10, 0, 0), {}));  // the gate alone would admit it
  EXPECT_FALSE(eval.addSegments(5.0, Pose2(10, 0, 0), segs));
  EXPECT_EQ(eval.scanCount(), 2u);
  EXPECT_EQ(eval.originalCount(), 1u);
  eval.reset();
  EXPECT_TRUE(eval.addScan(5.0, Pose2(0, 0, 0), {}));
}

// A replay does not start where the last pass did (the first scans wait for tf, the gate still
// holds the end of the last pass), and the tf filter lets some scans through late: a scan older
// than the newest stored one is stored only where the stored scans leave a gap, so a replay keeps
// the stored chain instead of starting one of its own beside it.
TEST(MapEvaluator, ReplayAddsNoScansBesideTheStoredOnes)
{
  MapEvaluator eval(EvaluatorParams{});  // gate 0.2 m; a scan every 0.12 m: every other one is stored
  auto pass = [&](int first, int dropped)
  {
    std::size_t stored = 0;
    for (int i = first; i <= 20; ++i)
      if (i != dropped && eval.addScan(i, Pose2(0.12 * i, 0, 0), {})) ++stored;
    return stored;
  };
  EXPECT_EQ(pass(0, 8), 10u);  // 0, 2, 4, 6, then 9 (8 dropped), 11, ..., 19
  // The replay starts at scan 1, 2.16 m from the gate's last pose (scan 19), which the live gate
  // would store, as scan 8 (0.24 m after scan 6): both lie within 0.2 m of a stored scan.
  EXPECT_EQ(pass(1, -1), 0u);
  EXPECT_EQ(pass(0, -1), 0u);
  EXPECT_EQ(eval.scanCount(), 10u);
  // Past the stored span the live gate decides; a late scan gets in where the stored ones leave a gap.
  EXPECT_TRUE(eval.addScan(30, Pose2(4, 0, 0), {}));
  EXPECT_TRUE(eval.addScan(40, Pose2(5, 0, 0), {}));
  EXPECT_TRUE(eval.addScan(35, Pose2(4.5, 0, 0), {}));
  EXPECT_FALSE(eval.addScan(36, Pose2(4.6, 0, 0), {}));
  EXPECT_FALSE(eval.addScan(41, Pose2(5.1, 0, 0), {}));  // the live gate is still at scan 40
  EXPECT_EQ(eval.scanCount(), 13u);
}

TEST(MapEvaluator, TrajectoryReRegistersScansAndSegments)
{
  // Two keyframes whose recorded poses drifted by 0.3 m / 3 degrees from the truth.
  const Pose2 true0(0.0, 0.0, 0.0), true1(0.5, 0.2, 0.3);
  const Pose2 drift(0.3, -0.2, 3.0 * linemap::kPi / 180.0);
  MapEvaluator eval(EvaluatorParams{});
  for (const auto& [stamp, truth] : {std::pair<double, Pose2>{1.0, true0}, {2.0, true1}})
  {
    const Pose2 recorded = drift * truth;
    ASSERT_TRUE(eval.addScan(stamp, recorded, wallPointsInLaserFrame(truth)));
    ASSERT_TRUE(eval.addSegments(stamp, recorded, wallsInLaserFrame(truth)));
  }
  const double drifted_quality = eval.evaluate(kWalls).quality.quality;

  // One pose per keyframe plus one that matches none.
  EXPECT_EQ(eval.applyTrajectory({{1.0, true0}, {2.0, true1}, {7.0, Pose2()}}), 1u);
  const auto m = eval.evaluate(kWalls);
  // Registered on the truth, every point lies on a map cell: q is 100 % and the originals lie on the walls.
  EXPECT_NEAR(m.quality.quality, 100.0, 1e-9);
  EXPECT_LT(drifted_quality, 50.0);
  EXPECT_NEAR(m.error.mean_error, 0.0, 1e-9);
  EXPECT_EQ(m.error.assigned, 8u);
  EXPECT_EQ(m.statistics.segment_count, 4u);
  EXPECT_NEAR(m.statistics.mean_length, 4.0, 1e-12);
}

namespace
{
/// The keyframe gate on tf stores every frame; trajectories only re-register (the tests of the
/// correction of frames that are no nodes).
EvaluatorParams tfParams()
{
  EvaluatorParams p;
  p.keyframe_source = line_map_merging::KeyframeSource::kTf;
  return p;
}
}  // namespace

TEST(MapEvaluator, UnmatchedKeyframeTakesInterpolatedCorrection)
{
  MapEvaluator eval(tfParams());
  const Pose2 offset(1.0, 0.0, 0.0);  // the whole trajectory moves by 1 m in x
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(eval.addSegments(i, Pose2(i, 0, 0), {Segment2(Vec2(0, 1), Vec2(0.5, 1))}));
  eval.applyTrajectory({{0.0, offset * Pose2(0, 0, 0)}, {2.0, offset * Pose2(2, 0, 0)}});
  // The middle keyframe (stamp 1) had no pose: it gets the same 1 m correction, so its
  // original lands on the map segment from x = 2 to 2.5.
  const auto m = eval.evaluate({Segment2(Vec2(1, 1), Vec2(3.5, 1))});
  EXPECT_NEAR(m.error.mean_error, 0.0, 1e-9);
  EXPECT_EQ(m.error.assigned, 3u);
}

// A back end's node is often a scan the evaluator did not store (Intel's converted stamps lie 1 ms
// apart in bursts): its pose still corrects the stored scans, through the odometry from it to them,
// and is never taken as a stored scan's own pose.
TEST(MapEvaluator, PoseOfAnUnstoredScanMovesItsStoredNeighbourByRelativeOdometry)
{
  MapEvaluator eval(tfParams());
  const std::vector<Segment2> seen{Segment2(Vec2(0, 1), Vec2(0.5, 1))};
  for (const auto& [stamp, pose, stored] : {std::tuple{1.000, Pose2(0, 0, 0), true},
                                            std::tuple{1.002, Pose2(0.05, 0, 0), false},  // inside the gate
                                            std::tuple{2.000, Pose2(1, 0, 0), true}})
  {
    ASSERT_EQ(eval.addScan(stamp, pose, {}), stored);
    ASSERT_EQ(eval.addSegments(stamp, pose, seen), stored);
  }
  // The unstored scan is 3 m further along than odometry said: the stored scan 0.05 m before it
  // goes to x = 3.0 (not 3.05, its neighbour's own pose); the one at t = 2 stays at x = 1.
  EXPECT_EQ(eval.applyTrajectory({{1.002, Pose2(3.05, 0, 0)}, {2.0, Pose2(1, 0, 0)}}), 0u);
  const auto m = eval.evaluate({Segment2(Vec2(3, 1), Vec2(3.5, 1)), Segment2(Vec2(1, 1), Vec2(1.5, 1))});
  EXPECT_NEAR(m.error.mean_error, 0.0, 1e-9);
  EXPECT_EQ(m.error.assigned, 2u);
  EXPECT_EQ(eval.applyTrajectory({{5.0, Pose2(3.05, 0, 0)}}), 1u);  // no scan was seen then
}

TEST(MapEvaluator, OdometryPosesKeepCorrectionsApartAcrossAMapToOdomJump)
{
  // Odometry drifted from the truth by `d`. The first two keyframes were registered on raw
  // odometry (map->odom = identity); then the back end's map->odom jumped to `d`, so the later ones
  // were registered on the truth. The trajectory holds keyframes 0 and 2 only: keyframe 1 must get
  // keyframe 0's correction, not a blend with keyframe 2's identity.
  const Pose2 d(0.3, -0.2, 3.0 * linemap::kPi / 180.0);
  const std::vector<Pose2> truth{Pose2(-1.0, 0.0, 0.0), Pose2(-0.5, 0.3, 0.4), Pose2(0.0, 0.0, 0.8),
                                 Pose2(0.5, -0.3, 1.2)};
  for (const bool with_odometry : {true, false})
  {
    EvaluatorParams params = tfParams();
    // Without odometry the map-frame corrections of keyframes 0 and 2 are interpolated (nearest
    // would take keyframe 0's by the tie-break alone).
    if (!with_odometry) params.correction = line_map_merging::CorrectionMode::kInterpolate;
    MapEvaluator eval(params);
    for (int i = 0; i < 4; ++i)
    {
      const Pose2 odom = d.inverse() * truth[i];
      const Pose2 registered = i < 2 ? odom : truth[i];
      const std::optional<Pose2> odom_pose = with_odometry ? std::optional<Pose2>(odom) : std::nullopt;
      ASSERT_TRUE(eval.addScan(i, registered, wallPointsInLaserFrame(truth[i]), odom_pose));
      ASSERT_TRUE(eval.addSegments(i, registered, wallsInLaserFrame(truth[i]), odom_pose));
    }
    EXPECT_EQ(eval.applyTrajectory({{0.0, truth[0]}, {2.0, truth[2]}}), 0u);
    const auto m = eval.evaluate(kWalls);
    if (with_odometry)
    {
      EXPECT_NEAR(m.quality.quality, 100.0, 1e-9);
      EXPECT_NEAR(m.error.mean_error, 0.0, 1e-9);
      EXPECT_EQ(m.error.assigned, 16u);
    }
    else  // the map-frame interpolation misplaces keyframe 1: its four originals leave their walls
      EXPECT_EQ(m.error.assigned, 12u);
  }
}

// Coverage and redundancy through evaluate(): the square's walls scanned (1 cm apart, 400 points
// per wall) and extracted exactly. Mapping all four walls covers everything; leaving the west wall
// out loses its 400 points except the 11 within one sigma (5 cm) of the neighbouring walls' ends
// (t <= 0.0125 and t >= 0.9875 of the 4 m wall), and exactly a quarter of the originals' length.
TEST(MapEvaluator, CoverageDropsWhenAWallIsLeftOut)
{
  MapEvaluator eval(EvaluatorParams{});
  const std::vector<Vec2> points = wallPointsInLaserFrame(Pose2(0, 0, 0));
  const double per_wall = points.size() / 4.0;  // 400, or 401 if the sampling's t reaches 1 - 1e-16
  ASSERT_TRUE(eval.addScan(1.0, Pose2(0, 0, 0), points));
  ASSERT_TRUE(eval.addSegments(1.0, Pose2(0, 0, 0), wallsInLaserFrame(Pose2(0, 0, 0))));
  const auto all = eval.evaluate(kWalls);
  EXPECT_EQ(all.point_coverage.points, points.size());
  EXPECT_EQ(all.point_coverage.covered, points.size());
  EXPECT_NEAR(all.length_coverage.fraction(), 1.0, 1e-12);
  EXPECT_EQ(all.redundancy.pairs, 0u);
  EXPECT_EQ(all.error.unassigned, 0u);

  const std::vector<Segment2> three(kWalls.begin(), kWalls.begin() + 3);
  const auto m = eval.evaluate(three);
  EXPECT_NEAR(static_cast<double>(m.point_coverage.covered), 3.0 * per_wall + 11.0, 1.5);
  EXPECT_NEAR(m.length_coverage.fraction(), 0.75, 1e-12);
  EXPECT_EQ(m.error.unassigned, 1u);  // the west wall's original has no map segment

  // Straight structure, classified once with the table: the four walls, bar at most the 19 points
  // within 0.1 m of each corner (structure_coverage.hpp). All covered by the four walls; without
  // the west wall, its points but the 11 near the ends are uncovered: 3.9 m unmapped, less what the
  // smeared scale's band of a neighbouring wall (up to its half-width, 0.25 m, from each corner)
  // covers through its feet on that wall's line.
  const auto& structure = eval.structure();
  EXPECT_EQ(structure.points, points.size());
  EXPECT_GE(structure.indices.size(), points.size() - 4 * 19);
  EXPECT_EQ(all.structure_coverage.points, structure.indices.size());
  EXPECT_EQ(all.structure_coverage.covered, all.structure_coverage.points);
  EXPECT_EQ(all.structure_coverage.unmapped_length, 0.0);
  EXPECT_NEAR(all.structure_coverage.length, 16.0, 0.45);  // to a 0.1 m column per wall
  EXPECT_NEAR(static_cast<double>(m.structure_coverage.uncovered.size()), per_wall - 11.0, 20.0);
  EXPECT_GE(m.structure_coverage.unmapped_length, 3.9 - 2 * 0.25 - 0.15);
  EXPECT_LE(m.structure_coverage.unmapped_length, 3.9 + 0.15);
  // Corners are no crossings; a segment through the north wall, 0.5 m past it either way, is one.
  EXPECT_TRUE(all.crossing_pairs.empty());
  std::vector<Segment2> crossed = kWalls;
  crossed.emplace_back(Vec2(0, 1.5), Vec2(0, 2.5));
  const auto x = eval.evaluate(crossed);
  ASSERT_EQ(x.crossing_pairs.size(), 1u);
  EXPECT_NEAR((x.crossing_pairs[0].point - Vec2(0, 2)).norm(), 0.0, 1e-9);

  // The north wall drawn twice, the copy 3 cm inside: one redundant pair overlapping 4 m.
  std::vector<Segment2> twice = kWalls;
  twice.emplace_back(Vec2(2, 1.97), Vec2(-2, 1.97));
  const auto r = eval.evaluate(twice);
  EXPECT_EQ(r.redundancy.pairs, 1u);
  EXPECT_NEAR(r.redundancy.overlap_length, 4.0, 1e-12);
}

// Once a trajectory came, the scans stored are the back end's nodes (gated on their poses), each at
// its node's pose, as the merger's keyframes; a node whose scan comes later waits for it.
TEST(MapEvaluator, AfterATrajectoryTheNodesChooseTheStoredScans)
{
  EvaluatorParams params;  // keyframe_source auto, gate 0.2 m
  MapEvaluator eval(params);
  // A scan every 0.105 m along x; odometry reads 14 % long.
  auto odom = [](int i) { return Pose2(0.12 * i, 0, 0); };
  auto truth = [](int i) { return Pose2(0.105 * i, 0, 0); };
  for (int i = 0; i < 10; ++i) eval.addScan(i, odom(i), wallPointsInLaserFrame(truth(i)), odom(i));
  EXPECT_EQ(eval.scanCount(), 5u);  // 0, 2, 4, 6, 8 on tf
  // Nodes at every scan up to 9 and, not yet seen, 10..13.
  std::vector<std::pair<double, Pose2>> nodes;
  for (int i = 0; i < 14; ++i) nodes.emplace_back(i, truth(i));
  EXPECT_EQ(eval.applyTrajectory(nodes), 4u);  // 10..13 unseen yet
  // Node 9 is 0.105 m past node 8: below the gate. Scans 10..13 arrive: 10 and 12 are stored at once,
  // at their nodes' poses (odometry would put them 0.15-0.2 m off).
  for (int i = 10; i < 14; ++i)
    EXPECT_EQ(eval.addScan(i, odom(i), wallPointsInLaserFrame(truth(i)), odom(i)), i % 2 == 0) << i;
  EXPECT_EQ(eval.scanCount(), 7u);
  // The walls of the truth are where the stored scans say.
  const auto m = eval.evaluate(kWalls);
  EXPECT_GT(m.quality.quality, 99.0);
}
