// Scan simulator: ray casting against hand-computed ranges, noise statistics,
// determinism, odometry drift, the ground truth file and world file errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include "eval_test_helpers.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "line_map_eval/simulation/simulator.hpp"

namespace
{
using linemap::kPi;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;
using namespace line_map_eval;

const std::string kWorlds = std::string(LINEMAP_SOURCE_DIR) + "/config/worlds/";

/// The 4 x 4 m room [0, 4] x [0, 4], walls counter-clockwise from the origin.
std::vector<Segment2> squareRoom()
{
  return {
      {Vec2(0, 0), Vec2(4, 0)}, {Vec2(4, 0), Vec2(4, 4)}, {Vec2(4, 4), Vec2(0, 4)}, {Vec2(0, 4), Vec2(0, 0)}};
}

/// A temporary file removed at the end of the test.
struct TempFile
{
  std::string path;
  explicit TempFile(const std::string& name, const std::string& text = "")
  {
    path = ::testing::TempDir() + "/" + std::to_string(::getpid()) + "_" + name;
    std::ofstream(path) << text;
  }
  ~TempFile() { std::remove(path.c_str()); }
};

/// Whether the closed segments [p1, p2] and [q1, q2] properly cross (orientation test).
bool crosses(const Vec2& p1, const Vec2& p2, const Vec2& q1, const Vec2& q2)
{
  const auto orient = [](const Vec2& a, const Vec2& b, const Vec2& c)
  { return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()); };
  const double d1 = orient(q1, q2, p1), d2 = orient(q1, q2, p2);
  const double d3 = orient(p1, p2, q1), d4 = orient(p1, p2, q2);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0;
}

World office()
{
  return loadWorld(kWorlds + "office.yaml");
}
World squareRoomWorld()
{
  return loadWorld(kWorlds + "square_room.yaml");
}

