// The one online path's schedule and feed: what the back end publishes along a recording (as the bag
// writers write it), and scans posed by map -> odom -> base -> laser into the OnlineMapper.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_eval/online/online_drive.hpp"
#include "line_map_merging/mergers/merger.hpp"

using namespace line_map_eval;
using linemap::Pose2;

namespace
{
/// Ten scans 1 s apart driving 1 m each along x by odometry; keyframes at scans 1, 3, 5, 7, 9 whose
/// corrected poses lie 0.5 m to the left of the odometry (a constant correction).
Recording straightRun()
{
  Recording rec;
  rec.base_to_laser = Pose2(0.1, 0.0, 0.0);
  for (int i = 0; i < 10; ++i)
  {
    RecordedScan s;
    s.stamp = 100.0 + i;
    s.odom = Pose2(i, 0.0, 0.0);
    rec.scans.push_back(s);
  }
  for (std::size_t i = 1; i < 10; i += 2)
    rec.keyframes.push_back({i, Pose2(static_cast<double>(i), 0.5, 0.0)});
  return rec;
}

bool near(const Pose2& a, const Pose2& b)
{
  return std::abs(a.x - b.x) < 1e-12 && std::abs(a.y - b.y) < 1e-12 && std::abs(a.theta - b.theta) < 1e-12;
}
}  // namespace

TEST(OnlineDrive, TheBackEndPublishesEveryNKeyframesAndAtTheEnd)
{
  const Recording rec = straightRun();
  const BackEndSchedule s = loopClosureSchedule(rec, 2);
  // Five keyframes, every 2: after the 2nd (scan 3), the 4th (scan 7) and the 5th (scan 9, the last).
  ASSERT_EQ(s.trajectories.size(), 3u);
  EXPECT_EQ(s.trajectories[0].stamp, 103.0);
  EXPECT_EQ(s.trajectories[1].stamp, 107.0);
  EXPECT_EQ(s.trajectories[2].stamp, 109.0);
  EXPECT_EQ(s.trajectories[0].poses.size(), 2u);
  EXPECT_EQ(s.trajectories[2].poses.size(), 5u);
  EXPECT_EQ(s.trajectories[2].poses[4].first, 109.0);
  EXPECT_TRUE(near(s.trajectories[2].poses[4].second, Pose2(9.0, 0.5, 0.0)));
  // map -> odom at every scan: identity until the first trajectory, the correction from then on.
  ASSERT_EQ(s.map_to_odom.size(), rec.scans.size());
  EXPECT_TRUE(near(s.map_to_odom[2].second, Pose2()));
  EXPECT_TRUE(near(s.map_to_odom[3].second, Pose2(0.0, 0.5, 0.0)));
  // Every 0: only at the end.
  EXPECT_EQ(loopClosureSchedule(rec, 0).trajectories.size(), 1u);
}

TEST(OnlineDrive, FixedPosesPutEveryKeyframeAtItsPose)
{
  const Recording rec = straightRun();
  const BackEndSchedule s = fixedPoseSchedule(rec);
  EXPECT_TRUE(s.trajectories.empty());
  for (const auto& kf : rec.keyframes)
  {
    const RecordedScan& scan = rec.scans[kf.scan_index];
    EXPECT_TRUE(near(sampleAt(s.map_to_odom, scan.stamp) * scan.odom, kf.pose));
  }
}

TEST(OnlineDrive, ScansArePosedByMapToOdomAndTrajectoriesFollowTheirScan)
{
  const Recording rec = straightRun();
  const BackEndSchedule schedule = loopClosureSchedule(rec, 2);
  linemap::ParamSet params;
  params.set("keyframe_distance", "0.5");
  auto mp = line_map_merging::OnlineMapperParams::fromParams(params);
  mp.keyframe_source = line_map_merging::KeyframeSource::kTf;  // every scan gated, none held
  line_map_merging::OnlineMapper mapper(line_map_merging::makeMerger("cae", params), mp);
  std::vector<std::pair<std::size_t, std::size_t>> order;  // (scans fed, trajectories fed)
  std::size_t scans = 0, trajectories = 0;
  OnlineDriveHooks hooks;
  hooks.scan = [&](std::size_t i, const line_map_merging::StampedScan& s)
  {
    ++scans;
    // Laser in map = map -> odom at the scan * odom * mount.
    EXPECT_TRUE(
        near(s.laser, sampleAt(schedule.map_to_odom, s.stamp) * rec.scans[i].odom * rec.base_to_laser));
  };
  hooks.trajectory = [&](std::size_t, const TrajectoryEmission& t)
  {
    ++trajectories;
    order.emplace_back(scans, trajectories);
    EXPECT_EQ(t.stamp, rec.scans[scans - 1].stamp);  // right after the scan it is stamped with
  };
  auto segments = [](std::size_t, const Pose2&)
  {
    return std::vector<linemap::Segment2>{
        linemap::Segment2(linemap::Vec2(1.0, -1.0), linemap::Vec2(1.0, 1.0))};
  };
  EXPECT_EQ(driveOnline(mapper, rec, schedule, segments, hooks), 3u);
  EXPECT_EQ(scans, 10u);
  ASSERT_EQ(order.size(), 3u);
  EXPECT_EQ(order[0].first, 4u);
  EXPECT_EQ(mapper.counters().trajectories, 3u);
  // Every scan moved 1 m >= the 0.5 m gate: every scan is a keyframe.
  EXPECT_EQ(mapper.keyframeStamps().size(), 10u);
}
