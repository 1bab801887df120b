// CARMEN reader, keyframe pairing, beam geometry and the Recording built from the logs.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <boost/iostreams/copy.hpp>
#include <boost/iostreams/filter/bzip2.hpp>
#include <boost/iostreams/filter/gzip.hpp>
#include <boost/iostreams/filtering_stream.hpp>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "eval_test_helpers.hpp"
#include "line_map_eval/batch/progress.hpp"
#include "line_map_eval/datasets/bag_reader.hpp"
#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"

using namespace line_map_eval;

namespace
{
const std::string kDatasets = LINEMAP_SOURCE_DIR "/../shared/datasets/";
constexpr double kPi = linemap::kPi;

/// Path of a dataset file; records a failure naming it when it is missing.
bool dataset(const std::string& name, std::string& path)
{
  path = kDatasets + name;
  if (access(path.c_str(), R_OK) == 0) return true;
  ADD_FAILURE() << "dataset file missing: " << path << " (see ../shared/datasets/README.md)";
  return false;
}

using line_map_eval::test_helpers::TempDir;

/// A valid 3-beam FLASER line.
std::string flaser(double t, double x = 0.0)
{
  std::ostringstream s;
  s << "FLASER 3 1.5 2.25 3 " << x << " 0 0 " << x << " 0 0 " << t << " host " << t;
  return s.str();
}

/// Error message of reading `content` (line `bad_line` is the bad one), or "" when it parsed.
std::string errorOf(const TempDir& dir, const std::string& content)
{
  const std::string p = dir.write("bad.clf", content);
  try
  {
    readCarmenLog(p);
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

std::string compress(const std::string& text, bool gzip)
{
  namespace io = boost::iostreams;
  std::string out;
  io::filtering_ostream stream;
  if (gzip)
    stream.push(io::gzip_compressor());
  else
    stream.push(io::bzip2_compressor());
  stream.push(io::back_inserter(out));
  stream << text;
  stream.reset();
  return out;
}
}  // namespace

TEST(CarmenLog, DatasetsParseWithTheDocumentedCounts)
{
  struct Expect
  {
    const char* file;
    std::size_t scans;
    std::size_t beams;
  };
  for (const Expect e : {Expect{"intel.clf.bz2", 13631, 180}, Expect{"intel-corrected.log.gz", 910, 180},
                         Expect{"aces.clf.bz2", 7374, 180}, Expect{"aces-corrected.log.gz", 440, 180},
                         Expect{"mit-csail.clf.bz2", 1988, 361}, Expect{"csail-corrected.log.gz", 406, 361}})
  {
    std::string path;
    if (!dataset(e.file, path)) continue;
    const CarmenLog log = readCarmenLog(path);
    EXPECT_EQ(log.scans.size(), e.scans) << e.file;
    EXPECT_EQ(log.skipped_bad, 0u) << e.file;
    for (const CarmenScan& s : log.scans) ASSERT_EQ(s.ranges.size(), e.beams) << e.file << " line " << s.line;
  }
}

TEST(CarmenLog, IntelRawLogContent)
{
  std::string path;
  if (!dataset("intel.clf.bz2", path)) return;
  const CarmenLog log = readCarmenLog(path);
  // README: FLASER + ODOM, robot_frontlaser_offset 0.0; header values checked by hand with bzcat | head.
  EXPECT_EQ(log.odometry.size(), 26915u);
  ASSERT_EQ(log.params.count("robot_frontlaser_offset"), 1u);
  EXPECT_EQ(log.params.at("robot_frontlaser_offset"), "0.0");
  const CarmenScan& first = log.scans.front();
  EXPECT_EQ(first.type, CarmenScanType::FLaser);
  EXPECT_NEAR(first.timestamp, 976052857.337530, 1e-6);
  EXPECT_NEAR(first.logger_timestamp, 0.000246, 1e-9);
  EXPECT_NEAR(first.robot_pose.theta, -0.002458, 1e-12);
  EXPECT_NEAR(log.odometry.front().timestamp, 976052857.337284, 1e-6);
}

TEST(CarmenLog, CorruptLinesNameFileAndLine)
{
  TempDir dir;
  const std::string head = "# comment\nPARAM robot_frontlaser_offset 0.0 nohost 0\n" + flaser(1.0) + "\n";
  // The bad line is line 4 in every case.
  struct Case
  {
    std::string line;
    std::string expect;
  };
  const std::string long_line = "FLASER 3 1 2 3 0 0 0 0 0 0 1 host 1 " + std::string(70000, ' ');
  for (const Case& c : {Case{"FLASER 180 1.0 2.0 3.0", "FLASER: expected 180 ranges"},
                        Case{"FLASER 3 1.0 abc 2.0 0 0 0 0 0 0 2.0 host 2.0", "'abc'"},
                        Case{"FLASER 4 1 2 3 0 0 0 0 0 0 2.0 host 2.0", "expected 4 ranges, got 3"},
                        Case{"FLASER 2 1 2 3 0 0 0 0 0 0 2.0 host 2.0", "expected 2 ranges, got 3"},
                        Case{"FLASER x 1 2 0 0 0 0 0 0 2.0 host 2.0", "num_readings"},
                        Case{"ODOM 0 0 0 0 0 2.0 host", "ODOM"}, Case{long_line, "longer than"},
                        Case{"ROBOTLASER1 0 -1.57 3.14 0.0175 81.9 0.01 0 3 1 2 3 0 0 0 0", "ROBOTLASER1"}})
  {
    const std::string msg = errorOf(dir, head + c.line + "\n" + flaser(3.0) + "\n");
    EXPECT_NE(msg.find("bad.clf:4: "), std::string::npos) << "got: " << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
  }
  // 1-based numbering: a bad first line is line 1.
  EXPECT_NE(errorOf(dir, "FLASER 3 1 2\n").find("bad.clf:1: "), std::string::npos);

  // Lenient mode drops the bad line, counts it and keeps the rest.
  const std::string p = dir.write("lenient.clf", head + "FLASER 3 1 2\n" + flaser(3.0) + "\n");
  CarmenReadOptions lenient;
  lenient.lenient = true;
  const CarmenLog log = readCarmenLog(p, lenient);
  EXPECT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(log.skipped_bad, 1u);
  ASSERT_EQ(log.problems.size(), 1u);
  EXPECT_NE(log.problems[0].find("lenient.clf:4: "), std::string::npos);
  EXPECT_EQ(log.scans[1].line, 5u);

  EXPECT_THROW(readCarmenLog(dir.path() + "/does_not_exist.clf"), std::runtime_error);
  // A file that claims to be bzip2 but is not.
  const std::string fake = dir.write("fake.clf.bz2", "BZh9 this is not bzip2 data at all");
  try
  {
    readCarmenLog(fake);
    ADD_FAILURE() << "corrupt bzip2 accepted";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("fake.clf.bz2"), std::string::npos) << e.what();
  }
}

TEST(CarmenLog, ParsesEveryField)
{
  TempDir dir;
  const std::string text =
      "ODOM 1 2 0.5 0.3 0.1 0.05 100.25 host 0.5\n"
      "NEFF 27.6 0 pippo 0\nRLASER 1 2 0 0 0 0 0 0 0 host 0\n"
      "FLASER 3 1.5 2.25 81.83 0.1 0.2 0.3 1.1 1.2 1.3 100.5 host 0.75\n"
      "ROBOTLASER1 0 -1.5 0.04 0.02 81.9 0.01 0 3 4.5 5.5 6.5 2 0.25 0.75 "
      "1.2 2.0 0.0 1.0 2.0 0.0 0.4 0.1 0.5 0.6 0.7 101.0 b21 1.25\n";
  const CarmenLog log = readCarmenLog(dir.write("fields.clf", text));
  EXPECT_EQ(log.skipped_unknown, 2u);  // NEFF, RLASER
  ASSERT_EQ(log.odometry.size(), 1u);
  EXPECT_DOUBLE_EQ(log.odometry[0].pose.y, 2.0);
  EXPECT_DOUBLE_EQ(log.odometry[0].accel, 0.05);
  EXPECT_DOUBLE_EQ(log.odometry[0].timestamp, 100.25);
  ASSERT_EQ(log.scans.size(), 2u);
  const CarmenScan& f = log.scans[0];
  EXPECT_EQ(f.ranges, (std::vector<float>{1.5f, 2.25f, 81.83f}));
  EXPECT_DOUBLE_EQ(f.laser_pose.theta, 0.3);
  EXPECT_DOUBLE_EQ(f.robot_pose.x, 1.1);
  EXPECT_DOUBLE_EQ(f.logger_timestamp, 0.75);
  EXPECT_EQ(f.line, 4u);
  const CarmenScan& r = log.scans[1];
  EXPECT_EQ(r.type, CarmenScanType::RobotLaser1);
  EXPECT_DOUBLE_EQ(r.start_angle, -1.5);
  EXPECT_DOUBLE_EQ(r.field_of_view, 0.04);
  EXPECT_DOUBLE_EQ(r.angular_resolution, 0.02);
  EXPECT_DOUBLE_EQ(r.max_range, 81.9);
  EXPECT_EQ(r.ranges, (std::vector<float>{4.5f, 5.5f, 6.5f}));
  EXPECT_EQ(r.remissions, (std::vector<float>{0.25f, 0.75f}));
  EXPECT_DOUBLE_EQ(r.laser_pose.x, 1.2);
  EXPECT_DOUBLE_EQ(r.robot_pose.x, 1.0);
  EXPECT_DOUBLE_EQ(r.tv, 0.4);
  EXPECT_DOUBLE_EQ(r.turn_axis, 0.7);
  EXPECT_DOUBLE_EQ(r.timestamp, 101.0);
  EXPECT_DOUBLE_EQ(r.logger_timestamp, 1.25);

  // ROBOTLASER1 geometry comes from its own fields; the mounting from laser vs robot pose.
  CarmenLog only_robot = log;
  only_robot.scans.erase(only_robot.scans.begin());
  const Recording rec = fromCarmen(only_robot, nullptr);
  EXPECT_DOUBLE_EQ(rec.geometry.angle_min, -1.5);
  EXPECT_DOUBLE_EQ(rec.geometry.angle_increment, 0.02);
  EXPECT_NEAR(rec.geometry.range_max, 81.895, 1e-12);
  EXPECT_NEAR(rec.base_to_laser.x, 0.2, 1e-12);
  EXPECT_NEAR(rec.base_to_laser.y, 0.0, 1e-12);
}

/// A ROBOTLASER1 line: geometry, ranges, laser and robot pose, time t (no remissions).
std::string robotLaser(double start, double fov, double res, double max_range,
                       const std::vector<double>& ranges, const Pose2& laser, const Pose2& robot, double t)
{
  std::ostringstream s;
  s.precision(17);
  s << "ROBOTLASER1 0 " << start << " " << fov << " " << res << " " << max_range << " 0.01 0 "
    << ranges.size();
  for (const double r : ranges) s << " " << r;
  s << " 0 " << laser.x << " " << laser.y << " " << laser.theta << " " << robot.x << " " << robot.y << " "
    << robot.theta << " 0 0 0 0 0 " << t << " host " << t - 100.0;
  return s.str();
}

/// Three ROBOTLASER1 lines, the middle one with another start angle, beam count and maximum range
/// (as interlaced scans of a SICK LMS): geometry A = 3 beams from -90 deg, 90 deg apart, no return
/// 10 m; B = 2 beams from -45 deg, 90 deg apart, no return 12 m. The laser sits 0.22 m ahead of the robot.
std::string alternatingLog()
{
  const double s2 = std::sqrt(2.0);
  return robotLaser(-kPi / 2, kPi, kPi / 2, 10.0, {1, 2, 3}, {0.22, 0, 0}, {0, 0, 0}, 100.0) + "\n" +
         robotLaser(-kPi / 4, kPi, kPi / 2, 12.0, {s2, s2}, {1, 2.22, kPi / 2}, {1, 2, kPi / 2}, 101.0) +
         "\n" + robotLaser(-kPi / 2, kPi, kPi / 2, 10.0, {4, 5, 6}, {1.78, 0, kPi}, {2, 0, kPi}, 102.0) +
         "\n";
}

void expectGeometry(const ScanGeometry& g, double angle_min, double increment, std::size_t beams,
                    double range_max)
{
  EXPECT_NEAR(g.angle_min, angle_min, 1e-12);
  EXPECT_NEAR(g.angle_increment, increment, 1e-12);
  EXPECT_EQ(g.beam_count, beams);
  EXPECT_NEAR(g.range_max, range_max, 1e-12);
  EXPECT_EQ(g.range_min, 0.0);
}

TEST(CarmenRecording, RobotLaser1GeometryIsReadScanByScan)
{
  TempDir dir;
  const CarmenLog log = readCarmenLog(dir.write("alternating.clf", alternatingLog()));
  ASSERT_EQ(log.scans.size(), 3u);
  EXPECT_EQ(log.scans[1].ranges.size(), 2u);
  EXPECT_NEAR(log.scans[1].start_angle, -kPi / 4, 1e-15);
  EXPECT_DOUBLE_EQ(log.scans[1].max_range, 12.0);

  CarmenRecordingReport report;
  const Recording rec = fromCarmen(log, nullptr, {}, &report);
  ASSERT_EQ(rec.scans.size(), 3u);
  // The recording's geometry is the first scan's; only the scan that differs carries its own.
  expectGeometry(rec.geometry, -kPi / 2, kPi / 2, 3, 9.995);
  EXPECT_FALSE(rec.scans[0].geometry.has_value());
  ASSERT_TRUE(rec.scans[1].geometry.has_value());
  expectGeometry(rec.geometryOf(rec.scans[1]), -kPi / 4, kPi / 2, 2, 11.995);
  EXPECT_FALSE(rec.scans[2].geometry.has_value());
  EXPECT_EQ(report.geometries, 2u);
  EXPECT_DOUBLE_EQ(report.no_return_range, 10.0);

  // Odometry = the robot pose of each line; mounting = laser relative to robot pose, the same on every line.
  EXPECT_EQ(report.odometry_source, "scan odometry fields");
  EXPECT_NEAR(rec.scans[1].odom.x, 1.0, 1e-15);
  EXPECT_NEAR(rec.scans[1].odom.y, 2.0, 1e-15);
  EXPECT_NEAR(rec.scans[2].odom.theta, kPi, 1e-15);
  EXPECT_NEAR(rec.base_to_laser.x, 0.22, 1e-12);
  EXPECT_NEAR(rec.base_to_laser.y, 0.0, 1e-12);
  EXPECT_NEAR(rec.base_to_laser.theta, 0.0, 1e-12);
  EXPECT_LT(report.max_mounting_shift, 1e-12);
  EXPECT_LT(report.max_mounting_turn, 1e-12);

  // The scans' points in the world, every scan under its own geometry (computed by hand: laser pose =
  // robot pose + 0.22 m ahead, beam angles start + i * 90 deg).
  Recording posed = rec;
  for (std::size_t i = 0; i < posed.scans.size(); ++i) posed.keyframes.push_back({i, posed.scans[i].odom});
  const std::vector<Vec2> points = registeredScanPoints(posed);
  const std::vector<std::pair<double, double>> expected = {{0.22, -1}, {2.22, 0}, {0.22, 3},  {2, 3.22},
                                                           {0, 3.22},  {1.78, 4}, {-3.22, 0}, {1.78, -6}};
  ASSERT_EQ(points.size(), expected.size());
  for (std::size_t i = 0; i < points.size(); ++i)
  {
    EXPECT_NEAR(points[i].x(), expected[i].first, 1e-6) << i;  // ranges are floats
    EXPECT_NEAR(points[i].y(), expected[i].second, 1e-6) << i;
  }
}

TEST(CarmenRecording, FlaserBeamCountMayChangeToo)
{
  TempDir dir;
  const CarmenLog log = readCarmenLog(
      dir.write("f.clf", flaser(1.0) + "\nFLASER 4 1 2 3 4 0 0 0 0 0 0 2.0 host 2.0\n" + flaser(3.0) + "\n"));
  CarmenRecordingOptions options;
  options.no_return_range = 10.0;
  const Recording rec = fromCarmen(log, nullptr, options);
  expectGeometry(rec.geometry, -kPi / 2, kPi / 2, 3, 9.995);
  expectGeometry(rec.geometryOf(rec.scans[1]), -3 * kPi / 8, kPi / 4, 4, 9.995);  // pi/n for even n
  EXPECT_FALSE(rec.scans[2].geometry.has_value());
}

TEST(CarmenRecording, VaryingGeometryReachesEveryLaserScanOfTheBag)
{
  TempDir dir;
  const Recording rec = fromCarmen(readCarmenLog(dir.write("alternating.clf", alternatingLog())), nullptr);
  BagWriterOptions options;
  options.progress = false;
  const std::string path = dir.path() + "/alternating.bag";
  writeBag(rec, path, options);

  std::vector<sensor_msgs::LaserScan> scans;
  {
    rosbag::Bag bag(path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/scan")))
      scans.push_back(*m.instantiate<sensor_msgs::LaserScan>());
  }
  ASSERT_EQ(scans.size(), 3u);
  const float a = static_cast<float>(-kPi / 2), b = static_cast<float>(-kPi / 4);
  const float step = static_cast<float>(kPi / 2);
  for (const std::size_t i : {0u, 2u})
  {
    EXPECT_EQ(scans[i].ranges.size(), 3u);
    EXPECT_EQ(scans[i].angle_min, a);
    EXPECT_EQ(scans[i].angle_increment, step);
    EXPECT_NEAR(scans[i].angle_max, kPi / 2, 1e-6);
    EXPECT_FLOAT_EQ(scans[i].range_max, 9.995f);
  }
  EXPECT_EQ(scans[1].ranges.size(), 2u);
  EXPECT_EQ(scans[1].angle_min, b);
  EXPECT_EQ(scans[1].angle_increment, step);
  EXPECT_NEAR(scans[1].angle_max, kPi / 4, 1e-6);
  EXPECT_FLOAT_EQ(scans[1].range_max, 11.995f);

  // Read back, the scan keeps its own geometry.
  const Recording back = readBag(path).recording;
  ASSERT_EQ(back.scans.size(), 3u);
  EXPECT_EQ(back.geometry.beam_count, 3u);
  EXPECT_FALSE(back.scans[2].geometry.has_value());
  ASSERT_TRUE(back.scans[1].geometry.has_value());
  EXPECT_EQ(back.scans[1].geometry->beam_count, 2u);
  EXPECT_NEAR(back.scans[1].geometry->angle_min, -kPi / 4, 1e-6);
}

TEST(CarmenLog, BeamCountMustFitTheFieldOfView)
{
  TempDir dir;
  const std::string first = robotLaser(-kPi / 2, kPi, kPi / 2, 10.0, {1, 2, 3}, {}, {}, 100.0) + "\n";
  // pi at pi/2 holds 2 (interlaced) or 3 beams; line 3 has 4.
  const std::string msg = errorOf(
      dir, first + "# x\n" + robotLaser(-kPi / 2, kPi, kPi / 2, 10.0, {1, 2, 3, 4}, {}, {}, 101.0) + "\n");
  EXPECT_NE(msg.find("bad.clf:3: ROBOTLASER1: num_readings (field 9) is 4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("(fields 4, 5) holds 2 or 3 beams"), std::string::npos) << msg;
  EXPECT_NE(errorOf(dir, robotLaser(-kPi / 2, kPi, kPi / 2, 10.0, {1}, {}, {}, 100.0)).find("bad.clf:1: "),
            std::string::npos);
  // 180 deg at 1 deg: 180 or 181 beams (the two geometries of fr-clinic), not 179 or 182.
  for (const std::size_t n : {179u, 180u, 181u, 182u})
  {
    const std::vector<double> ranges(n, 1.0);
    const std::string e =
        errorOf(dir, robotLaser(-1.570796, 3.141593, 0.017453, 81.9, ranges, {}, {}, 1.0) + "\n");
    EXPECT_EQ(e.empty(), n == 180 || n == 181) << n << ": " << e;
  }

  struct Case
  {
    std::string line;
    std::string expect;
  };
  for (const Case& c :
       {Case{"RAWLASER1 0 -1.5707963 3.1415927 1.5707963 10 0.01 0 3 1 2 3 0 5 host",
             "expected 3 ranges, got 2"},
        Case{"RAWLASER2 0 -1.5707963 3.1415927 1.5707963 10 0.01 0 3 1 x 3 0 5 host 5",
             "RAWLASER2: ranges (field 11) is not a number: 'x'"},
        Case{"RAWLASER3 0 -1.5707963 3.1415927 0 10 0.01 0 3 1 2 3 0 5 host 5",
             "RAWLASER3: angular_resolution (field 5) must be positive"},
        Case{"RAWLASER4 0 -1.5707963 3.1415927 1.5707963 10 0.01 0 3 1 2 3 2 7 5 host 5",
             "RAWLASER4: expected 2 remissions, got 1"},
        Case{"ROBOTLASER1 0 -1.5707963 nan 1.5707963 10 0.01 0 3 1 2 3 0 0 0 0 0 0 0 0 0 0 0 0 5 host 5",
             "field_of_view (field 4) is not a number: 'nan'"}})
  {
    const std::string e = errorOf(dir, first + c.line + "\n");
    EXPECT_NE(e.find("bad.clf:2: "), std::string::npos) << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << "got: " << e;
  }
}

TEST(CarmenRecording, RawLaserOdometryFromOdomLines)
{
  TempDir dir;
  // No pose on RAWLASER lines: ODOM interpolated at the scan stamp (t = 11 is halfway from 10 to 12).
  const std::string text =
      "PARAM robot_frontlaser_offset 0.1 nohost 0\n"
      "ODOM 0 0 0 0 0 0 10.0 h 0\nODOM 2 0 0.2 0 0 0 12.0 h 0\n"
      "RAWLASER1 0 -1.5707963267948966 3.1415926535897931 1.5707963267948966 10 0.01 0 3 1 2 3 0 11.0 h 1\n"
      "RAWLASER1 0 -0.78539816339744828 3.1415926535897931 1.5707963267948966 20 0.01 0 2 1 1 2 0.5 0.75 "
      "11.5 h 1.5\n";
  const CarmenLog log = readCarmenLog(dir.write("raw.clf", text));
  ASSERT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(log.scans[0].type, CarmenScanType::RawLaser);
  EXPECT_EQ(log.scans[1].raw_laser, 1);
  EXPECT_EQ(log.scans[1].remissions, (std::vector<float>{0.5f, 0.75f}));
  EXPECT_DOUBLE_EQ(log.scans[1].timestamp, 11.5);
  EXPECT_DOUBLE_EQ(log.scans[1].logger_timestamp, 1.5);

  CarmenRecordingReport report;
  const Recording rec = fromCarmen(log, nullptr, {}, &report);
  EXPECT_EQ(report.odometry_source, "ODOM lines");
  EXPECT_NEAR(rec.scans[0].odom.x, 1.0, 1e-12);
  EXPECT_NEAR(rec.scans[0].odom.theta, 0.1, 1e-12);
  EXPECT_NEAR(rec.scans[1].odom.x, 1.5, 1e-12);
  EXPECT_NEAR(rec.scans[1].odom.theta, 0.15, 1e-12);
  EXPECT_NEAR(rec.base_to_laser.x, 0.1, 1e-15);  // RAWLASER1 is the front laser
  expectGeometry(rec.geometry, -kPi / 2, kPi / 2, 3, 9.995);
  expectGeometry(rec.geometryOf(rec.scans[1]), -kPi / 4, kPi / 2, 2, 19.995);

  // RAWLASER2 (another laser): not the front laser's offset; with no ODOM lines no odometry at all.
  const CarmenLog rear = readCarmenLog(dir.write(
      "rear.clf",
      "PARAM robot_frontlaser_offset 0.1 nohost 0\n"
      "RAWLASER2 0 -1.5707963267948966 3.1415926535897931 1.5707963267948966 10 0.01 0 3 1 2 3 0 11 h 1\n"));
  const Recording rear_rec = fromCarmen(rear, nullptr, {}, &report);
  EXPECT_EQ(rear_rec.base_to_laser.x, 0.0);
  EXPECT_EQ(rear_rec.scans[0].odom.x, 0.0);
  EXPECT_NE(report.odometry_source.find("no ODOM lines"), std::string::npos) << report.odometry_source;

  // Two lasers in one log: refused, naming the line.
  const CarmenLog two =
      readCarmenLog(dir.write("two.clf", text + "RAWLASER2 0 -1.5707963267948966 "
                                                "3.1415926535897931 1.5707963267948966 10 0.01 0 3 "
                                                "1 2 3 0 12 h 2\n"));
  try
  {
    fromCarmen(two, nullptr);
    ADD_FAILURE() << "two lasers accepted";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("two.clf:6: RAWLASER2 after RAWLASER1"), std::string::npos)
        << e.what();
  }
}

// A corrected log of keyframes: the FLASER pose fields are the corrected poses of a robot speeding up along
// x, x(t) = (t - 10)^2; the ODOM lines, every 0.1 s, report the pose 0.3 s old (the ODOM line stamped tau
// holds x(tau - 0.3)). The odometry agrees with the poses' steps only interpolated at a scan's stamp plus
// 0.3 s (there the interpolation hits ODOM samples exactly); without the option the pose fields are the
// odometry.
TEST(CarmenRecording, CorrectedLogOdometryFromItsOdomLinesAtTheFittedDelay)
{
  TempDir dir;
  const auto x = [](double t) { return (t - 10.0) * (t - 10.0); };
  std::ostringstream text;
  text.precision(17);
  for (int i = 0; i <= 100; ++i)
  {
    const double tau = 9.5 + 0.1 * i;
    text << "ODOM " << x(tau - 0.3) << " 0 0 0 0 0 " << tau << " h " << tau << "\n";
  }
  for (const double t : {10.5, 11.6, 12.7, 13.8, 14.9, 16.0, 17.1, 18.2})
    text << "FLASER 3 1.5 2.25 3 " << x(t) << " 0 0 " << x(t) << " 0 0 " << t << " host " << t << "\n";
  const CarmenLog log = readCarmenLog(dir.write("corrected.clf", text.str()));
  EXPECT_NEAR(fitOdometryDelay(log, 0.5, 0.01), 0.3, 1e-9);

  CarmenRecordingOptions options;
  options.odometry_from_odom_lines = true;
  options.odometry_delay = 0.3;
  CarmenRecordingReport report;
  const Recording rec = fromCarmen(log, nullptr, options, &report);
  EXPECT_EQ(report.odometry_source, "ODOM lines");
  ASSERT_EQ(rec.scans.size(), 8u);
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
    EXPECT_NEAR(rec.scans[i].odom.x, x(log.scans[i].timestamp), 1e-9) << "scan " << i;
  EXPECT_EQ(fromCarmen(log, nullptr, {}, &report).scans[3].odom.x, x(13.8));
  EXPECT_EQ(report.odometry_source, "scan odometry fields");
}

TEST(CarmenRecording, FrClinicAlternatesTwoGeometries)
{
  std::string path;
  if (!dataset("fr-clinic.clf.bz2", path)) return;
  CarmenReadOptions first40;
  first40.max_scans = 40;
  const CarmenLog log = readCarmenLog(path, first40);
  ASSERT_EQ(log.scans.size(), 40u);
  // README and `bzcat | head -40`: 181 beams from -90 deg, 180 beams from -89.75, -89.5 or -89.25 deg,
  // 1 deg apart over a 180 deg field of view.
  std::set<double> starts181, starts180;
  for (const CarmenScan& s : log.scans)
  {
    ASSERT_EQ(s.type, CarmenScanType::RobotLaser1);
    EXPECT_DOUBLE_EQ(s.field_of_view, 3.141593);
    EXPECT_DOUBLE_EQ(s.angular_resolution, 0.017453);
    ASSERT_TRUE(s.ranges.size() == 180 || s.ranges.size() == 181) << s.line;
    (s.ranges.size() == 181 ? starts181 : starts180).insert(s.start_angle);
  }
  EXPECT_EQ(starts181, (std::set<double>{-1.570796}));
  EXPECT_EQ(starts180, (std::set<double>{-1.566433, -1.562070, -1.557706}));

  CarmenRecordingReport report;
  const Recording rec = fromCarmen(log, nullptr, {}, &report);
  expectGeometry(rec.geometry, -1.570796, 0.017453, 181, 81.895);
  ASSERT_TRUE(rec.scans[1].geometry.has_value());  // line 2: 180 beams from -89.75 deg
  expectGeometry(*rec.scans[1].geometry, -1.566433, 0.017453, 180, 81.895);
  EXPECT_EQ(report.geometries, 4u);
  for (const RecordedScan& s : rec.scans) EXPECT_EQ(s.ranges.size(), rec.geometryOf(s).beam_count);
  // Laser 0.22 m ahead of the robot on every line (poses printed to 1e-6); odometry = robot pose.
  EXPECT_NEAR(rec.base_to_laser.x, 0.22, 1e-6);
  EXPECT_NEAR(rec.base_to_laser.y, 0.0, 1e-6);
  EXPECT_NEAR(rec.base_to_laser.theta, 0.0, 1e-6);
  EXPECT_LT(report.max_mounting_shift, 1e-5);
  EXPECT_EQ(report.odometry_source, "scan odometry fields");
  EXPECT_DOUBLE_EQ(rec.scans[1].odom.x, 0.205315);
  EXPECT_DOUBLE_EQ(rec.scans[1].odom.theta, -0.003076);
}

TEST(CarmenLog, PlainGzipAndBzip2GiveIdenticalRecords)
{
  std::string path;
  if (!dataset("intel.clf.bz2", path)) return;
  // The first 3000 lines of the real log, stored three ways under misleading names:
  // the reader must go by the magic bytes.
  std::istringstream all(readMaybeCompressedFile(path));
  std::string text, line;
  for (int i = 0; i < 3000 && std::getline(all, line); ++i) text += line + "\n";
  TempDir dir;
  const CarmenLog plain = readCarmenLog(dir.write("a.gz", text));
  const CarmenLog gz = readCarmenLog(dir.write("b.clf", compress(text, true)));
  const CarmenLog bz = readCarmenLog(dir.write("c.log", compress(text, false)));
  ASSERT_GT(plain.scans.size(), 500u);
  // Truncated compressed files are errors naming the file, not silently shorter logs.
  for (const bool gzip : {true, false})
  {
    const std::string packed = compress(text, gzip);
    const std::string cut = dir.write(gzip ? "cut.gz" : "cut.bz2", packed.substr(0, packed.size() / 2));
    try
    {
      readCarmenLog(cut);
      ADD_FAILURE() << "truncated " << (gzip ? "gzip" : "bzip2") << " accepted";
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(cut), std::string::npos) << e.what();
    }
  }
  for (const CarmenLog* other : {&gz, &bz})
  {
    ASSERT_EQ(other->scans.size(), plain.scans.size());
    ASSERT_EQ(other->odometry.size(), plain.odometry.size());
    EXPECT_EQ(other->params, plain.params);
    for (std::size_t i = 0; i < plain.scans.size(); ++i)
    {
      const CarmenScan &a = plain.scans[i], &b = other->scans[i];
      ASSERT_EQ(a.ranges, b.ranges);
      ASSERT_EQ(a.timestamp, b.timestamp);
      ASSERT_EQ(a.robot_pose.x, b.robot_pose.x);
      ASSERT_EQ(a.robot_pose.theta, b.robot_pose.theta);
      ASSERT_EQ(a.line, b.line);
    }
  }
}

TEST(CarmenLog, KeyframesPairWithRawScansByRanges)
{
  struct Expect
  {
    const char *raw, *corrected;
    std::size_t count, first, last;
  };
  // Intel: dataset README. ACES and CSAIL: found by an independent script over the text files.
  for (const Expect e : {Expect{"intel.clf.bz2", "intel-corrected.log.gz", 910, 169, 13583},
                         Expect{"aces.clf.bz2", "aces-corrected.log.gz", 440, 136, 7185},
                         Expect{"mit-csail.clf.bz2", "csail-corrected.log.gz", 406, 61, 1916}})
  {
    std::string raw_path, corrected_path;
    if (!dataset(e.raw, raw_path) || !dataset(e.corrected, corrected_path)) continue;
    const CarmenLog raw = readCarmenLog(raw_path);
    const CarmenLog corrected = readCarmenLog(corrected_path);
    const std::vector<std::size_t> pairs = pairKeyframes(raw, corrected);
    ASSERT_EQ(pairs.size(), e.count) << e.raw;
    EXPECT_EQ(pairs.front(), e.first) << e.raw;
    EXPECT_EQ(pairs.back(), e.last) << e.raw;
    for (std::size_t k = 0; k < pairs.size(); ++k)
    {
      if (k > 0)
      {
        ASSERT_GT(pairs[k], pairs[k - 1]) << e.raw;
      }
      ASSERT_EQ(raw.scans[pairs[k]].ranges, corrected.scans[k].ranges) << e.raw << " keyframe " << k;
    }
  }
}

TEST(CarmenLog, UnpairableKeyframeIsAnError)
{
  TempDir dir;
  const CarmenLog raw = readCarmenLog(dir.write("raw.clf", flaser(1.0) + "\n" + flaser(2.0, 1.0) + "\n"));
  // Keyframe 1 has ranges that no raw scan has.
  const CarmenLog corrected =
      readCarmenLog(dir.write("corr.log", "# x\n" + flaser(2.0) + "\nFLASER 3 9 9 9 0 0 0 0 0 0 3 h 3\n"));
  try
  {
    pairKeyframes(raw, corrected);
    ADD_FAILURE() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("corr.log:3: keyframe 1"), std::string::npos) << e.what();
  }
  // Identical ranges in both raw scans: keyframes pair in order, never twice with the same scan.
  const CarmenLog twice = readCarmenLog(dir.write("twice.log", flaser(5.0) + "\n" + flaser(6.0) + "\n"));
  EXPECT_EQ(pairKeyframes(raw, twice), (std::vector<std::size_t>{0, 1}));
}

TEST(CarmenLog, BeamGeometry)
{
  const ScanGeometry g180 = carmenBeamGeometry(180, 81.83);
  EXPECT_NEAR(g180.angle_increment, kPi / 180.0, 1e-15);
  EXPECT_NEAR(g180.angle_min, -89.5 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(g180.angle_min + 179 * g180.angle_increment, 89.5 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(g180.range_max, 81.825, 1e-12);
  // The no-return code is rejected, the largest real reading (1 cm below) is kept.
  EXPECT_GT(81.83f, g180.range_max);
  EXPECT_LE(81.82f, g180.range_max);

  const ScanGeometry g361 = carmenBeamGeometry(361, 81.91);
  EXPECT_NEAR(g361.angle_increment, kPi / 360.0, 1e-15);
  EXPECT_NEAR(g361.angle_min, -kPi / 2.0, 1e-12);
  EXPECT_NEAR(g361.angle_min + 360 * g361.angle_increment, kPi / 2.0, 1e-12);
  EXPECT_EQ(g361.beam_count, 361u);

  const ScanGeometry aces = carmenBeamGeometry(180, 50.0);
  EXPECT_GT(50.0f, aces.range_max);
  EXPECT_LE(49.91f, aces.range_max);  // ACES holds real readings up to 49.91 m
  EXPECT_THROW(carmenBeamGeometry(1, 10.0), std::invalid_argument);
}

/// A 3-beam FLASER line with the given readings at time t.
std::string flaserRanges(double t, double a, double b, double c)
{
  std::ostringstream s;
  s << "FLASER 3 " << a << " " << b << " " << c << " 0 0 0 0 0 0 " << t << " host " << t;
  return s.str();
}

TEST(CarmenRecording, NoReturnCodesThatVaryAreAllInvalid)
{
  // No-return written as 81.87, 81.89 and 81.91 m: all three are codes (range_max 5 mm below the
  // lowest, 81.865 m); 81.0 m lies more than 1 % (0.82 m) below the largest and stays a reading.
  TempDir dir;
  const CarmenLog log = readCarmenLog(dir.write(
      "jitter.clf", flaserRanges(1.0, 2.5, 81.91, 7.0) + "\n" + flaserRanges(2.0, 81.87, 3.0, 81.89) + "\n" +
                        flaserRanges(3.0, 81.89, 81.91, 10.0) + "\n" + flaserRanges(4.0, 81.0, 4.0, 81.87) +
                        "\n"));
  EXPECT_DOUBLE_EQ(carmenNoReturnFloor(log), static_cast<double>(81.87f));
  const Recording rec = fromCarmen(log, nullptr);
  EXPECT_NEAR(rec.geometry.range_max, 81.865, 1e-5);
  std::size_t valid = 0, codes = 0;
  for (const RecordedScan& scan : rec.scans)
    for (const float r : scan.ranges)
    {
      const bool is_code = r > 81.5f;
      if (r <= rec.geometry.range_max) ++valid;
      if (is_code) ++codes;
      EXPECT_EQ(r <= rec.geometry.range_max, !is_code) << r;
    }
  EXPECT_EQ(codes, 6u);
  EXPECT_EQ(valid, 6u);

  // ACES: 50.0 for no return, real readings up to 49.91 m (9 cm apart: no code).
  const CarmenLog aces = readCarmenLog(dir.write("aces.clf", flaserRanges(1.0, 50.0, 49.91, 3.0) + "\n"));
  EXPECT_DOUBLE_EQ(carmenNoReturnFloor(aces), static_cast<double>(50.0f));
  EXPECT_GE(fromCarmen(aces, nullptr).geometry.range_max, 49.91);
  EXPECT_LT(fromCarmen(aces, nullptr).geometry.range_max, 50.0);

  // A usable range below the sensor's maximum caps range_max.
  CarmenRecordingOptions options;
  options.max_usable_range = 40.0;
  EXPECT_DOUBLE_EQ(fromCarmen(log, nullptr, options).geometry.range_max, 40.0);
}

TEST(CarmenRecording, StampsBecomeStrictlyIncreasing)
{
  TempDir dir;
  const CarmenLog raw =
      readCarmenLog(dir.write("t.clf", flaser(10.0) + "\n" + flaser(10.1) + "\n" + flaser(10.05) + "\n" +
                                           flaser(10.1005) + "\n" + flaser(10.2) + "\n"));
  CarmenRecordingReport report;
  const Recording rec = fromCarmen(raw, nullptr, {}, &report);
  const double expected[] = {10.0, 10.1, 10.101, 10.102, 10.2};
  ASSERT_EQ(rec.scans.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(rec.scans[i].stamp, expected[i], 1e-9) << i;
  EXPECT_EQ(report.stamps_adjusted, 2u);
  EXPECT_NEAR(report.max_stamp_shift, 0.051, 1e-9);
}

TEST(CarmenRecording, OdometryFromOdomLinesAndMountingFromParam)
{
  TempDir dir;
  // Scans without odometry (all zero), ODOM lines moving along x, a 0.1 m laser offset.
  const std::string text =
      "PARAM robot_frontlaser_offset 0.1 nohost 0\n"
      "ODOM 0 0 0 0 0 0 1.0 h 0\nODOM 1 0 0.2 0 0 0 2.0 h 0\nODOM 3 0 0.4 0 0 0 3.0 h 0\n" +
      flaser(1.5) + "\n" + flaser(2.75) + "\n";
  const CarmenLog raw = readCarmenLog(dir.write("o.clf", text));
  const CarmenLog corrected = readCarmenLog(
      dir.write("c.log", "FLASER 3 1.5 2.25 3 1 1 1.5707963267948966 1 1 1.5707963267948966 2 h 2\n"));
  CarmenRecordingReport report;
  const Recording rec = fromCarmen(raw, &corrected, {}, &report);
  EXPECT_EQ(report.odometry_source, "ODOM lines");
  EXPECT_NEAR(rec.base_to_laser.x, 0.1, 1e-15);
  ASSERT_EQ(rec.scans.size(), 2u);
  EXPECT_NEAR(rec.scans[0].odom.x, 0.5, 1e-12);
  EXPECT_NEAR(rec.scans[0].odom.theta, 0.1, 1e-12);
  EXPECT_NEAR(rec.scans[1].odom.x, 2.5, 1e-12);
  EXPECT_NEAR(rec.scans[1].odom.theta, 0.35, 1e-12);
  // The keyframe pairs with the first raw scan (same ranges); its base pose is the laser pose
  // moved 0.1 m backwards along the heading (+y): (1, 0.9, pi/2).
  ASSERT_EQ(rec.keyframes.size(), 1u);
  EXPECT_EQ(rec.keyframes[0].scan_index, 0u);
  EXPECT_NEAR(rec.keyframes[0].pose.x, 1.0, 1e-12);
  EXPECT_NEAR(rec.keyframes[0].pose.y, 0.9, 1e-12);
  EXPECT_NEAR(rec.keyframes[0].pose.theta, kPi / 2, 1e-12);
}

TEST(CarmenRecording, IntelRecording)
{
  std::string raw_path, corrected_path;
  if (!dataset("intel.clf.bz2", raw_path) || !dataset("intel-corrected.log.gz", corrected_path)) return;
  const CarmenLog raw = readCarmenLog(raw_path);
  const CarmenLog corrected = readCarmenLog(corrected_path);
  CarmenRecordingReport report;
  const Recording rec = fromCarmen(raw, &corrected, {}, &report);
  ASSERT_EQ(rec.scans.size(), 13631u);
  EXPECT_EQ(rec.geometry.beam_count, 180u);
  EXPECT_DOUBLE_EQ(report.no_return_range, static_cast<double>(81.83f));  // README: Intel writes 81.83
  EXPECT_EQ(report.odometry_source, "scan odometry fields");
  // Stamps: strictly increasing, never earlier than written, unchanged where the log was in order.
  std::size_t unchanged = 0;
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
  {
    if (i > 0)
    {
      ASSERT_GE(rec.scans[i].stamp - rec.scans[i - 1].stamp, 1e-3 - 1e-6) << i;
    }
    ASSERT_GE(rec.scans[i].stamp, raw.scans[i].timestamp) << i;
    if (rec.scans[i].stamp == raw.scans[i].timestamp) ++unchanged;
    ASSERT_EQ(rec.scans[i].odom.x, raw.scans[i].robot_pose.x);
  }
  // At least the 631 backward steps of the README had to move; most stamps stay.
  EXPECT_GE(report.stamps_adjusted, 631u);
  EXPECT_EQ(unchanged + report.stamps_adjusted, rec.scans.size());
  EXPECT_GT(unchanged, rec.scans.size() / 2);
  ASSERT_EQ(rec.keyframes.size(), 910u);
  EXPECT_EQ(rec.keyframes.front().scan_index, 169u);
  EXPECT_EQ(rec.keyframes.back().scan_index, 13583u);
  // Mounting is the identity (robot_frontlaser_offset 0.0): keyframe pose = corrected laser pose.
  for (std::size_t k = 0; k < rec.keyframes.size(); ++k)
  {
    EXPECT_NEAR(rec.keyframes[k].pose.x, corrected.scans[k].laser_pose.x, 1e-12);
    EXPECT_NEAR(rec.keyframes[k].pose.y, corrected.scans[k].laser_pose.y, 1e-12);
    EXPECT_NEAR(std::remainder(rec.keyframes[k].pose.theta - corrected.scans[k].laser_pose.theta, 2 * kPi),
                0.0, 1e-12);
  }
  // max_scans keeps a prefix and the keyframes inside it.
  CarmenRecordingOptions first1000;
  first1000.max_scans = 1000;
  const Recording prefix = fromCarmen(raw, &corrected, first1000);
  EXPECT_EQ(prefix.scans.size(), 1000u);
  for (const CorrectedKeyframe& kf : prefix.keyframes) EXPECT_LT(kf.scan_index, 1000u);
  EXPECT_EQ(prefix.geometry.range_max, rec.geometry.range_max);
}

TEST(ProgressBar, SilentUnlessFinishedWhenNotATerminal)
{
  std::ostringstream log, tty, off;
  {
    ProgressBar bar("convert", 10, true, log, false);
    for (std::size_t i = 1; i <= 10; ++i) bar.update(i);
    EXPECT_EQ(log.str(), "");
    bar.finish();
    bar.finish();
  }
  EXPECT_EQ(log.str().rfind("convert [" + std::string(30, '#') + "] 10/10 100%", 0), 0u) << log.str();
  const std::string printed = log.str();
  EXPECT_EQ(std::count(printed.begin(), printed.end(), '\n'), 1);
  {
    ProgressBar bar("convert", 4, true, tty, true);
    bar.update(2);
    bar.update(4);
    bar.finish();
  }
  EXPECT_NE(tty.str().find('\r'), std::string::npos);
  EXPECT_NE(tty.str().find("4/4"), std::string::npos);
  {
    ProgressBar bar("convert", 4, false, off, true);
    bar.update(4);
    bar.finish();
  }
  EXPECT_EQ(off.str(), "");
}