TEST(RayCasting, SquareRoomHandComputedRanges)
{
  const auto walls = squareRoom();
  const Vec2 o(1.0, 0.5);
  // 0 deg: the wall x = 4 at (4, 0.5): 4 - 1 = 3.
  EXPECT_NEAR(castRay(walls, o, 0.0).range, 3.0, 1e-12);
  EXPECT_EQ(castRay(walls, o, 0.0).face, 1);
  // 90 deg: the wall y = 4 at (1, 4): 4 - 0.5 = 3.5.
  EXPECT_NEAR(castRay(walls, o, kPi / 2).range, 3.5, 1e-12);
  EXPECT_EQ(castRay(walls, o, kPi / 2).face, 2);
  // 180 deg: the wall x = 0 at (0, 0.5): 1.
  EXPECT_NEAR(castRay(walls, o, kPi).range, 1.0, 1e-12);
  EXPECT_EQ(castRay(walls, o, kPi).face, 3);
  // -90 deg: the wall y = 0 at (1, 0): 0.5.
  EXPECT_NEAR(castRay(walls, o, -kPi / 2).range, 0.5, 1e-12);
  EXPECT_EQ(castRay(walls, o, -kPi / 2).face, 0);
  // 45 deg: x = 4 is reached at t = 3 sqrt 2 (y = 3.5 < 4), before y = 4 at t = 3.5 sqrt 2.
  EXPECT_NEAR(castRay(walls, o, kPi / 4).range, 3.0 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(castRay(walls, o, kPi / 4).face, 1);
  // 135 deg: x = 0 at t = sqrt 2 (y = 1.5).
  EXPECT_NEAR(castRay(walls, o, 3 * kPi / 4).range, std::sqrt(2.0), 1e-12);
  // -45 deg: y = 0 at t = 0.5 sqrt 2 (x = 1.5).
  EXPECT_NEAR(castRay(walls, o, -kPi / 4).range, 0.5 * std::sqrt(2.0), 1e-12);
  // atan2(1, 2): y = 4 is 3.5 up, x = 4 is 3 across; x = 4 first at t = 3 / cos = 3 sqrt(5) / 2.
  EXPECT_NEAR(castRay(walls, o, std::atan2(1.0, 2.0)).range, 1.5 * std::sqrt(5.0), 1e-12);

  // From outside, looking away: no wall.
  const RayHit miss = castRay(walls, Vec2(5, 5), kPi / 4);
  EXPECT_TRUE(std::isinf(miss.range));
  EXPECT_EQ(miss.face, -1);
}

TEST(RayCasting, ScanAnglesFollowTheLaserHeading)
{
  // 5 beams over 180 deg with the laser facing +y: beams at 0, 45, 90, 135, 180 deg in the map.
  LaserModel laser;
  laser.beams = 5;
  laser.fov = kPi;
  const auto hits = castScan(squareRoom(), Pose2(1.0, 0.5, kPi / 2), laser);
  ASSERT_EQ(hits.size(), 5u);
  const double expected[5] = {3.0, 3.0 * std::sqrt(2.0), 3.5, std::sqrt(2.0), 1.0};
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(hits[i].range, expected[i], 1e-12) << "beam " << i;
}

TEST(RayCasting, NoReturnIsInfiniteAndBeyondRangeMax)
{
  LaserModel laser;
  laser.beams = 3;
  laser.range_max = 2.0;
  laser.sigma = 0.0;
  Random rng(1, 1);
  // From (1, 0.5) facing +x: beams at -90 (0.5 m), 0 (3 m > range_max) and +90 deg (3.5 m).
  const auto ranges = measureScan(castScan(squareRoom(), Pose2(1.0, 0.5, 0.0), laser), laser, rng);
  EXPECT_NEAR(ranges[0], 0.5, 1e-12);
  EXPECT_TRUE(std::isinf(ranges[1]) && ranges[1] > 0);
  EXPECT_TRUE(std::isinf(ranges[2]) && ranges[2] > 0);
}

TEST(Simulator, NoiselessEndpointsLieOnTheNearestWall)
{
  SimulationOptions opt;
  opt.sigma = 0.0;
  opt.spurious = 0.0;
  opt.scans = 40;
  const SimulationResult sim = simulate(office(), opt);
  const World& w = sim.world;
  ASSERT_EQ(sim.truth.scans.size(), 40u);
  Random unused(1, 1);
  std::size_t valid = 0;
  for (std::size_t k = 0; k < sim.truth.scans.size(); ++k)
  {
    const Pose2& pose = sim.truth.scans[k].pose;
    // The truth pose is the true base pose composed with the mounting.
    const Pose2 expected = sim.recording.keyframes[k].pose * w.laser.mounting;
    EXPECT_NEAR(pose.x, expected.x, 1e-12);
    EXPECT_NEAR(pose.y, expected.y, 1e-12);
    const std::vector<Segment2>& faces = sim.truth.walls;
    const std::vector<double> ranges = measureScan(castScan(faces, pose, w.laser), w.laser, unused);
    for (std::size_t i = 0; i < ranges.size(); ++i)
    {
      const float recorded = sim.recording.scans[k].ranges[i];
      if (!std::isfinite(ranges[i]))
      {
        EXPECT_TRUE(std::isinf(recorded));
        continue;
      }
      EXPECT_NEAR(recorded, ranges[i], 1e-6 * ranges[i]);  // float storage
      const double a = pose.theta + w.laser.angleMin() + i * w.laser.angleIncrement();
      const Vec2 end = pose.translation() + ranges[i] * Vec2(std::cos(a), std::sin(a));
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& s : faces)
        nearest = std::min(nearest, linemap::distanceToSegment(end, s.start, s.end));
      ASSERT_LT(nearest, 1e-9) << "scan " << k << " beam " << i;
      // Nothing in between: the beam stopped at the first face, and never inside a solid wall.
      const Vec2 before = pose.translation() + (ranges[i] - 1e-6) * Vec2(std::cos(a), std::sin(a));
      for (std::size_t j = 0; j < faces.size(); ++j)
        ASSERT_FALSE(crosses(pose.translation(), before, faces[j].start, faces[j].end))
            << "scan " << k << " beam " << i << " passes through face " << j;
      for (const Wall& wall : w.walls)
      {
        const Vec2 u = (wall.segment.end - wall.segment.start).normalized(), q = before - wall.segment.start;
        const double along = u.dot(q), across = u.x() * q.y() - u.y() * q.x();
        ASSERT_FALSE(along > 0.0 && along < wall.segment.length() &&
                     std::abs(across) < 0.5 * wall.thickness - 1e-9)
            << "scan " << k << " beam " << i << " ends inside a solid wall";
      }
      ++valid;
    }
  }
  EXPECT_GT(valid, 40u * 300u);  // indoors nearly every beam returns
}

TEST(Simulator, SameSeedSameScansOtherSeedOtherNoise)
{
  SimulationOptions opt;
  opt.scans = 20;
  opt.sigma = 0.03;
  opt.spurious = 0.2;
  opt.seed = 7;
  const World w = office();
  const SimulationResult a = simulate(w, opt), b = simulate(w, opt);
  opt.seed = 8;
  const SimulationResult c = simulate(w, opt);
  std::size_t differing = 0, total = 0;
  for (std::size_t k = 0; k < a.recording.scans.size(); ++k)
  {
    EXPECT_EQ(a.recording.scans[k].ranges, b.recording.scans[k].ranges);
    EXPECT_EQ(a.recording.scans[k].odom.x, b.recording.scans[k].odom.x);
    EXPECT_EQ(a.recording.scans[k].odom.theta, b.recording.scans[k].odom.theta);
    for (std::size_t i = 0; i < a.recording.scans[k].ranges.size(); ++i, ++total)
      differing += a.recording.scans[k].ranges[i] != c.recording.scans[k].ranges[i];
  }
  EXPECT_GT(differing, total * 9 / 10);
  // The true trajectory does not depend on the seed.
  EXPECT_EQ(a.recording.keyframes.back().pose.x, c.recording.keyframes.back().pose.x);
}

