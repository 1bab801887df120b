// LaserSlam on a ray-cast room: with drifting odometry and without odometry the trajectory stays on
// the truth, loops close; bad input (time going back, empty scans, odometry jumps, NaN odometry) is
// counted and leaves the graph intact; closure attempts are recorded with their keyframes; in clutter the
// closures' score floor follows the front end's scores down.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "line_map_merging/slam/laser_slam.hpp"
#include "slam_world.hpp"

using line_map_merging::ClosureAttempt;
using line_map_merging::LaserSlam;
using line_map_merging::LaserSlamParams;
using line_map_merging::SlamOutcome;
using line_map_merging::SlamScan;
using linemap::Pose2;

namespace
{
/// Two laps of a 5.5 x 3 m rectangle in the room: 5 cm per scan, turning 0.1 rad per scan at corners.
std::vector<Pose2> laps(int count)
{
  const std::vector<linemap::Vec2> corners = {{1.5, 4.0}, {7.0, 4.0}, {7.0, 1.0}, {1.5, 1.0}};
  std::vector<linemap::Vec2> goals;
  for (int lap = 0; lap < count; ++lap)
    for (std::size_t c = 1; c <= corners.size(); ++c) goals.push_back(corners[c % corners.size()]);
  return slam_world::drive(Pose2(1.5, 4.0, 0.0), goals);
}

/// Odometry with a heading bias per metre and per radian: the loop visibly fails to close.
std::vector<Pose2> drifting(const std::vector<Pose2>& truth)
{
  std::vector<Pose2> odom{truth[0]};
  for (std::size_t i = 1; i < truth.size(); ++i)
  {
    Pose2 step = truth[i - 1].inverse() * truth[i];
    step.theta += 0.03 * std::hypot(step.x, step.y) + 0.02 * step.theta;
    odom.push_back(odom.back() * step);
  }
  return odom;
}

/// Largest and mean position error; the SLAM's map frame is the first pose.
std::pair<double, double> errors(const std::vector<std::pair<double, Pose2>>& poses,
                                 const std::vector<Pose2>& truth)
{
  double m = 0.0, sum = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i)
  {
    const Pose2 p = truth[0] * poses[i].second;
    const double e = std::hypot(p.x - truth[i].x, p.y - truth[i].y);
    m = std::max(m, e);
    sum += e;
  }
  return {m, sum / static_cast<double>(poses.size())};
}

// Range noise 5 mm, cells 2.5 cm: a few centimetres at worst, about one centimetre on average.
void expectOnTruth(const std::vector<std::pair<double, Pose2>>& poses, const std::vector<Pose2>& truth)
{
  const auto [worst, mean] = errors(poses, truth);
  EXPECT_LT(worst, 0.1);
  EXPECT_LT(mean, 0.03);
}

struct Room
{
  LaserSlam slam;
  std::vector<Pose2> truth, odom;
  explicit Room(const LaserSlamParams& p = {}) : slam(p), truth(laps(2)), odom(drifting(truth)) {}
  SlamScan scan(std::size_t i, bool with_odom) const
  {
    SlamScan s;
    s.stamp = 1.0 + 0.2 * static_cast<double>(i);
    s.points = slam_world::scan(slam_world::room(), truth[i], 180, 20.0, 0.005, static_cast<unsigned>(i));
    if (with_odom) s.odom = odom[i];
    return s;
  }
};
}  // namespace

TEST(LaserSlam, DriftingOdometryLoopCloses)
{
  Room run;
  double odom_error = 0.0;
  for (std::size_t i = 0; i < run.truth.size(); ++i)
  {
    ASSERT_NE(run.slam.addScan(run.scan(i, true)), SlamOutcome::kRejected);
    odom_error = std::max(odom_error, (run.odom[i].translation() - run.truth[i].translation()).norm());
  }
  EXPECT_GT(odom_error, 0.3);  // the odometry alone is far off
  EXPECT_LT(errors(run.slam.scanPoses(), run.truth).first, odom_error / 3.0);
  const auto& c = run.slam.counters();
  EXPECT_GT(c.loops_accepted, 0u);
  EXPECT_EQ(c.poor_matches, 0u);
  EXPECT_EQ(run.slam.scanPoses().size(), run.truth.size());
  expectOnTruth(run.slam.scanPoses(), run.truth);
  // The trajectory is of the keyframes, stamped with their scans' stamps, in order.
  const auto t = run.slam.trajectory();
  ASSERT_EQ(t.size(), c.keyframes);
  for (std::size_t k = 1; k < t.size(); ++k) EXPECT_GT(t[k].first, t[k - 1].first);
}

