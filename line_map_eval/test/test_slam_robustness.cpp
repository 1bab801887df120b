// The robustness benchmark's parts against hand-computed values: the scaled parameter values (a count
// that a plain product would make fractional, a ratio a product would push past 1, a probability whose
// tail must scale), the input faults (a scale fault that also turned the odometry, a drop that also
// removed the first scan, jitter that reordered scans would each fail), the ground-truth relations and
// the summary's percentiles and failures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "line_map_eval/batch/slam_robustness.hpp"

using namespace line_map_eval;
using linemap::Pose2;

namespace
{
/// `n` scans 0.1 s apart driving along x, 0.05 m per scan, turning 0.01 rad per scan.
Recording arc(std::size_t n)
{
  Recording r;
  Pose2 p;
  for (std::size_t i = 0; i < n; ++i)
  {
    RecordedScan s;
    s.stamp = 1.0 + 0.1 * static_cast<double>(i);
    s.odom = p;
    r.scans.push_back(s);
    r.keyframes.push_back({i, p});
    p = p * Pose2(0.05, 0.0, 0.01);
  }
  return r;
}

double odometryPath(const Recording& r)
{
  double path = 0.0;
  for (std::size_t i = 1; i < r.scans.size(); ++i)
  {
    const Pose2 step = r.scans[i - 1].odom.inverse() * r.scans[i].odom;
    path += std::hypot(step.x, step.y);
  }
  return path;
}
}  // namespace

TEST(SlamRobustness, ScaledValuesKeepTheKeysKind)
{
  EXPECT_EQ(*scaledValue("front_end/min_points", "20", 0.7), "14");
  EXPECT_EQ(*scaledValue("front_end/min_points", "20", 1.4), "28");
  // 1 x 0.7 rounds back to 1: nothing to try.
  EXPECT_FALSE(scaledValue("loop/every", "1", 0.7).has_value());
  EXPECT_FALSE(scaledValue("loop/candidates", "1", 1.4).has_value()) << "1.4 rounds to 1";
}

TEST(SlamRobustness, RatiosAndProbabilitiesStayValid)
{
  EXPECT_DOUBLE_EQ(std::stod(*scaledValue("loop/ambiguity_margin", "0.8", 1.4)), 1.0);
  EXPECT_DOUBLE_EQ(std::stod(*scaledValue("loop/ambiguity_margin", "0.1", 0.7)), 0.07);
  // The tail 0.001 scaled: 0.9986 and 0.9993.
  EXPECT_NEAR(std::stod(*scaledValue("loop/consistency_probability", "0.999", 1.4)), 0.9986, 1e-9);
  EXPECT_NEAR(std::stod(*scaledValue("loop/consistency_probability", "0.999", 0.7)), 0.9993, 1e-9);
  EXPECT_NEAR(std::stod(*scaledValue("front_end/sigma", "0.03", 1.4)), 0.042, 1e-12);
}

TEST(SlamRobustness, ScalableKeysAreTheSlamsNumbers)
{
  linemap::ParamSet p;
  p.set("front_end/sigma", "0.03");
  p.set("loop/corroborate_xy", "1.0e9");  // an off switch
  p.set("map_frame", "map");
  p.set("queue_size", "1000");  // the ROS wrapper's
  p.set("isotropic_ratio", "0.05");
  const auto keys = scalableSlamKeys(p);
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_EQ(keys[0], "front_end/sigma");
  EXPECT_EQ(keys[1], "isotropic_ratio");
  EXPECT_EQ(parameterVariants(p).size(), 4u);
}

TEST(SlamRobustness, OdometryScaleLengthensEveryStepAndTurnsNothing)
{
  const Recording r = arc(101);
  const FaultyRecording f = withFault(r, InputFault::kOdometryScale, 1);
  const double ratio = odometryPath(f.recording) / odometryPath(r);
  EXPECT_NEAR(std::fabs(ratio - 1.0), 0.03, 1e-9);
  EXPECT_NEAR(f.recording.scans.back().odom.theta, r.scans.back().odom.theta, 1e-12);
}

TEST(SlamRobustness, HeadingDriftTurnsByThePath)
{
  const Recording r = arc(101);  // 5 m
  const FaultyRecording f = withFault(r, InputFault::kHeadingDrift, 1);
  const double drift =
      linemap::normalizeAngle(f.recording.scans.back().odom.theta - r.scans.back().odom.theta);
  EXPECT_NEAR(std::fabs(drift), 0.003 * 5.0, 1e-9);
  EXPECT_NEAR(odometryPath(f.recording), odometryPath(r), 1e-9);
}