TEST(Simulator, RandomDrawsHaveTheRightMoments)
{
  Random rng(3, 1);
  const int n = 200000;
  double su = 0, sn = 0, sn2 = 0;
  for (int i = 0; i < n; ++i)
  {
    const double u = rng.uniform();
    ASSERT_TRUE(u >= 0.0 && u < 1.0);
    su += u;
    const double z = rng.normal();
    sn += z;
    sn2 += z * z;
  }
  EXPECT_NEAR(su / n, 0.5, 0.005);  // std of the mean: 0.29 / sqrt(n) = 0.0006
  EXPECT_NEAR(sn / n, 0.0, 0.01);
  EXPECT_NEAR(sn2 / n, 1.0, 0.02);
}

/// Per beam: measured minus true range, over a square room run.
std::vector<double> rangeErrors(double sigma, double spurious)
{
  SimulationOptions opt;
  opt.scans = 200;
  opt.sigma = sigma;
  opt.spurious = spurious;
  const SimulationResult sim = simulate(squareRoomWorld(), opt);
  std::vector<double> errors;
  for (std::size_t k = 0; k < sim.truth.scans.size(); ++k)
  {
    const auto hits = castScan(sim.truth.walls, sim.truth.scans[k].pose, sim.world.laser);
    for (std::size_t i = 0; i < hits.size(); ++i)
      errors.push_back(double(sim.recording.scans[k].ranges[i]) - hits[i].range);
  }
  return errors;
}

TEST(Simulator, SpuriousFractionAndNoiseStd)
{
  const double sigma = 0.03, spurious = 0.2;
  const std::vector<double> errors = rangeErrors(sigma, spurious);
  ASSERT_GT(errors.size(), 50000u);
  std::size_t outliers = 0;
  double sum2 = 0.0;
  std::size_t inliers = 0;
  for (const double e : errors)
  {
    if (!(std::abs(e) <= 6 * sigma))
      ++outliers;
    else
    {
      sum2 += e * e;
      ++inliers;
    }
  }
  // A spurious reading is uniform in [0, 30): it lands within 6 sigma of the truth with
  // probability 12 sigma / 30 = 1.2 %, so about 0.2 * 0.988 of the beams look spurious.
  EXPECT_NEAR(double(outliers) / errors.size(), spurious, 0.02);
  EXPECT_NEAR(std::sqrt(sum2 / inliers), sigma, 0.1 * sigma);

  // Without spurious readings no error exceeds 6 sigma (probability 2e-9 per beam).
  const std::vector<double> clean = rangeErrors(sigma, 0.0);
  double clean2 = 0.0;
  for (const double e : clean)
  {
    ASSERT_LE(std::abs(e), 6 * sigma);
    clean2 += e * e;
  }
  EXPECT_NEAR(std::sqrt(clean2 / clean.size()), sigma, 0.1 * sigma);
}

TEST(Simulator, OdometryDriftsUnlessDisabled)
{
  const World w = office();
  ASSERT_FALSE(w.odometry.isZero());
  SimulationOptions opt;
  opt.scans = 300;
  const SimulationResult drift = simulate(w, opt);
  const auto& rec = drift.recording;
  ASSERT_EQ(rec.keyframes.size(), rec.scans.size());
  // Odometry starts at the true pose and ends away from it.
  EXPECT_NEAR(rec.scans.front().odom.x, rec.keyframes.front().pose.x, 1e-12);
  const Pose2 end_err = rec.keyframes.back().pose.inverse() * rec.scans.back().odom;
  EXPECT_GT(std::hypot(end_err.x, end_err.y), 0.05);

  opt.drift = false;
  const SimulationResult exact = simulate(w, opt);
  for (std::size_t k = 0; k < exact.recording.scans.size(); ++k)
  {
    const Pose2& o = exact.recording.scans[k].odom;
    const Pose2& t = exact.recording.keyframes[k].pose;
    ASSERT_NEAR(o.x, t.x, 1e-9) << k;
    ASSERT_NEAR(o.y, t.y, 1e-9) << k;
    ASSERT_NEAR(linemap::normalizeAngle(o.theta - t.theta), 0.0, 1e-9) << k;
  }
}