// No closure to repair anything (loop search off), true odometry. A slip of the front end halfway (0.3 m and
// 5 degrees: its frame jumps, its local map with it) leaves every later pose 0.3 m off, unless the keyframe
// edge across it takes the odometry's motion, which the two keyframes' scans fit better than the slipped
// match's (only the few scans between the slip and the next keyframe then stay off). A jump of the odometry
// instead (its later poses 0.3 m and 5 degrees off) is a disagreement too, but there the scans fit the match:
// the edge keeps it, and the trajectory stays on the truth.
TEST(LaserSlam, TheScanPairTellsWhichOfMatchAndOdometrySlipped)
{
  const Pose2 slip(0.3, 0.0, 5.0 * linemap::kPi / 180.0);
  for (const bool follow : {true, false})
  {
    LaserSlamParams p;
    p.loop_candidates = 0;
    p.suspect_edge_follows_odometry = follow;
    Room run(p);
    run.odom = run.truth;
    const std::size_t half = run.truth.size() / 2;
    for (std::size_t i = 0; i < run.truth.size(); ++i)
    {
      if (i == half) run.slam.injectFrontEndSlip(slip);
      ASSERT_NE(run.slam.addScan(run.scan(i, true)), SlamOutcome::kRejected);
    }
    const auto& c = run.slam.counters();
    EXPECT_EQ(c.suspect_edges, 1u);
    EXPECT_EQ(c.suspect_edges_on_odometry, follow ? 1u : 0u);
    const double mean = errors(run.slam.scanPoses(), run.truth).second;
    if (follow)
      EXPECT_LT(mean, 0.03);
    else
      EXPECT_GT(mean, 0.2);  // half the scans 0.3 m off and more, turned 5 degrees about the slip
  }
  Room jumped;
  jumped.odom = jumped.truth;
  for (std::size_t i = jumped.truth.size() / 2; i < jumped.truth.size(); ++i)
    jumped.odom[i] = jumped.odom[i] * slip;
  for (std::size_t i = 0; i < jumped.truth.size(); ++i)
    ASSERT_NE(jumped.slam.addScan(jumped.scan(i, true)), SlamOutcome::kRejected);
  EXPECT_EQ(jumped.slam.counters().suspect_edges, 1u);
  EXPECT_EQ(jumped.slam.counters().suspect_edges_on_odometry, 0u);
  expectOnTruth(jumped.slam.scanPoses(), jumped.truth);
}

// Every closure attempt that got as far as a match is recorded with its keyframes and outcome; the
// records agree with the counters, and the first accepted closure joins two keyframes that the truth
// puts at the laps' meeting point (the start, where the second lap first sees the first one again).
TEST(LaserSlam, ClosureAttemptsAreRecorded)
{
  Room run;
  for (std::size_t i = 0; i < run.truth.size(); ++i) run.slam.addScan(run.scan(i, true));
  using line_map_merging::ClosureOutcome;
  const auto& attempts = run.slam.closureAttempts();
  const auto& c = run.slam.counters();
  const auto count = [&](ClosureOutcome o)
  {
    return static_cast<std::size_t>(
        std::count_if(attempts.begin(), attempts.end(), [o](const auto& a) { return a.outcome == o; }));
  };
  EXPECT_EQ(count(ClosureOutcome::kAccepted), c.loops_accepted);
  EXPECT_EQ(count(ClosureOutcome::kAmbiguous), c.loops_ambiguous);
  EXPECT_EQ(count(ClosureOutcome::kInconsistent), c.loops_inconsistent);
  EXPECT_EQ(count(ClosureOutcome::kRejectedGraph), c.loops_rejected_graph);
  EXPECT_LE(count(ClosureOutcome::kRejectedScore), c.loops_rejected_score);
  EXPECT_LE(attempts.size(), c.loop_attempts);
  const auto& kfs = run.slam.keyframes();
  const auto truthOf = [&](std::size_t k) { return run.truth[kfs[k].scan].translation(); };
  const ClosureAttempt* first = nullptr;
  for (const auto& a : attempts)
  {
    ASSERT_LT(a.from, a.to);
    ASSERT_LT(a.to, kfs.size());
    EXPECT_GE(kfs[a.to].path - kfs[a.from].path, run.slam.params().loop_min_path);
    if (a.outcome != ClosureOutcome::kAccepted) continue;
    EXPECT_GE(a.score, a.min_score);
    EXPECT_LE(a.min_score, run.slam.params().loop_min_score);
    // A true closure: the submap's centre is the candidate nearest the estimate, within the search radius.
    EXPECT_LT((truthOf(a.from) - truthOf(a.to)).norm(), 1.0) << a.from << " - " << a.to;
    if (!first) first = &a;
  }
  ASSERT_NE(first, nullptr);
  const linemap::Vec2 meeting = run.truth.front().translation();
  EXPECT_LT((truthOf(first->from) - meeting).norm(), 1.5);
  EXPECT_LT((truthOf(first->to) - meeting).norm(), 1.5);
}

