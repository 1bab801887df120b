// runLocalization (localization_recording.hpp): a recording driven through an L-shaped room, localized
// from its first pose and by global localization, whose earlier scans are then re-localized too.
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_eval/datasets/localization_recording.hpp"

using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;
using namespace line_map_eval;

namespace
{
std::vector<Segment2> lRoom()
{
  const std::vector<Vec2> c{{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 8}, {0, 8}};
  std::vector<Segment2> s;
  for (std::size_t i = 0; i < c.size(); ++i) s.push_back({c[i], c[(i + 1) % c.size()]});
  return s;
}

float castRay(const std::vector<Segment2>& world, const Vec2& o, double angle, double max_range)
{
  const Vec2 d(std::cos(angle), std::sin(angle));
  double best = max_range;
  for (const auto& s : world)
  {
    const Vec2 e = s.end - s.start, w = s.start - o;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::fabs(den) < 1e-12) continue;
    const double t = (w.x() * e.y() - w.y() * e.x()) / den, u = (w.x() * d.y() - w.y() * d.x()) / den;
    if (t > 1e-9 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return static_cast<float>(best);
}

Pose2 truth(std::size_t i)
{
  return {1.5 + 0.1 * static_cast<double>(i), 2.0, 0.0};
}

// 60 scans along the lower arm, 360 beams, odometry exact and starting at the identity; the laser sits
// 0.2 m ahead of the base.
Recording drive()
{
  Recording r;
  r.geometry = {-linemap::kPi, 2.0 * linemap::kPi / 360.0, 360, 0.1, 20.0};
  r.base_to_laser = {0.2, 0.0, 0.0};
  for (std::size_t i = 0; i < 60; ++i)
  {
    RecordedScan s;
    s.stamp = 0.2 * static_cast<double>(i + 1);
    s.odom = truth(0).inverse() * truth(i);
    const Pose2 laser = truth(i) * r.base_to_laser;
    for (std::size_t b = 0; b < 360; ++b)
      s.ranges.push_back(castRay(
          lRoom(), laser.translation(),
          laser.theta + r.geometry.angle_min + static_cast<double>(b) * r.geometry.angle_increment, 20.0));
    r.scans.push_back(s);
  }
  return r;
}
}  // namespace

TEST(LocalizationRecording, ScanPointsAreInTheBaseFrame)
{
  const Recording r = drive();
  const auto scan = localizerScan(r, 0);
  EXPECT_EQ(scan.points.size(), 360u);
  EXPECT_NEAR(scan.sensor.x(), 0.2, 1e-12);
  // The beam straight back (angle -pi) from the laser at x = 1.7 meets the wall x = 0: 1.7 m, i.e.
  // 1.5 m behind the base.
  EXPECT_NEAR(scan.points.front().x(), -1.5, 1e-5);
  EXPECT_NEAR(scan.points.front().y(), 0.0, 1e-5);
}

TEST(LocalizationRecording, FromTheFirstPoseAndByGlobalLocalization)
{
  const Recording r = drive();
  const line_map_merging::LocalizerParams params;
  const auto tracked = runLocalization(r, lRoom(), params, Pose2(1.52, 1.97, 0.02));
  ASSERT_EQ(tracked.scan_poses.size(), 60u);
  for (std::size_t i = 0; i < 60; ++i)
  {
    EXPECT_LT(std::hypot(tracked.scan_poses[i].x - truth(i).x, tracked.scan_poses[i].y - truth(i).y), 1e-3)
        << i;
    EXPECT_TRUE(tracked.localized[i]);
  }
  EXPECT_FALSE(tracked.recovered_at);

  // Without an initial pose: accepted after accept_travel (2 m, 20 scans), and then every scan from the
  // first is localized again from the accepted pose carried back by the odometry.
  const auto global = runLocalization(r, lRoom(), params, std::nullopt);
  ASSERT_TRUE(global.recovered_at);
  EXPECT_GE(*global.recovered_at, 20u);
  EXPECT_LT(*global.recovered_at, 60u);
  ASSERT_EQ(global.scan_poses.size(), 60u);
  for (std::size_t i = 0; i < 60; ++i)
    EXPECT_LT(std::hypot(global.scan_poses[i].x - truth(i).x, global.scan_poses[i].y - truth(i).y), 1e-3)
        << i;
}