TEST(Simulator, HeadingBiasAccumulatesPerMetre)
{
  // Bias only: the odometry heading error is bias * distance driven, turns add nothing.
  World w = squareRoomWorld();
  w.odometry = OdometryModel{};
  w.odometry.heading_bias = 0.01;
  SimulationOptions opt;
  opt.scans = 100;
  const SimulationResult sim = simulate(w, opt);
  double driven = 0.0;
  const auto& kf = sim.recording.keyframes;
  for (std::size_t k = 1; k < kf.size(); ++k)
    driven += std::hypot(kf[k].pose.x - kf[k - 1].pose.x, kf[k].pose.y - kf[k - 1].pose.y);
  ASSERT_GT(driven, 7.0);  // most of the 7.81 m lap
  const double err = linemap::normalizeAngle(sim.recording.scans.back().odom.theta - kf.back().pose.theta);
  EXPECT_NEAR(err, 0.01 * driven, 1e-9);
}

TEST(PathFollower, LapTimeAndPosesInClosedForm)
{
  const World w = squareRoomWorld();
  const PathFollower f(w.path);
  // A convex counter-clockwise loop turns 2 pi in total; legs 2 + 2 + 1.8 + |(-0.2, -2)|.
  const double length = 2 + 2 + 1.8 + std::hypot(0.2, 2.0);
  EXPECT_NEAR(pathLength(w.path), length, 1e-12);
  EXPECT_NEAR(f.lapTime(), length / w.path.speed + 2 * kPi / w.path.turn_rate, 1e-9);
  const Pose2 start = f.poseAt(0.0);
  EXPECT_NEAR(start.x, -1, 1e-12);
  EXPECT_NEAR(start.y, -1, 1e-12);
  EXPECT_NEAR(start.theta, 0, 1e-12);
  // Half way along the first leg (1 m at 0.4 m/s).
  EXPECT_NEAR(f.poseAt(2.5).x, 0.0, 1e-12);
  // At (1, -1), a quarter of the pi/2 turn done: pi/8 at 1 rad/s.
  const Pose2 turning = f.poseAt(5.0 + kPi / 8);
  EXPECT_NEAR(turning.x, 1, 1e-12);
  EXPECT_NEAR(turning.y, -1, 1e-12);
  EXPECT_NEAR(turning.theta, kPi / 8, 1e-12);
  // One lap later it is back at the start.
  EXPECT_NEAR(f.poseAt(f.lapTime()).x, -1, 1e-9);
  // Default scan count: one scan every scan_period over the lap.
  const SimulationResult sim = simulate(w);
  EXPECT_EQ(sim.recording.scans.size(), std::size_t(std::floor(f.lapTime() / w.path.scan_period)));
  EXPECT_NEAR(sim.recording.scans[1].stamp - sim.recording.scans[0].stamp, w.path.scan_period, 1e-12);
}

namespace
{
/// The face pieces one noiseless scan from `pose` sees.
std::vector<VisibleWall> castVisiblePieces(const std::vector<Segment2>& faces, const Pose2& pose,
                                           const LaserModel& laser, std::size_t min_beams)
{
  std::vector<int> wall;
  std::vector<double> range;
  for (const auto& h : castScan(faces, pose, laser))
  {
    wall.push_back(h.face);
    range.push_back(h.range);
  }
  return visibleWallPieces(faces, pose, laser.angleMin(), laser.angleIncrement(), wall, range, min_beams);
}
}  // namespace