// Turning on the spot faster than the odometry says (it reports 40 % of each 0.25 rad step, like a
// slipping wheel): every scan's heading is off the prediction by more than the normal search window. A
// match inside that window is poor or lies on its border, so the wide window must be searched too, and
// its refinement not held to the predicted heading; otherwise the heading error accumulates scan by scan.
TEST(LaserSlam, FastTurnBeyondTheOdometryWindow)
{
  std::vector<Pose2> truth{Pose2(6.0, 4.0, 0.0)}, odom{Pose2(6.0, 4.0, 0.0)};
  for (int i = 0; i < 50; ++i)
  {
    truth.push_back(truth.back() * Pose2(0.0, 0.0, 0.25));
    odom.push_back(odom.back() * Pose2(0.0, 0.0, 0.1));
  }
  LaserSlam slam;
  for (std::size_t i = 0; i < truth.size(); ++i)
  {
    SlamScan s;
    s.stamp = 1.0 + 0.2 * static_cast<double>(i);
    s.points = slam_world::scan(slam_world::room(), truth[i], 180, 20.0, 0.005, static_cast<unsigned>(i));
    s.odom = odom[i];
    slam.addScan(s);
  }
  const auto poses = slam.scanPoses();
  ASSERT_EQ(poses.size(), truth.size());
  double worst_heading = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i)
    worst_heading =
        std::max(worst_heading,
                 std::fabs(linemap::normalizeAngle((truth[0] * poses[i].second).theta - truth[i].theta)));
  EXPECT_LT(worst_heading, 0.02);
  EXPECT_GT(slam.counters().wide_searches, 10u);
}

TEST(LaserSlam, WithoutOdometry)
{
  Room run;
  for (std::size_t i = 0; i < run.truth.size(); ++i) run.slam.addScan(run.scan(i, false));
  EXPECT_EQ(run.slam.counters().without_odometry, run.truth.size());
  expectOnTruth(run.slam.scanPoses(), run.truth);
}

// Without odometry, twelve blind scans on the first straight (too few points: posed by the
// constant-velocity prediction): the first match after them spans thirteen scans' motion, which is
// per-scan velocity only once spread over them; taken whole, the prediction would run 0.65 m per scan
// ahead, beyond the wide window, and never be caught again.
TEST(LaserSlam, WithoutOdometryAcrossBlindScans)
{
  Room run;
  for (std::size_t i = 0; i < run.truth.size(); ++i)
  {
    SlamScan s = run.scan(i, false);
    if (i >= 40 && i < 52) s.points.clear();
    run.slam.addScan(s);
  }
  EXPECT_EQ(run.slam.counters().few_points, 12u);
  expectOnTruth(run.slam.scanPoses(), run.truth);
}

