// Localization in a line map (line_map_localizer.hpp, localization_segment_matcher.hpp,
// localization_global_search.hpp) on synthetic maps whose scans are ray-cast here.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/mergers/merger.hpp"

using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;
using namespace line_map_merging;

namespace
{
constexpr double kDeg = linemap::kPi / 180.0;

// An L-shaped room, counter-clockwise (free side, the inside, on the left): asymmetric, so one scan
// fixes the pose.
std::vector<Segment2> lRoom()
{
  const std::vector<Vec2> c{{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 8}, {0, 8}};
  std::vector<Segment2> s;
  for (std::size_t i = 0; i < c.size(); ++i) s.push_back({c[i], c[(i + 1) % c.size()]});
  return s;
}

// Range along the ray from `origin` at `angle` to the nearest segment, or `max_range`.
double castRay(const std::vector<Segment2>& world, const Vec2& origin, double angle, double max_range)
{
  const Vec2 d(std::cos(angle), std::sin(angle));
  double best = max_range;
  for (const auto& s : world)
  {
    const Vec2 e = s.end - s.start;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::fabs(den) < 1e-12) continue;
    const Vec2 w = s.start - origin;
    const double t = (w.x() * e.y() - w.y() * e.x()) / den;
    const double u = (w.x() * d.y() - w.y() * d.x()) / den;
    if (t > 1e-9 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return best;
}

// Points (base frame, sensor at the base) of a scan of `beams` beams over 360 degrees from `pose`,
// with Gaussian range noise; beams without a return are left out.
std::vector<Vec2> scanFrom(const std::vector<Segment2>& world, const Pose2& pose, int beams = 360,
                           double noise = 0.0, unsigned seed = 1, double max_range = 20.0)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise > 0.0 ? noise : 1.0);
  std::vector<Vec2> points;
  for (int b = 0; b < beams; ++b)
  {
    const double a = -linemap::kPi + 2.0 * linemap::kPi * b / beams;
    double r = castRay(world, pose.translation(), pose.theta + a, max_range);
    if (r >= max_range) continue;
    if (noise > 0.0) r += n(rng);
    points.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return points;
}

LocalizationSegmentIndex indexOf(const std::vector<Segment2>& map)
{
  return LocalizationSegmentIndex(map, 0.5, SegmentMatchParams().max_distance);
}
}  // namespace

TEST(LocalizationSegmentIndex, NearestSegmentAndFreeSide)
{
  const auto index = indexOf(lRoom());
  // 0.1 m inside the bottom wall: its nearest point is straight below.
  const auto n = index.nearest({5.0, 0.1});
  ASSERT_TRUE(n);
  EXPECT_EQ(n->segment, 0u);
  EXPECT_NEAR(n->distance, 0.1, 1e-12);
  EXPECT_NEAR(n->closest.x(), 5.0, 1e-12);
  // Beyond the corner (10, 0): the distance to the end point, not to the line.
  const auto corner = index.nearest({10.1, -0.1});
  ASSERT_TRUE(corner);
  EXPECT_NEAR(corner->distance, std::hypot(0.1, 0.1), 1e-12);
  // Nothing within reach (0.3 m) in the middle of the room.
  EXPECT_FALSE(index.nearest({2.0, 2.0}));
  // Seen from outside the room (below the bottom wall) the wall shows its back: skipped.
  const Vec2 outside(5.0, -2.0);
  EXPECT_FALSE(index.nearest({5.0, -0.1}, &outside));
  const Vec2 inside(5.0, 2.0);
  EXPECT_TRUE(index.nearest({5.0, -0.1}, &inside));
}

