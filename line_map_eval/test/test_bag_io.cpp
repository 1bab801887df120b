// Bag writer and reader: a CARMEN prefix with its corrected keyframes, and a
// hand-made recording with closed-form map->odom values.
#include <gtest/gtest.h>
#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <stdlib.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <cmath>
#include <string>

#include "eval_test_helpers.hpp"
#include "line_map_eval/datasets/bag_reader.hpp"
#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"

using namespace line_map_eval;

namespace
{
const std::string kDatasets = LINEMAP_SOURCE_DIR "/../shared/datasets/";
constexpr double kPi = linemap::kPi;

using line_map_eval::test_helpers::TempDir;

double angleDiff(double a, double b)
{
  return std::remainder(a - b, 2.0 * kPi);
}

void expectPoseNear(const Pose2& a, const Pose2& b, double tol, const std::string& what)
{
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(angleDiff(a.theta, b.theta), 0.0, tol) << what;
}

/// The map->odom sample with exactly this stamp.
const Pose2* mapToOdomAt(const BagContents& bag, double stamp)
{
  for (const auto& [t, p] : bag.map_to_odom)
    if (t == stamp) return &p;
  return nullptr;
}
}  // namespace

TEST(BagIo, IntelPrefixRoundTrip)
{
  const std::string raw_path = kDatasets + "intel.clf.bz2",
                    corrected_path = kDatasets + "intel-corrected.log.gz";
  ASSERT_EQ(access(raw_path.c_str(), R_OK), 0) << "dataset file missing: " << raw_path;
  ASSERT_EQ(access(corrected_path.c_str(), R_OK), 0) << "dataset file missing: " << corrected_path;
  const CarmenLog raw = readCarmenLog(raw_path);
  const CarmenLog corrected = readCarmenLog(corrected_path);
  CarmenRecordingOptions rec_options;
  rec_options.max_scans = 1000;
  const Recording rec = fromCarmen(raw, &corrected, rec_options);
  const std::size_t n = rec.scans.size(), total = rec.keyframes.size();
  ASSERT_EQ(n, 1000u);
  // Keyframes among the first 1000 raw scans (the first one is raw scan 169).
  ASSERT_GT(total, 40u);
  ASSERT_NE(total % 20, 0u) << "pick a prefix whose keyframe count is not a multiple of N";

  TempDir dir;
  const std::string bag_path = dir.file("intel.bag");
  BagWriterOptions options;
  options.trajectory_every = 20;
  options.progress = false;
  BagWriteSummary summary;
  writeBag(rec, bag_path, options, &summary);
  const std::size_t emissions = (total + 19) / 20;
  EXPECT_EQ(summary.trajectory_emissions, emissions);
  EXPECT_EQ(summary.scans, n);

  const BagContents bag = readBag(bag_path);
  const Recording& back = bag.recording;

  // Scans: count, strictly increasing stamps equal to the recording's (ns resolution), ranges.
  ASSERT_EQ(back.scans.size(), n);
  for (std::size_t i = 0; i < n; ++i)
  {
    if (i > 0)
    {
      ASSERT_GT(back.scans[i].stamp, back.scans[i - 1].stamp) << i;
    }
    ASSERT_NEAR(back.scans[i].stamp, rec.scans[i].stamp, 1e-6) << i;
    ASSERT_EQ(back.scans[i].ranges, rec.scans[i].ranges) << i;
  }
  EXPECT_EQ(back.geometry.beam_count, 180u);
  EXPECT_NEAR(back.geometry.angle_increment, kPi / 180.0, 1e-7);
  EXPECT_NEAR(back.geometry.angle_min, -89.5 * kPi / 180.0, 1e-6);
  EXPECT_NEAR(back.geometry.range_max, 81.825, 1e-4);
  EXPECT_EQ(bag.scan_frame, "laser");

  // tf odom->base_link once per scan at its stamp, equal to the odometry.
  ASSERT_EQ(bag.odom_to_base.size(), n);
  for (std::size_t i = 0; i < n; ++i)
  {
    ASSERT_EQ(bag.odom_to_base[i].first, back.scans[i].stamp) << i;
    expectPoseNear(bag.odom_to_base[i].second, rec.scans[i].odom, 1e-9, "odom " + std::to_string(i));
  }
  // tf_static base_link->laser once.
  EXPECT_EQ(bag.static_transforms, 1u);
  expectPoseNear(back.base_to_laser, rec.base_to_laser, 1e-12, "base_to_laser");

  // map->odom at every scan stamp.
  ASSERT_EQ(bag.map_to_odom.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(bag.map_to_odom[i].first, back.scans[i].stamp) << i;

  // Trajectory emissions: k-th holds min(k*N, total) poses, each stamped with its scan's stamp.
  ASSERT_EQ(bag.trajectory.size(), emissions);
  for (std::size_t e = 0; e < emissions; ++e)
  {
    const TrajectoryEmission& em = bag.trajectory[e];
    const std::size_t expected = std::min((e + 1) * 20, total);
    ASSERT_EQ(em.poses.size(), expected) << "emission " << e;
    for (std::size_t j = 0; j < expected; ++j)
    {
      const std::size_t scan = rec.keyframes[j].scan_index;
      ASSERT_EQ(em.poses[j].first, back.scans[scan].stamp) << "emission " << e << " pose " << j;
      expectPoseNear(em.poses[j].second, rec.keyframes[j].pose, 1e-9, "path pose");
    }
    // Header stamp = stamp of the latest keyframe included.
    EXPECT_EQ(em.stamp, em.poses.back().first);
    // After the emission, map->odom maps the latest keyframe's odometry onto its corrected pose.
    const std::size_t latest = rec.keyframes[expected - 1].scan_index;
    const Pose2* m2o = mapToOdomAt(bag, em.stamp);
    ASSERT_NE(m2o, nullptr);
    expectPoseNear(*m2o * back.scans[latest].odom, rec.keyframes[expected - 1].pose, 1e-6, "map->odom");
    // ... and keeps that value until the next emission.
    const double next = e + 1 < emissions ? bag.trajectory[e + 1].stamp : back.scans.back().stamp + 1.0;
    for (const auto& [t, p] : bag.map_to_odom)
      if (t > em.stamp && t < next) expectPoseNear(p, *m2o, 1e-12, "map->odom held");
  }
  // Identity before the first emission.
  for (const auto& [t, p] : bag.map_to_odom)
    if (t < bag.trajectory.front().stamp) expectPoseNear(p, Pose2(), 0.0, "map->odom before first emission");

  // The reader's keyframes are the last emission's poses matched to scans.
  ASSERT_EQ(back.keyframes.size(), total);
  for (std::size_t k = 0; k < total; ++k)
    EXPECT_EQ(back.keyframes[k].scan_index, rec.keyframes[k].scan_index);

  // Every message is stored at its header stamp, and the topics are where the README says.
  rosbag::Bag b;
  b.open(bag_path, rosbag::bagmode::Read);
  std::size_t scans = 0, paths = 0, tfs = 0, statics = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(b))
  {
    if (const auto s = m.instantiate<sensor_msgs::LaserScan>())
    {
      ++scans;
      EXPECT_EQ(m.getTopic(), "/scan");
      EXPECT_EQ(s->header.stamp, m.getTime());
    }
    else if (const auto p = m.instantiate<nav_msgs::Path>())
    {
      ++paths;
      EXPECT_EQ(m.getTopic(), "/optimized_trajectory");
      EXPECT_EQ(p->header.frame_id, "map");
      EXPECT_EQ(p->header.stamp, m.getTime());
    }
    else if (const auto t = m.instantiate<tf2_msgs::TFMessage>())
    {
      (m.getTopic() == "/tf_static" ? statics : tfs) += 1;
      for (const auto& tr : t->transforms) EXPECT_EQ(tr.header.stamp, m.getTime());
    }
  }
  EXPECT_EQ(scans, n);
  EXPECT_EQ(paths, emissions);
  EXPECT_EQ(tfs, n);
  EXPECT_EQ(statics, 1u);
}