TEST(GroundTruth, HandComputedVisiblePieces)
{
  // Laser at (1, 2) facing +x, 181 beams at 1 deg from -90 to 90 deg in the 4 x 4 room.
  // Wall x = 4 is hit for |a| <= atan(2/3) = 33.7 deg: beams -33..33 (67), y = 2 -+ 3 tan 33.
  // Wall y = 0 is hit for a in [-90, -34] (57 beams), x from 1 to 1 + 2 / tan 34; y = 4 likewise.
  LaserModel laser;
  laser.beams = 181;
  const Pose2 pose(1.0, 2.0, 0.0);
  const auto walls = squareRoom();
  const auto vis = castVisiblePieces(walls, pose, laser, 5);
  ASSERT_EQ(vis.size(), 3u);
  const double d33 = 3.0 * std::tan(33.0 * kPi / 180), x34 = 1.0 + 2.0 / std::tan(34.0 * kPi / 180);
  EXPECT_EQ(vis[0].wall, 0u);
  EXPECT_EQ(vis[0].beams, 57u);
  EXPECT_NEAR((vis[0].segment.start - Vec2(1, 0)).norm(), 0, 1e-9);
  EXPECT_NEAR((vis[0].segment.end - Vec2(x34, 0)).norm(), 0, 1e-9);
  EXPECT_EQ(vis[1].wall, 1u);
  EXPECT_EQ(vis[1].beams, 67u);
  EXPECT_NEAR((vis[1].segment.start - Vec2(4, 2 - d33)).norm(), 0, 1e-9);
  EXPECT_NEAR((vis[1].segment.end - Vec2(4, 2 + d33)).norm(), 0, 1e-9);
  EXPECT_EQ(vis[2].wall, 2u);  // directed like the wall: from x = 4 towards x = 0
  EXPECT_EQ(vis[2].beams, 57u);
  EXPECT_NEAR((vis[2].segment.start - Vec2(x34, 4)).norm(), 0, 1e-9);
  EXPECT_NEAR((vis[2].segment.end - Vec2(1, 4)).norm(), 0, 1e-9);

  // The threshold is inclusive: 57 keeps the three walls, 58 only the 67-beam one, 68 none.
  const auto count = [&](std::size_t min_beams)
  { return castVisiblePieces(walls, pose, laser, min_beams).size(); };
  EXPECT_EQ(count(57), 3u);
  EXPECT_EQ(count(58), 1u);
  EXPECT_EQ(count(68), 0u);
}

TEST(GroundTruth, AWallHiddenBehindAPillarIsSeenInRuns)
{
  // Laser at the origin facing +y, 181 beams at 1 deg. Wall y = 10 from x = -12 to 12; a thin
  // pillar y = 5 from x = -1 to 1 hides it for |x| <= 2 at y = 10 (beams within atan(1/5) = 11.3 deg
  // of the axis hit the pillar first: beams 79..101, 23 of them).
  LaserModel laser;
  laser.beams = 181;
  laser.range_max = 30.0;
  const Pose2 pose(0.0, 0.0, kPi / 2);
  const std::vector<Segment2> faces = {Segment2(Vec2(12, 10), Vec2(-12, 10)),
                                       Segment2(Vec2(1, 5), Vec2(-1, 5))};
  const auto vis = castVisiblePieces(faces, pose, laser, 5);
  ASSERT_EQ(vis.size(), 2u);
  EXPECT_EQ(vis[0].wall, 0u);
  EXPECT_EQ(vis[0].beams, 101u - 23u);  // the wall is hit within 50 deg of the axis: beams 40..140
  // The hull runs from x = 10 / tan(40 deg) to its mirror; the runs stop at the pillar's shadow, the
  // last beam beside it 12 deg off the axis: x = +-10 tan(12 deg).
  const double far = 10.0 / std::tan(40.0 * kPi / 180);
  EXPECT_NEAR(vis[0].segment.start.x(), far, 1e-9);
  EXPECT_NEAR(vis[0].segment.end.x(), -far, 1e-9);
  ASSERT_EQ(vis[0].runs.size(), 2u);
  const double edge = 10.0 * std::tan(12.0 * kPi / 180);
  EXPECT_NEAR(vis[0].runs[0].start.x(), far, 1e-9);
  EXPECT_NEAR(vis[0].runs[0].end.x(), edge, 1e-9);
  EXPECT_NEAR(vis[0].runs[1].start.x(), -edge, 1e-9);
  EXPECT_NEAR(vis[0].runs[1].end.x(), -far, 1e-9);
  EXPECT_EQ(vis[1].wall, 1u);
  EXPECT_TRUE(vis[1].runs.empty());  // one run: the hull

  // Only the runs are seen, not the shadow between them; the file keeps them.
  line_map_eval::GroundTruth truth;
  truth.walls = faces;
  truth.scans.resize(1);
  truth.scans[0].visible = vis;
  const SeenParts seen = line_map_eval::seenParts(truth, 0.6, 10);
  ASSERT_EQ(seen[0].size(), 2u);
  EXPECT_NEAR(seen[0][0].second - seen[0][0].first, far - edge, 1e-9);
  EXPECT_NEAR(seen[0][1].first - seen[0][0].second, 2.0 * edge, 1e-9);
  TempFile file("runs_truth.yaml");
  writeGroundTruth(truth, file.path);
  EXPECT_TRUE(readGroundTruth(file.path).scans[0].visible == vis);
}