TEST(SlamRobustness, DroppedScansKeepTheFirstAndTheirOrigin)
{
  const Recording r = arc(2000);
  const FaultyRecording f = withFault(r, InputFault::kDroppedScans, 3);
  const double dropped = 1.0 - static_cast<double>(f.recording.scans.size()) / 2000.0;
  // Binomial(1999, 0.1): standard deviation 0.0067 of the share.
  EXPECT_NEAR(dropped, 0.1, 0.03);
  ASSERT_EQ(f.original.size(), f.recording.scans.size());
  EXPECT_EQ(f.original.front(), 0u);
  for (std::size_t i = 0; i < f.original.size(); ++i)
    EXPECT_EQ(f.recording.scans[i].stamp, r.scans[f.original[i]].stamp);
  ASSERT_EQ(f.recording.keyframes.size(), f.recording.scans.size());
  for (const auto& kf : f.recording.keyframes)
    EXPECT_EQ(kf.pose.x, r.keyframes[f.original[kf.scan_index]].pose.x);
}

TEST(SlamRobustness, LateStartDropsOnlyAPrefix)
{
  const Recording r = arc(1000);
  for (std::uint32_t seed = 1; seed <= 5; ++seed)
  {
    const FaultyRecording f = withFault(r, InputFault::kLateStart, seed);
    const std::size_t first = f.original.front();
    EXPECT_GE(first, 20u);
    EXPECT_LE(first, 100u);
    EXPECT_EQ(f.recording.scans.size(), 1000u - first);
    EXPECT_EQ(f.original.back(), 999u);
  }
}

TEST(SlamRobustness, JitteredStampsStayInOrderAndNear)
{
  const Recording r = arc(500);
  const FaultyRecording f = withFault(r, InputFault::kStampJitter, 4);
  double moved = 0.0;
  for (std::size_t i = 0; i < r.scans.size(); ++i)
  {
    if (i > 0)
    {
      EXPECT_GT(f.recording.scans[i].stamp, f.recording.scans[i - 1].stamp);
    }
    EXPECT_LE(std::fabs(f.recording.scans[i].stamp - r.scans[i].stamp), 0.02 + 1e-9);  // a fifth of 0.1 s
    moved = std::max(moved, std::fabs(f.recording.scans[i].stamp - r.scans[i].stamp));
  }
  EXPECT_GT(moved, 0.01);
}

TEST(SlamRobustness, TruthRelationsAreTrueRelativePosesWithRevisits)
{
  // Out 10 m along x and back along y = 0.5: the way back passes every sample of the way out.
  Recording r;
  for (int i = 0; i <= 100; ++i)
  {
    RecordedScan s;
    s.stamp = i;
    r.scans.push_back(s);
    r.keyframes.push_back({r.scans.size() - 1, Pose2(0.1 * i, 0.0, 0.0)});
  }
  for (int i = 0; i <= 100; ++i)
  {
    RecordedScan s;
    s.stamp = 200 + i;
    r.scans.push_back(s);
    r.keyframes.push_back({r.scans.size() - 1, Pose2(10.0 - 0.1 * i, 0.5, linemap::kPi)});
  }
  const auto relations = truthRelations(r, 1.0, 2.0, 5.0);
  std::size_t revisits = 0;
  for (const auto& rel : relations)
  {
    const bool out = rel.t1 < 150, back = rel.t2 >= 150;
    if (out && back)
    {
      ++revisits;
      // From (x, 0, 0) to (x', 0.5, pi): dx = x' - x, dy = 0.5, turned by pi.
      EXPECT_NEAR(std::fabs(rel.delta.theta), linemap::kPi, 1e-9);
      EXPECT_NEAR(rel.delta.y, 0.5, 1e-9);
      EXPECT_LE(std::hypot(rel.delta.x, rel.delta.y), 2.0);
    }
    else if (!back)
    {
      EXPECT_NEAR(rel.delta.y, 0.0, 1e-12);
      EXPECT_NEAR(rel.delta.x, (rel.t2 - rel.t1) * 0.1, 1e-9);
    }
  }
  // Samples of the way out up to x = 9 have a sample of the way back within 2 m and over 5 m of path on.
  EXPECT_GE(revisits, 6u);
}

TEST(SlamRobustness, SummaryPercentilesAndFailures)
{
  std::vector<RobustnessRun> runs(10);
  const double errors[] = {0.02, 0.021, 0.019, 0.022, 0.018, 0.025, 0.03, 0.041, 0.2, 0.023};
  for (std::size_t i = 0; i < runs.size(); ++i)
  {
    runs[i].variant.label = i == 0 ? "defaults" : "run " + std::to_string(i);
    runs[i].error.translation_mean = errors[i];
    runs[i].error.used = 10;
  }
  const RobustnessSummary s = summarize(runs);
  EXPECT_DOUBLE_EQ(s.defaults, 0.02);
  EXPECT_DOUBLE_EQ(s.median, 0.0225);  // (0.022 + 0.023) / 2
  EXPECT_DOUBLE_EQ(s.p90, 0.041);      // the 9th of 10
  EXPECT_DOUBLE_EQ(s.worst, 0.2);
  EXPECT_EQ(s.worst_label, "run 8");
  EXPECT_EQ(s.failures, 2u);  // 0.041 > 2 x 0.02 and 0.2
  EXPECT_FALSE(runs[7].failure.empty());
  EXPECT_FALSE(runs[8].failure.empty());
  EXPECT_TRUE(runs[6].failure.empty());
}