TEST(BagIo, ClosedFormMapToOdom)
{
  // Three scans, every scan a keyframe, trajectory every 2: emissions after keyframes 2 and 3.
  Recording rec;
  rec.geometry = carmenBeamGeometry(4, 10.0);
  rec.base_to_laser = Pose2(0.2, 0.0, 0.0);
  const Pose2 odom[3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, kPi / 2}};
  const Pose2 corrected[3] = {{0, 0, 0}, {2, 1, kPi / 2}, {0, 1, kPi}};
  for (int i = 0; i < 3; ++i)
  {
    rec.scans.push_back({100.0 + 0.5 * i, {1.f, 2.f, 3.f, 4.f}, odom[i]});
    rec.keyframes.push_back({static_cast<std::size_t>(i), corrected[i]});
  }
  TempDir dir;
  BagWriterOptions options;
  options.trajectory_every = 2;
  options.progress = false;
  options.compression = "lz4";
  writeBag(rec, dir.file("small.bag"), options);
  const BagContents bag = readBag(dir.file("small.bag"));
  ASSERT_EQ(bag.trajectory.size(), 2u);
  EXPECT_EQ(bag.trajectory[0].poses.size(), 2u);
  EXPECT_EQ(bag.trajectory[1].poses.size(), 3u);
  EXPECT_DOUBLE_EQ(bag.trajectory[0].stamp, 100.5);
  EXPECT_DOUBLE_EQ(bag.trajectory[1].stamp, 101.0);
  ASSERT_EQ(bag.map_to_odom.size(), 3u);
  // Before any emission: identity. At 100.5: (2,1,pi/2) * (1,0,0)^-1 = (2,0,pi/2).
  // At 101.0: (0,1,pi) * (1,1,pi/2)^-1; (1,1,pi/2)^-1 = (-1,1,-pi/2) -> (0+1, 1-1, pi/2) = (1,0,pi/2).
  expectPoseNear(bag.map_to_odom[0].second, Pose2(0, 0, 0), 1e-12, "t=100");
  expectPoseNear(bag.map_to_odom[1].second, Pose2(2, 0, kPi / 2), 1e-12, "t=100.5");
  expectPoseNear(bag.map_to_odom[2].second, Pose2(1, 0, kPi / 2), 1e-12, "t=101");
  expectPoseNear(bag.recording.base_to_laser, Pose2(0.2, 0, 0), 1e-12, "mount");
  EXPECT_NEAR(bag.recording.geometry.range_max, 9.995, 1e-6);
}