// The reference: every segment measured, the nearest within reach kept (by squared distance), and among
// equally near ones the last.
std::optional<LocalizationSegmentIndex::Nearest> nearestByBruteForce(const std::vector<Segment2>& segments,
                                                                     const Vec2& p, double reach,
                                                                     const Vec2* sensor)
{
  std::optional<LocalizationSegmentIndex::Nearest> best;
  double best_d2 = reach * reach;
  for (std::size_t i = 0; i < segments.size(); ++i)
  {
    const auto& s = segments[i];
    if (sensor && linemap::cross(s.end - s.start, *sensor - s.start) < 0.0) continue;
    const Vec2 d = s.end - s.start;
    const double t = std::clamp((p - s.start).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const Vec2 c = s.start + t * d;
    const double d2 = (p - c).squaredNorm();
    if (d2 <= best_d2)
    {
      best_d2 = d2;
      best = LocalizationSegmentIndex::Nearest{i, c, std::sqrt(d2)};
    }
  }
  return best;
}

TEST(LocalizationSegmentIndex, RingSearchFindsWhatMeasuringEverySegmentFinds)
{
  // Many short overlapping pieces of a few walls, as the keyframe scans of a saved session give, plus exact
  // duplicates (equally near: the later one must win) and scattered clutter, the nearest of which
  // lies anywhere up to reach and beyond.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> along(0.0, 1.0), jitter(-0.02, 0.02), anywhere(-1.0, 9.0);
  std::vector<Segment2> segments;
  const std::vector<Segment2> walls{{{0, 0}, {8, 0}}, {{8, 0}, {8, 6}}, {{8, 6}, {0, 6}}, {{3, 1}, {3, 5}}};
  for (int view = 0; view < 12; ++view)
    for (const auto& w : walls)
    {
      const Vec2 direction = (w.end - w.start).normalized();
      for (double a = along(rng) * 0.05; a < w.length(); a += 0.06)
      {
        const Vec2 a0 = w.start + a * direction, a1 = w.start + std::min(w.length(), a + 0.05) * direction;
        segments.push_back({a0 + Vec2(jitter(rng), jitter(rng)), a1 + Vec2(jitter(rng), jitter(rng))});
      }
    }
  const std::size_t pieces = segments.size();
  for (std::size_t i = 0; i < 40; ++i)
  {
    const Segment2 copy = segments[i * 37 % pieces];
    segments.push_back(copy);
  }
  for (int i = 0; i < 400; ++i)
  {
    const Vec2 a(anywhere(rng), anywhere(rng));
    segments.push_back({a, a + Vec2(jitter(rng) * 10.0, jitter(rng) * 10.0)});
  }
  const double reach = 0.3;
  const Vec2 sensor(4.0, 3.0);
  std::uniform_real_distribution<double> query(-1.5, 9.5);
  for (const double cell : {0.05, 0.1, 0.5, 2.0})
  {
    const LocalizationSegmentIndex index(segments, cell, reach);
    int found = 0;
    for (int q = 0; q < 4000; ++q)
    {
      // Half the queries near a wall (within reach or just beyond), half anywhere, some outside the map.
      const auto& w = walls[static_cast<std::size_t>(q) % walls.size()];
      const Vec2 normal = Vec2(-(w.end - w.start).y(), (w.end - w.start).x()).normalized();
      const Vec2 p = q % 2 == 0 ? Vec2(w.start + along(rng) * (w.end - w.start) + normal * (along(rng) - 0.5))
                                : Vec2(query(rng), query(rng));
      for (const Vec2* from : {static_cast<const Vec2*>(nullptr), &sensor})
      {
        const auto got = index.nearest(p, from);
        const auto expected = nearestByBruteForce(segments, p, reach, from);
        ASSERT_EQ(got.has_value(), expected.has_value()) << "cell " << cell << " at " << p.transpose();
        if (!got) continue;
        ++found;
        EXPECT_EQ(got->segment, expected->segment) << "cell " << cell << " at " << p.transpose();
        EXPECT_NEAR(got->distance, expected->distance, 1e-12);
        EXPECT_NEAR((got->closest - expected->closest).norm(), 0.0, 1e-12);
      }
    }
    // Both kinds of answer were asked for.
    EXPECT_GT(found, 2000);
    EXPECT_LT(found, 7000);
  }
}

TEST(LocalizationSegmentMatcher, LocalizesFromAPerturbedGuess)
{
  const auto map = lRoom();
  const auto index = indexOf(map);
  const Pose2 truth(2.0, 2.5, 0.3);
  const auto points = scanFrom(map, truth, 360, 0.01, 7);
  const Pose2 guess(2.15, 2.38, 0.3 + 4 * kDeg);
  const SegmentMatch m = matchToSegments(index, points, guess, std::nullopt, SegmentMatchParams());
  ASSERT_TRUE(m.valid);
  EXPECT_LT(std::hypot(m.pose.x - truth.x, m.pose.y - truth.y), 0.01);
  EXPECT_LT(std::fabs(m.pose.theta - truth.theta), 0.2 * kDeg);
  EXPECT_GT(m.inlier_share, 0.99);
  // Noise 1 cm against point_sigma 3 cm: the score is near exp(-1/18).
  EXPECT_NEAR(m.score, std::exp(-0.5 * (0.01 * 0.01) / (0.03 * 0.03)), 0.02);
  // The guess itself scores worse.
  EXPECT_LT(evaluateOnSegments(index, points, guess, SegmentMatchParams()).score, m.score - 0.2);
}

TEST(LocalizationSegmentMatcher, ClutterNotInTheMapDoesNotPull)
{
  const auto map = lRoom();
  auto world = map;
  // Absent from the map: a cabinet 0.6 m in front of the robot, a person beside it, and a shelf 0.15 m
  // in front of the left wall, hiding 2 m of it (its points lie within the pairing distance of the
  // wall: a least-squares fit would shift the pose towards it by their share of the x constraint).
  world.push_back({{3.0, 2.0}, {3.0, 3.4}});
  world.push_back({{3.0, 3.4}, {2.6, 3.4}});
  world.push_back({{1.5, 3.2}, {1.2, 3.2}});
  world.push_back({{0.15, 0.5}, {0.15, 2.5}});
  const Pose2 truth(2.4, 2.5, 0.0);
  const auto points = scanFrom(world, truth, 360, 0.005, 3);
  const auto index = indexOf(map);
  const Pose2 guess(2.5, 2.4, 2 * kDeg);
  const SegmentMatch m = matchToSegments(index, points, guess, std::nullopt, SegmentMatchParams());
  EXPECT_LT(std::hypot(m.pose.x - truth.x, m.pose.y - truth.y), 0.01);
  EXPECT_LT(std::fabs(m.pose.theta - truth.theta), 0.2 * kDeg);
  // The clutter hides a fifth of the beams or more: the inlier share says so.
  EXPECT_LT(m.inlier_share, 0.8);
  EXPECT_GT(m.inlier_share, 0.5);
  // Without the robust loss (a scale far beyond every residual) and the narrower second gate the
  // shelf pulls the pose off.
  SegmentMatchParams plain;
  plain.loss_scale = 1e3;
  plain.refine_distance = plain.max_distance;
  const SegmentMatch p = matchToSegments(index, points, guess, std::nullopt, plain);
  EXPECT_GT(std::hypot(p.pose.x - truth.x, p.pose.y - truth.y), 0.02);
}

TEST(LocalizationSegmentMatcher, CorridorIsDegenerateAlongItsAxisAndThePriorHoldsIt)
{
  // Two parallel walls 2 m apart, 100 m long, free sides facing each other.
  const std::vector<Segment2> corridor{{{-50, -1}, {50, -1}}, {{50, 1}, {-50, 1}}};
  const auto index = indexOf(corridor);
  const auto points = scanFrom(corridor, {0.0, 0.0, 0.0});
  PosePrior prior;
  prior.mean = {0.3, 0.0, 0.0};  // odometry: 0.3 m further along than the truth
  prior.information.diagonal() << 1.0 / (0.1 * 0.1), 1.0 / (0.1 * 0.1), 1.0 / (0.05 * 0.05);
  // The search starts at x = 0.8, neither the truth nor the prior: a solve that ignores the prior has
  // nothing to move x and ends where it started, 0.5 m from where the prior holds it.
  const SegmentMatch m = matchToSegments(index, points, {0.8, 0.12, 0.03}, prior, SegmentMatchParams());
  // Across the corridor and in heading the walls decide; along it nothing but the prior.
  EXPECT_NEAR(m.pose.y, 0.0, 1e-3);
  EXPECT_NEAR(m.pose.theta, 0.0, 0.05 * kDeg);
  EXPECT_NEAR(m.pose.x, 0.3, 1e-6);
  EXPECT_NEAR(m.scan_information(0, 0), 0.0, 1e-9);
  // The scan's information across: sum of 1/sigma^2 over the points (all on the walls, inliers).
  EXPECT_NEAR(m.scan_information(1, 1), static_cast<double>(points.size()) / (0.03 * 0.03),
              1e-3 * m.scan_information(1, 1));
  // Covariance along the axis is the prior's variance, across it the scan's far smaller one.
  EXPECT_NEAR(m.covariance(0, 0), 0.1 * 0.1, 1e-6);
  EXPECT_LT(m.covariance(1, 1), 1e-5);
}

TEST(LocalizationGlobalSearch, FindsThePoseInAnAsymmetricRoom)
{
  const auto map = lRoom();
  LocalizationGlobalSearch search(map, GlobalSearchParams());
  for (const Pose2& truth : {Pose2(2.0, 6.0, 1.0), Pose2(8.0, 2.0, -2.5), Pose2(1.5, 1.0, 3.0)})
  {
    const auto found = search.search(scanFrom(map, truth, 360, 0.01, 5));
    ASSERT_FALSE(found.empty());
    const Pose2& p = found.front().pose;
    EXPECT_LT(std::hypot(p.x - truth.x, p.y - truth.y), 0.1) << truth.x << " " << truth.y;
    EXPECT_LT(std::fabs(linemap::normalizeAngle(p.theta - truth.theta)), 2 * kDeg);
  }
  EXPECT_TRUE(search.search({}).empty());
}

namespace
{
// Drives along x from (1.5, 2) in 0.1 m steps; odometry starts at the identity.
struct Drive
{
  std::vector<Segment2> world;
  Pose2 start{1.5, 2.0, 0.0};
  Pose2 truth(int i) const { return {start.x + 0.1 * i, start.y, start.theta}; }
  LocalizerScan scan(int i) const
  {
    LocalizerScan s;
    s.stamp = 0.1 * (i + 1);
    s.points = scanFrom(world, truth(i), 360, 0.01, static_cast<unsigned>(i + 11));
    s.odom = start.inverse() * truth(i);
    return s;
  }
  /// Distance of `pose` from the truth of scan i.
  double miss(const Pose2& pose, int i) const { return std::hypot(pose.x - truth(i).x, pose.y - truth(i).y); }
  /// The result of the last of scans 0 .. count - 1 fed to `localizer`.
  LocalizerResult feed(LineMapLocalizer& localizer, int count) const
  {
    LocalizerResult last;
    for (int i = 0; i < count; ++i) last = localizer.addScan(scan(i));
    return last;
  }
};
}  // namespace

TEST(LineMapLocalizer, TracksFromTheInitialPose)
{
  const Drive drive{lRoom()};
  LineMapLocalizer localizer(lRoom());
  localizer.setPose({1.55, 2.05, 2 * kDeg});
  for (int i = 0; i < 60; ++i)
  {
    const auto r = localizer.addScan(drive.scan(i));
    EXPECT_EQ(r.outcome, LocalizerOutcome::kTracked);
    EXPECT_LT(drive.miss(r.pose, i), 0.01) << i;
    EXPECT_LT(std::fabs(r.pose.theta - drive.truth(i).theta), 0.2 * kDeg) << i;
  }
  EXPECT_EQ(localizer.counters().lost, 0u);
}

// A map that grows (the merger's topic) replaces the old one in the same frame: the track goes on in
// it, and a localizer that has no pose yet still has none.
TEST(LineMapLocalizer, NewMapKeepsTheTrack)
{
  const Drive drive{lRoom()};
  const std::vector<Segment2> room = lRoom();
  const std::vector<Segment2> first_half(room.begin(), room.begin() + room.size() / 2 + 1);
  LineMapLocalizer localizer(first_half);
  localizer.setPose({1.55, 2.05, 2 * kDeg});
  for (int i = 0; i < 10; ++i) localizer.addScan(drive.scan(i));
  localizer.setMap(lRoom());
  EXPECT_EQ(localizer.index().segments().size(), lRoom().size());
  for (int i = 10; i < 40; ++i)
  {
    const auto r = localizer.addScan(drive.scan(i));
    EXPECT_EQ(r.outcome, LocalizerOutcome::kTracked) << i;
    EXPECT_LT(drive.miss(r.pose, i), 0.01) << i;
  }
  LineMapLocalizer unposed(first_half);
  unposed.setMap(lRoom());
  EXPECT_FALSE(unposed.addScan(drive.scan(0)).localized);
}

TEST(LineMapLocalizer, GlobalLocalizationWithoutAnInitialPose)
{
  const Drive drive{lRoom()};
  LineMapLocalizer localizer(lRoom());
  std::optional<int> recovered;
  LocalizerResult last;
  for (int i = 0; i < 70; ++i)
  {
    last = localizer.addScan(drive.scan(i));
    if (last.outcome == LocalizerOutcome::kRecovered && !recovered) recovered = i;
    if (i == 0)
    {
      EXPECT_FALSE(last.localized);
    }
  }
  ASSERT_TRUE(recovered);
  // Accepted after accept_travel (2 m = 20 scans) at the earliest.
  EXPECT_GE(*recovered, 19);
  EXPECT_TRUE(last.localized);
  EXPECT_LT(drive.miss(last.pose, 69), 0.01);
  EXPECT_LT(std::fabs(last.pose.theta), 0.2 * kDeg);
}

namespace
{
/// The robot believes itself in the upper arm, facing down, and drives 70 scans: it must end
/// localized at its true pose.
LocalizerResult driveFromTheWrongArm(LineMapLocalizer& localizer)
{
  const Drive drive{lRoom()};
  localizer.setPose({2.0, 6.5, -1.6});
  const LocalizerResult last = drive.feed(localizer, 70);
  EXPECT_TRUE(last.localized);
  EXPECT_LT(drive.miss(last.pose, 69), 0.01);
  EXPECT_LT(std::fabs(last.pose.theta), 0.2 * kDeg);
  return last;
}
}  // namespace

TEST(LineMapLocalizer, KidnappedRobotIsRecovered)
{
  // The synthetic map is complete: a tracked scan has all its points on it, a wrong pose in a room
  // this plain (two arms of equal width) still a half.
  LocalizerParams params;
  params.lost_inlier_share = 0.8;
  LineMapLocalizer localizer(lRoom(), params);
  driveFromTheWrongArm(localizer);
  EXPECT_EQ(localizer.counters().lost, 1u);
  EXPECT_EQ(localizer.counters().recovered, 1u);
}

TEST(LineMapLocalizer, DoubtedTrackIsReplacedByABetterRival)
{
  // The wrong pose of the kidnapping above under the default parameters: it keeps matching half the
  // points, too many to be lost, too few to go unchallenged.
  LineMapLocalizer localizer(lRoom());
  driveFromTheWrongArm(localizer);
  EXPECT_EQ(localizer.counters().lost, 0u);
  EXPECT_EQ(localizer.counters().replaced, 1u);
}

TEST(LineMapLocalizer, BadInput)
{
  const Drive drive{lRoom()};
  LineMapLocalizer localizer(lRoom());
  localizer.setPose(drive.truth(0));
  const Pose2 first = localizer.addScan(drive.scan(0)).pose;
  // An empty scan: posed by the odometry, still localized.
  LocalizerScan empty = drive.scan(1);
  empty.points.clear();
  auto r = localizer.addScan(empty);
  EXPECT_EQ(r.outcome, LocalizerOutcome::kPredicted);
  EXPECT_TRUE(r.localized);
  const Pose2 predicted = first * (drive.scan(0).odom->inverse() * *drive.scan(1).odom);
  EXPECT_NEAR(r.pose.x, predicted.x, 1e-12);
  EXPECT_NEAR(r.pose.y, predicted.y, 1e-12);
  // Non-finite points and odometry are ignored; a scan out of order is rejected.
  LocalizerScan broken = drive.scan(2);
  broken.points.push_back({std::nan(""), 1.0});
  broken.odom = Pose2(std::nan(""), 0.0, 0.0);
  r = localizer.addScan(broken);
  EXPECT_EQ(r.outcome, LocalizerOutcome::kTracked);
  EXPECT_LT(drive.miss(r.pose, 2), 0.01);
  EXPECT_EQ(localizer.addScan(drive.scan(1)).outcome, LocalizerOutcome::kRejected);
  // A pose far outside the map: nothing matches; after lost_scans scans global localization starts.
  localizer.setPose({1000.0, -1000.0, 0.0});
  const std::size_t lost_scans = localizer.params().lost_scans;
  for (std::size_t i = 0; i < lost_scans; ++i)
  {
    r = localizer.addScan(drive.scan(static_cast<int>(3 + i)));
    EXPECT_EQ(r.inlier_share, 0.0);
  }
  EXPECT_FALSE(r.localized);
  EXPECT_EQ(localizer.counters().lost, 1u);
  // The clock going back: within the tolerance a scan is out of order and rejected; beyond it (a
  // replayed bag) the scan is taken, as a time jump.
  LineMapLocalizer replayed(lRoom());
  replayed.setPose(drive.truth(0));
  LocalizerScan late = drive.scan(0), early = drive.scan(0);
  late.stamp = 100.0;
  early.stamp = 100.0 - 0.5 * replayed.params().time_jump_tolerance;
  EXPECT_NE(replayed.addScan(late).outcome, LocalizerOutcome::kRejected);
  EXPECT_EQ(replayed.addScan(early).outcome, LocalizerOutcome::kRejected);
  early.stamp = 100.0 - 2.0 * replayed.params().time_jump_tolerance;
  EXPECT_EQ(replayed.addScan(early).outcome, LocalizerOutcome::kTracked);
  EXPECT_EQ(replayed.counters().time_jumps, 1u);
  // An empty map: every scan predicted, no crash.
  LineMapLocalizer nothing({});
  nothing.setPose({0, 0, 0});
  EXPECT_EQ(nothing.addScan(drive.scan(0)).outcome, LocalizerOutcome::kPredicted);
  // A missing map file names itself.
  EXPECT_THROW(loadLineMapSegments("/nonexistent/map.yaml"), MapFileError);
}