// Without odometry, the log pauses for 3 s while the robot turns in place (ACES does at a corner): it
// turned 1.44 rad then, and the constant velocity predicts one scan's turn, 0.08 rad. The first scan
// after the pause lies far outside the wide window around that prediction; found by searching every
// heading around where the robot was, its heading and every later one stay on the truth.
TEST(LaserSlam, WithoutOdometryAcrossAPauseWhileTurning)
{
  constexpr double kPeriod = 0.2, kTurn = 0.08;
  constexpr int kBefore = 20, kPaused = 18, kAfter = 20;
  LaserSlam slam;
  std::vector<Pose2> truth;
  Pose2 pose(4.5, 4.0, 0.0);
  for (int k = 0; k < kBefore + kPaused + kAfter; ++k)
  {
    pose = pose * Pose2(0.0, 0.0, k < kBefore + kPaused ? kTurn : 0.25 * kTurn);
    if (k >= kBefore && k < kBefore + kPaused) continue;  // no scan logged
    SlamScan s;
    s.stamp = 1.0 + kPeriod * static_cast<double>(k);
    s.points = slam_world::scan(slam_world::room(), pose, 180, 20.0, 0.005, static_cast<unsigned>(k));
    slam.addScan(s);
    truth.push_back(pose);
  }
  const auto poses = slam.scanPoses();
  ASSERT_EQ(poses.size(), truth.size());
  double worst_heading = 0.0, worst_position = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i)
  {
    const Pose2 p = truth[0] * poses[i].second;
    worst_heading = std::max(worst_heading, std::fabs(linemap::normalizeAngle(p.theta - truth[i].theta)));
    worst_position = std::max(worst_position, std::hypot(p.x - truth[i].x, p.y - truth[i].y));
  }
  EXPECT_LT(worst_heading, 0.03);
  EXPECT_LT(worst_position, 0.05);
  EXPECT_EQ(slam.counters().poor_matches, 0u);
}