TEST(GroundTruth, FileRoundTripAndPiecesOnTheirWalls)
{
  SimulationOptions opt;
  opt.scans = 30;
  const SimulationResult sim = simulate(office(), opt);
  const GroundTruth& t = sim.truth;
  std::size_t pieces = 0;
  for (const auto& s : t.scans)
    for (const auto& v : s.visible)
    {
      ASSERT_LT(v.wall, t.walls.size());
      const Segment2& w = t.walls[v.wall];
      EXPECT_LT(linemap::distanceToSegment(v.segment.start, w.start, w.end), 1e-9);
      EXPECT_LT(linemap::distanceToSegment(v.segment.end, w.start, w.end), 1e-9);
      EXPECT_GE(v.beams, t.min_beams);
      EXPECT_GE((v.segment.end - v.segment.start).dot(w.end - w.start), 0.0);  // same direction
      ++pieces;
    }
  EXPECT_GT(pieces, 30u * 3u);

  TempFile file("truth.yaml");
  writeGroundTruth(t, file.path);
  const GroundTruth r = readGroundTruth(file.path);
  EXPECT_EQ(r.world, "office");
  EXPECT_EQ(r.laser.beams, t.laser.beams);
  EXPECT_EQ(r.laser.angle_min, t.laser.angle_min);
  EXPECT_EQ(r.laser.angle_increment, t.laser.angle_increment);
  EXPECT_EQ(r.laser.range_min, t.laser.range_min);
  EXPECT_EQ(r.laser.range_max, t.laser.range_max);
  EXPECT_EQ(r.laser.sigma, t.laser.sigma);
  EXPECT_EQ(r.laser.spurious, t.laser.spurious);
  EXPECT_EQ(r.base_to_laser.x, t.base_to_laser.x);
  EXPECT_EQ(r.base_to_laser.theta, t.base_to_laser.theta);
  EXPECT_EQ(r.min_beams, t.min_beams);
  ASSERT_EQ(r.solids.size(), t.solids.size());
  for (std::size_t i = 0; i < t.solids.size(); ++i)
  {
    EXPECT_EQ(r.solids[i].segment.start, t.solids[i].segment.start);
    EXPECT_EQ(r.solids[i].segment.end, t.solids[i].segment.end);
    EXPECT_EQ(r.solids[i].thickness, t.solids[i].thickness);
  }
  ASSERT_EQ(r.walls.size(), t.walls.size());
  for (std::size_t i = 0; i < t.walls.size(); ++i)
  {
    EXPECT_EQ(r.walls[i].start, t.walls[i].start);
    EXPECT_EQ(r.walls[i].end, t.walls[i].end);
  }
  ASSERT_EQ(r.scans.size(), t.scans.size());
  for (std::size_t k = 0; k < t.scans.size(); ++k)
  {
    EXPECT_EQ(r.scans[k].stamp, t.scans[k].stamp);
    EXPECT_EQ(r.scans[k].pose.x, t.scans[k].pose.x);
    EXPECT_EQ(r.scans[k].pose.y, t.scans[k].pose.y);
    EXPECT_EQ(r.scans[k].pose.theta, t.scans[k].pose.theta);
    EXPECT_EQ(r.scans[k].visible, t.scans[k].visible);
  }
  EXPECT_EQ(truthPathForBag("/tmp/out.bag"), "/tmp/out.truth.yaml");
}

TEST(GroundTruth, ReaderNamesFileAndKey)
{
  const std::string laser =
      "laser: {beams: 3, angle_min: 0, angle_increment: 0.1, range_max: 30, sigma: 0, "
      "spurious: 0}\n";
  // A file of the thin-wall format is refused with what to do.
  TempFile old_format("old_truth.yaml", "format: linemap_truth/1\nworld: x\n" + laser +
                                            "base_to_laser: [0, 0, 0]\nwalls: []\nscans: []\n");
  try
  {
    readGroundTruth(old_format.path);
    FAIL() << "accepted linemap_truth/1";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("simulate the world again"), std::string::npos) << e.what();
  }
  TempFile thickness("bad_thickness.yaml",
                     "format: linemap_truth/2\nworld: x\n" + laser +
                         "base_to_laser: [0, 0, 0]\nsolids:\n  - {segment: [0, 0, 1, 0], "
                         "thickness: -1}\nwalls: []\nscans: []\n");
  try
  {
    readGroundTruth(thickness.path);
    FAIL() << "accepted a negative thickness";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("solids[0]/thickness"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("line 6"), std::string::npos) << e.what();
  }
  TempFile file("bad_truth.yaml", "format: linemap_truth/2\nworld: x\n" + laser +
                                      "base_to_laser: [0, 0]\nsolids: []\nwalls: []\nscans: []\n");
  try
  {
    readGroundTruth(file.path);
    FAIL() << "accepted a 2-number base_to_laser";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(file.path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("base_to_laser"), std::string::npos) << e.what();
  }
}

