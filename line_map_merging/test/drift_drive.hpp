// Test fixture shared by the online mapper tests: a robot driving straight past a wall while its
// odometry drifts, and the back end's nodes at the true poses of scans that are no keyframes.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "line_map_merging/online/online_mapper.hpp"

namespace drift_drive
{
using line_map_merging::StampedPose;
using line_map_merging::StampedScan;
using linemap::Pose2;
using linemap::Vec2;

constexpr double kStep = 0.05;   // [m] per scan
constexpr double kDrift = 0.01;  // [rad] odometry heading error per scan
constexpr int kScans = 120;

/// A robot driving straight along x at one scan per 0.05 m; its odometry turns by kDrift per scan
/// (after 120 scans: 1.2 rad and metres of position error). Each scan sees a wall at y = 1.
struct Drive
{
  std::vector<double> stamps;
  std::vector<Pose2> truth, odom;  // base = laser (identity mount)

  Drive()
  {
    Pose2 t, o;
    for (int i = 0; i < kScans; ++i)
    {
      stamps.push_back(100.0 + 0.1 * i);
      truth.push_back(t);
      odom.push_back(o);
      t = t * Pose2(kStep, 0.0, 0.0);
      o = o * Pose2(kStep, 0.0, kDrift);
    }
  }

  /// Scan i posed in the map through `map_to_odom` (what tf map -> laser gives).
  StampedScan scan(int i, const Pose2& map_to_odom = Pose2()) const
  {
    StampedScan s;
    s.stamp = stamps[i];
    s.odom = odom[i];
    s.laser = map_to_odom * odom[i];
    const Pose2 inv = truth[i].inverse();
    s.segments.emplace_back(inv.apply(Vec2(truth[i].x - 1.0, 1.0)), inv.apply(Vec2(truth[i].x + 1.0, 1.0)));
    return s;
  }

  /// The back end's nodes: true poses of scans 2, 6, 10, ... (none of them a keyframe, see below).
  std::vector<StampedPose> nodes() const
  {
    std::vector<StampedPose> out;
    for (int i = 2; i < kScans; i += 4) out.emplace_back(stamps[i], truth[i]);
    return out;
  }
};

/// The nodes of `run` at or before scan `last`.
inline std::vector<StampedPose> nodesUpTo(const Drive& run, int last)
{
  std::vector<StampedPose> out;
  for (const auto& n : run.nodes())
    if (n.first <= run.stamps[last]) out.push_back(n);
  return out;
}

/// The same keyframes (stamps, poses) and map (ids, endpoints) to 1e-9, and with `counters` the same
/// scan and trajectory counters (made by the same calls).
inline void expectSameMap(const line_map_merging::OnlineMapper& a, const line_map_merging::OnlineMapper& b,
                          bool counters = true)
{
  EXPECT_EQ(a.keyframeStamps(), b.keyframeStamps());
  const auto ka = a.merger().keyframes(), kb = b.merger().keyframes();
  ASSERT_EQ(ka.size(), kb.size());
  for (std::size_t i = 0; i < ka.size(); ++i)
  {
    EXPECT_EQ(ka[i].stamp, kb[i].stamp);
    EXPECT_NEAR(ka[i].pose.x, kb[i].pose.x, 1e-9);
    EXPECT_NEAR(ka[i].pose.y, kb[i].pose.y, 1e-9);
    EXPECT_NEAR(ka[i].pose.theta, kb[i].pose.theta, 1e-9);
  }
  const auto ma = a.merger().map(), mb = b.merger().map();
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i)
  {
    EXPECT_EQ(ma[i].id, mb[i].id);
    EXPECT_LT((ma[i].segment.start - mb[i].segment.start).norm(), 1e-9);
    EXPECT_LT((ma[i].segment.end - mb[i].segment.end).norm(), 1e-9);
  }
  if (!counters) return;
  const auto &ca = a.counters(), &cb = b.counters();
  EXPECT_EQ(ca.trajectories, cb.trajectories);
  EXPECT_EQ(ca.adjustments, cb.adjustments);
  EXPECT_EQ(ca.scans, cb.scans);
  EXPECT_EQ(ca.below_gate, cb.below_gate);
  EXPECT_EQ(ca.dropped, cb.dropped);
}

}  // namespace drift_drive