TEST(BagIo, ErrorsNameTheFile)
{
  Recording rec;
  rec.geometry = carmenBeamGeometry(2, 10.0);
  rec.scans.push_back({1.0, {1.f, 2.f}, Pose2()});
  BagWriterOptions options;
  options.progress = false;
  const std::string nowhere = "/nonexistent_dir_for_test/out.bag";
  try
  {
    writeBag(rec, nowhere, options);
    ADD_FAILURE() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(nowhere), std::string::npos) << e.what();
  }
  TempDir dir;
  // Stamps that do not increase are refused.
  rec.scans.push_back({1.0, {1.f, 2.f}, Pose2()});
  EXPECT_THROW(writeBag(rec, dir.file("a.bag"), options), std::runtime_error);
  try
  {
    readBag(dir.file("missing.bag"));
    ADD_FAILURE() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("missing.bag"), std::string::npos) << e.what();
  }
}

// A bag of scans alone (no /tf at all), as a user records with `rosbag record scan`: it is read with no
// odometry (every scan's at the identity, odometry false) and the laser at base_link, not refused.
TEST(BagIo, ScansAloneAreReadWithoutOdometry)
{
  TempDir dir;
  const std::string path = dir.file("scans.bag");
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (int i = 0; i < 3; ++i)
    {
      sensor_msgs::LaserScan scan;
      scan.header.stamp = ros::Time(100.0 + 0.2 * i);
      scan.header.frame_id = "laser";
      scan.angle_min = -1.0f;
      scan.angle_increment = 0.5f;
      scan.angle_max = 1.0f;
      scan.range_min = 0.1f;
      scan.range_max = 10.0f;
      scan.ranges = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
      bag.write("/scan", scan.header.stamp, scan);
    }
  }
  const BagContents bag = readBag(path);
  EXPECT_FALSE(bag.odometry);
  ASSERT_EQ(bag.recording.scans.size(), 3u);
  for (const auto& scan : bag.recording.scans) expectPoseNear(scan.odom, Pose2(), 0.0, "odometry");
  expectPoseNear(bag.recording.base_to_laser, Pose2(), 0.0, "mounting");
  EXPECT_NEAR(bag.recording.scans[2].stamp, 100.4, 1e-9);
}