/// The message of the error loading `text` as a world file (empty when it loads).
std::string worldError(const std::string& text, const std::string& name = "bad_world.yaml")
{
  TempFile file(name, text);
  try
  {
    loadWorld(file.path);
  }
  catch (const std::runtime_error& e)
  {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file.path), std::string::npos) << "the file is not named: " << msg;
    return msg;
  }
  return "";
}

const char* kPath = "path:\n  waypoints: [[1, 1], [3, 1], [3, 3]]\n";

TEST(World, ErrorsNameFileKeyAndLine)
{
  using line_map_eval::test_helpers::expectMentions;
  expectMentions(worldError(std::string("name: x\n") + kPath), {"walls"});
  expectMentions(worldError(std::string("walls:\n  - [0, 0, 4, 0]\n  - [4, 0, 4]\n") + kPath),
                 {"walls[1]", "got 3", "line 3"});
  expectMentions(worldError(std::string("walls:\n  - [0, 0, 4, zero]\n") + kPath), {"walls[0][3]"});
  expectMentions(worldError(std::string("walls: [[0, 0, 4, 0]]\nlazer: {beams: 3}\n") + kPath), {"lazer"});
  expectMentions(worldError(std::string("walls: [[0, 0, 4, 0]]\nlaser: {spurious: 1.5}\n") + kPath),
                 {"laser/spurious"});
  // The leg from (3, 1) to (3, 3) crosses the wall y = 2.
  expectMentions(worldError(std::string("walls: [[0, 2, 4, 2]]\n") + kPath),
                 {"path/waypoints[1]", "walls[0]"});
  expectMentions(
      worldError(std::string("walls:\n  - [0, 0, 4, 0]\n  - {segment: [0, 0, 0, 4], thickness: -0.1}\n") +
                 kPath),
      {"walls[1]/thickness", "line 3"});
  expectMentions(worldError(std::string("walls:\n  - {segment: [0, 0, 4, 0], thicknes: 0.1}\n") + kPath),
                 {"walls[0]/thicknes"});
  expectMentions(worldError(std::string("wall_thickness: -1\nwalls: [[0, 0, 4, 0]]\n") + kPath),
                 {"wall_thickness"});
  // The path keeps its clearance from the wall's surface: 0.95 m from the centre line y = 0 of a
  // 1.6 m thick wall is 0.15 m from its face, below the default 0.2 m.
  expectMentions(worldError(std::string("wall_thickness: 1.6\nwalls: [[0, 0, 4, 0]]\npath:\n  "
                                        "waypoints: [[1, 0.95], [3, 0.95], [3, 3]]\n")),
                 {"surface of walls[0]"});

  expectMentions(worldError("walls: [[0, 0, 4, 0]\n"), {"line"});

  EXPECT_NE(worldError("").find("empty"), std::string::npos);
  EXPECT_EQ(worldError(std::string("walls: [[0, 0, 4, 0]]\n") + kPath), "");
  EXPECT_NE(worldError("walls: [[0, 0, 4, 0]]\n", "no_path.yaml").find("path"), std::string::npos);
}

TEST(World, ShippedWorldsLoad)
{
  const World o = office();
  EXPECT_EQ(o.name, "office");
  EXPECT_GE(o.walls.size(), 40u);
  EXPECT_LE(o.walls.size(), 80u);
  const World l = loadWorld(kWorlds + "loop.yaml");
  EXPECT_GT(pathLength(l.path), 150.0);
  EXPECT_NO_THROW(squareRoomWorld());
  // Walls are 10 cm solids unless the entry says otherwise; the furniture outlines are thin.
  EXPECT_EQ(o.wall_thickness, 0.10);
  EXPECT_EQ(o.walls.front().thickness, 0.10);
  EXPECT_EQ(o.walls.back().thickness, 0.0);
  const World plain = parseWorld(std::string("walls: [[0, 0, 4, 0]]\n") + kPath, "plain");
  EXPECT_EQ(plain.walls.front().thickness, kDefaultWallThickness);
}

TEST(World, LoopFailsToCloseOnOdometry)
{
  // Odometry of the big loop ends metres away from the truth: the case the loop closure fixes.
  SimulationOptions opt;
  opt.scans = 200;
  const SimulationResult sim = simulate(loadWorld(kWorlds + "loop.yaml"), opt);
  const Pose2 err = sim.recording.keyframes.back().pose.inverse() * sim.recording.scans.back().odom;
  EXPECT_GT(std::hypot(err.x, err.y), 1.0);
}

}  // namespace