// Every fault is found by its printed name and by the name with dashes the command line takes; a failure's
// rerun options name exactly its run: a fault variant its fault and seed, a parameter variant its key.
TEST(SlamRobustness, AFailureCanBeRunAgainAlone)
{
  const std::vector<InputFault> all{InputFault::kOdometryScale, InputFault::kHeadingDrift,
                                    InputFault::kDroppedScans,  InputFault::kLateStart,
                                    InputFault::kStampJitter,   InputFault::kFrontEndSlip};
  EXPECT_EQ(allInputFaults(), all);
  EXPECT_EQ(faultOption(InputFault::kLateStart), "late-start");
  EXPECT_EQ(faultOption(InputFault::kFrontEndSlip), "front-end-slip");
  for (InputFault f : all)
  {
    EXPECT_EQ(faultFromName(faultName(f)), f) << faultName(f);
    std::string dashed = faultName(f);
    std::replace(dashed.begin(), dashed.end(), ' ', '-');
    EXPECT_EQ(faultFromName(dashed), f) << dashed;
  }
  EXPECT_EQ(faultFromName("late-start"), InputFault::kLateStart);
  EXPECT_EQ(faultFromName("front-end-slip"), InputFault::kFrontEndSlip);
  EXPECT_FALSE(faultFromName("late"));
  EXPECT_FALSE(faultFromName("slip"));

  const auto late = faultVariants({InputFault::kLateStart}, 3, 4);
  ASSERT_EQ(late.size(), 3u);
  EXPECT_EQ(rerunOptions(late[1]), "--only faults --fault late-start --runs 1 --seed 5");
  EXPECT_EQ(rerunOptions(faultVariants({InputFault::kFrontEndSlip}, 1, 18).front()),
            "--only faults --fault front-end-slip --runs 1 --seed 18");
  linemap::ParamSet defaults;
  defaults.set("loop/min_score", "0.55");
  const auto scaled = parameterVariants(defaults);
  ASSERT_EQ(scaled.size(), 2u);
  EXPECT_EQ(rerunOptions(scaled.front()), "--only parameters --keys loop/min_score");
  EXPECT_EQ(rerunOptions(RobustnessVariant{"defaults", {}, std::nullopt, 0}), "--only defaults");
}

// The faults' tally: per fault its runs, failures and worst error, in the order the faults first appear;
// the defaults and parameter runs are in no tally.
TEST(SlamRobustness, FailuresAreTalliedByFault)
{
  std::vector<RobustnessRun> runs(6);
  runs[0].variant = {"defaults", {}, std::nullopt, 0};
  runs[1].variant = {"loop/min_score x0.7", {"loop/min_score=0.385"}, std::nullopt, 0};
  runs[2].variant = faultVariants({InputFault::kLateStart}, 1, 1).front();
  runs[3].variant = faultVariants({InputFault::kFrontEndSlip}, 1, 1).front();
  runs[4].variant = faultVariants({InputFault::kLateStart}, 1, 2).front();
  runs[5].variant = faultVariants({InputFault::kFrontEndSlip}, 1, 2).front();
  const double errors[] = {0.02, 0.5, 0.03, 0.021, 0.05, 0.022};
  for (std::size_t i = 0; i < runs.size(); ++i)
  {
    runs[i].error.translation_mean = errors[i];
    runs[i].error.used = 10;
  }
  const RobustnessSummary s = summarize(runs);
  EXPECT_EQ(s.failures, 2u);  // the parameter run (0.5) and the second later start (0.05 > 2 x 0.02)
  ASSERT_EQ(s.by_fault.size(), 2u);
  EXPECT_EQ(s.by_fault[0].fault, InputFault::kLateStart);
  EXPECT_EQ(s.by_fault[0].runs, 2u);
  EXPECT_EQ(s.by_fault[0].failures, 1u);
  EXPECT_DOUBLE_EQ(s.by_fault[0].worst, 0.05);
  EXPECT_EQ(s.by_fault[1].fault, InputFault::kFrontEndSlip);
  EXPECT_EQ(s.by_fault[1].runs, 2u);
  EXPECT_EQ(s.by_fault[1].failures, 0u);
  EXPECT_DOUBLE_EQ(s.by_fault[1].worst, 0.022);
}