TEST(LaserSlam, BadInputIsCountedAndHarmless)
{
  Room run;
  const std::size_t n = run.truth.size() / 2;
  for (std::size_t i = 0; i < n; ++i) run.slam.addScan(run.scan(i, true));
  const std::size_t keyframes = run.slam.keyframes().size();
  const Pose2 before = run.slam.currentPose();

  // Time going back by 5 s: ignored, counted; nothing changes. (Stamps stay positive, as ROS and the
  // logs have them: linemap::TimeJumpDetector takes a stamp <= 0 for an unknown one.)
  SlamScan back = run.scan(n, true);
  back.stamp -= 5.0;
  ASSERT_GT(back.stamp, 0.0);
  EXPECT_EQ(run.slam.addScan(back), SlamOutcome::kRejected);
  EXPECT_EQ(run.slam.counters().time_jumps, 1u);
  EXPECT_EQ(run.slam.keyframes().size(), keyframes);
  EXPECT_NEAR(run.slam.currentPose().x, before.x, 1e-12);

  // An empty scan (the laser blinded): posed by odometry, counted, no keyframe.
  SlamScan empty = run.scan(n, true);
  empty.points.clear();
  EXPECT_EQ(run.slam.addScan(empty), SlamOutcome::kPredicted);
  EXPECT_EQ(run.slam.counters().few_points, 1u);

  // Odometry jumping by 3 m from here on, and one NaN odometry reading: matching carries on.
  for (std::size_t i = n + 1; i < run.truth.size(); ++i)
  {
    SlamScan s = run.scan(i, true);
    s.odom = Pose2(3.0, -2.0, 1.0) * *s.odom;
    if (i == n + 20) s.odom = Pose2(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
    EXPECT_EQ(run.slam.addScan(s), SlamOutcome::kMatched) << "scan " << i;
  }
  const auto& c = run.slam.counters();
  EXPECT_GE(c.odometry_jumps, 1u);
  EXPECT_EQ(c.poor_matches, 0u);
  EXPECT_EQ(c.rejected, 1u);
  // Every accepted scan has a pose (the rejected one none), all on the truth.
  const auto poses = run.slam.scanPoses();
  ASSERT_EQ(poses.size(), run.truth.size());
  expectOnTruth(poses, run.truth);
}

namespace
{
/// The parameters are refused with a message that names `key`.
void expectRefusedNaming(const linemap::ParamSet& p, const std::string& key)
{
  try
  {
    LaserSlamParams::fromParams(p);
    ADD_FAILURE() << "accepted; expected a refusal naming " << key;
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(LaserSlam, ParametersAreCheckedByName)
{
  linemap::ParamSet p;
  p.set("front_end/resolution", "-1");
  expectRefusedNaming(p, "front_end/resolution");
  p = linemap::ParamSet();
  p.set("loop/min_score", "0.7");
  EXPECT_DOUBLE_EQ(LaserSlamParams::fromParams(p).loop_min_score, 0.7);
  p.set("loop/min_score_ratio", "-0.1");
  expectRefusedNaming(p, "loop/min_score_ratio");
  p = linemap::ParamSet();
  p.set("loop/consensus_keyframes", "25");  // the former key: not silently ignored
  expectRefusedNaming(p, "loop/consensus_waiting");
  p = linemap::ParamSet();
  p.set("loop/consensus_waiting", "1");  // a consensus needs two waiting at least
  expectRefusedNaming(p, "loop/consensus_waiting");
}

TEST(LaserSlam, TheAmbiguityTestIsAMarginBelowTheBest)
{
  linemap::ParamSet p;
  p.set("loop/ambiguity_ratio", "0.9");  // the former key: not silently ignored
  expectRefusedNaming(p, "loop/ambiguity_margin");
  p = linemap::ParamSet();
  p.set("loop/ambiguity_margin", "1.5");
  expectRefusedNaming(p, "loop/ambiguity_margin");
  p.set("loop/ambiguity_margin", "0.2");
  const LaserSlamParams s = LaserSlamParams::fromParams(p);
  // A rival at 85 % of the best lies within 20 % of it; one at 75 % does not.
  EXPECT_TRUE(s.ambiguous(0.85));
  EXPECT_FALSE(s.ambiguous(0.75));
  LaserSlamParams off = s;
  off.loop_ambiguity_margin = 0.0;
  EXPECT_FALSE(off.ambiguous(1.0)) << "a margin of 0 is no test, even for a tie";
  off = s;
  off.loop_ambiguity_distance = 0.0;
  EXPECT_FALSE(off.ambiguous(1.0));
}

namespace
{
/// The room's two laps with the drifting odometry, a share `clutter` of the beams returning short of the
/// walls at random (people, chairs): every match, the front end's and the closures', scores that much lower.
LaserSlam clutteredLaps(const LaserSlamParams& p, double clutter, const Room& room)
{
  LaserSlam slam(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t i = 0; i < room.truth.size(); ++i)
  {
    SlamScan s = room.scan(i, true);
    for (auto& q : s.points)
      if (u(rng) < clutter) q *= 0.2 + 0.7 * u(rng);
    EXPECT_NE(slam.addScan(s), SlamOutcome::kRejected);
  }
  return slam;
}
}  // namespace

// In a cluttered room every match scores lower, true closures with the rest: the closures' floor follows
// the front end's score down, so they still go in (and only true ones); the absolute floor refuses most.
TEST(LaserSlam, ClutterLowersTheClosuresScoreFloorWithTheFrontEndsScore)
{
  const Room room;
  constexpr double kClutter = 0.5;
  LaserSlamParams relative, absolute;
  absolute.loop_min_score_ratio = 0.0;
  const LaserSlam a = clutteredLaps(relative, kClutter, room), b = clutteredLaps(absolute, kClutter, room);
  ASSERT_FALSE(a.closureAttempts().empty());
  ASSERT_FALSE(b.closureAttempts().empty());
  // The front end scores about the uncluttered share of the points (the clean room's 0.97), a little more
  // where a clutter point meets an earlier one: the floor is the ratio of that.
  const double floor = a.closureAttempts().back().min_score;
  EXPECT_GT(floor, relative.loop_min_score_ratio * (1.0 - kClutter) * 0.9);
  EXPECT_LT(floor, relative.loop_min_score_ratio * (1.0 - kClutter / 2.0));
  for (const ClosureAttempt& c : b.closureAttempts()) EXPECT_EQ(c.min_score, absolute.loop_min_score);
  EXPECT_GE(static_cast<double>(a.counters().loops_accepted),
            1.5 * static_cast<double>(b.counters().loops_accepted));
  const auto& kfs = a.keyframes();
  for (const ClosureAttempt& c : a.closureAttempts())
  {
    EXPECT_LE(c.min_score, relative.loop_min_score);
    if (c.outcome != line_map_merging::ClosureOutcome::kAccepted) continue;
    EXPECT_GE(c.score, c.min_score);
    EXPECT_LT((room.truth[kfs[c.from].scan].translation() - room.truth[kfs[c.to].scan].translation()).norm(),
              1.0)
        << c.from << " - " << c.to;
  }
  EXPECT_LT(errors(a.scanPoses(), room.truth).first, 0.1);
  // The diagnostics show the floor as it is now, which the absolute run keeps at loop_min_score.
  const auto shown = [](const LaserSlam& slam)
  {
    for (const auto& [key, value] : slam.diagnostics())
      if (key == "loop closures' score floor (now)") return std::stod(value);
    return -1.0;
  };
  EXPECT_GT(shown(a), 0.0);
  EXPECT_LT(shown(a), relative.loop_min_score_ratio * (1.0 - kClutter / 2.0));
  EXPECT_NEAR(shown(b), absolute.loop_min_score, 1e-3);
}