// The registration error is a first-order process along the path: over 10 km of straight path in
// 0.1 m steps with a 5 m correlation length (2,000 independent stretches) its stds are the model's
// within 5 %, and errors 5 m apart correlate by exp(-1) = 0.37. A zero model leaves the poses exact.
TEST(Simulator, RegistrationErrorIsStationaryAndCorrelatedAlongThePath)
{
  std::vector<Pose2> truth;
  for (int k = 0; k < 100000; ++k) truth.emplace_back(0.1 * k, 0.0, 0.0);
  RegistrationModel model;
  model.position = 0.04;
  model.heading = 0.007;
  model.correlation_length = 5.0;
  Random rng(5, 3);
  const std::vector<Pose2> registered = registrationErrors(truth, model, rng);
  ASSERT_EQ(registered.size(), truth.size());
  double sxx = 0.0, syy = 0.0, shh = 0.0, lagged = 0.0;
  const std::size_t lag = 50;  // 5 m
  for (std::size_t k = 0; k < truth.size(); ++k)
  {
    const double ex = registered[k].x - truth[k].x, ey = registered[k].y, eh = registered[k].theta;
    sxx += ex * ex;
    syy += ey * ey;
    shh += eh * eh;
    if (k >= lag) lagged += ex * (registered[k - lag].x - truth[k - lag].x);
  }
  const double n = static_cast<double>(truth.size());
  EXPECT_NEAR(std::sqrt(sxx / n), 0.04, 0.002);
  EXPECT_NEAR(std::sqrt(syy / n), 0.04, 0.002);
  EXPECT_NEAR(std::sqrt(shh / n), 0.007, 0.00035);
  EXPECT_NEAR(lagged / (n - lag) / (sxx / n), std::exp(-1.0), 0.05);

  World world = loadWorld(std::string(LINEMAP_SOURCE_DIR) + "/config/worlds/square_room.yaml");
  const SimulationResult exact = simulate(world);
  for (std::size_t k = 0; k < exact.recording.keyframes.size(); ++k)
  {
    const Pose2 laser = exact.recording.keyframes[k].pose * world.laser.mounting;
    EXPECT_NEAR(laser.x, exact.truth.scans[k].pose.x, 1e-12);
    EXPECT_NEAR(laser.y, exact.truth.scans[k].pose.y, 1e-12);
  }
  SimulationOptions options;
  options.registration = model;
  const SimulationResult smeared = simulate(world, options);
  // The scans and the ground truth are those of the exact run; only the keyframes' poses err.
  ASSERT_EQ(smeared.recording.scans.size(), exact.recording.scans.size());
  EXPECT_EQ(smeared.recording.scans[7].ranges, exact.recording.scans[7].ranges);
  EXPECT_EQ(smeared.truth.scans[7].pose.x, exact.truth.scans[7].pose.x);
  EXPECT_NE(smeared.recording.keyframes[7].pose.x, exact.recording.keyframes[7].pose.x);
  EXPECT_DOUBLE_EQ(smeared.truth.registration_position, 0.04);
  EXPECT_DOUBLE_EQ(smeared.truth.registration_heading, 0.007);
}

TEST(World, RegistrationBlockAndOption)
{
  const World w =
      parseWorld(std::string("walls: [[0, 0, 4, 0]]\nregistration: {position: 0.03, heading_deg: 0.5, "
                             "correlation_length: 8}\n") +
                     kPath,
                 "test.yaml");
  EXPECT_DOUBLE_EQ(w.registration.position, 0.03);
  EXPECT_NEAR(w.registration.heading, 0.5 * kPi / 180.0, 1e-15);
  EXPECT_DOUBLE_EQ(w.registration.correlation_length, 8.0);
  using line_map_eval::test_helpers::expectMentions;
  expectMentions(worldError(std::string("walls: [[0, 0, 4, 0]]\nregistration: {position: -1}\n") + kPath),
                 {"registration/position"});
  expectMentions(worldError(std::string("walls: [[0, 0, 4, 0]]\nregistration: {heading: 1}\n") + kPath),
                 {"registration/heading"});

  const RegistrationModel m = parseRegistrationOption("--pose-noise", "0.04,0.4");
  EXPECT_DOUBLE_EQ(m.position, 0.04);
  EXPECT_NEAR(m.heading, 0.4 * kPi / 180.0, 1e-15);
  EXPECT_DOUBLE_EQ(m.correlation_length, 10.0);
  EXPECT_DOUBLE_EQ(parseRegistrationOption("--pose-noise", "0,0,3").correlation_length, 3.0);
  for (const char* bad : {"0.04", "a,0.4", "0.04,-1", "0.1,0.2,0", "1,2,3,4", "0.1x,2"})
  {
    try
    {
      parseRegistrationOption("--pose-noise", bad);
      ADD_FAILURE() << bad << " was accepted";
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_NE(std::string(e.what()).find("--pose-noise"), std::string::npos) << e.what();
    }
  }
}
