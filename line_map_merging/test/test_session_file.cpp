// The session file alone and with the SLAM: a session is read back bit for bit (doubles included: -0,
// subnormals, the largest finite), a restored SLAM gives the same trajectory and maps on from where it
// stopped, and every damaged file (cut at any byte, a flipped bit, a newer version, an index out of
// range) is refused with a message naming the record, leaving the running SLAM as it was.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>

#include "line_map_merging/slam/laser_slam.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "slam_world.hpp"

using line_map_merging::decodeSession;
using line_map_merging::encodeSession;
using line_map_merging::LaserSlam;
using line_map_merging::PoseGraphEdge;
using line_map_merging::Session;
using line_map_merging::SessionFileError;
using line_map_merging::SlamKeyframe;
using line_map_merging::SlamScan;
using line_map_merging::SlamSession;
using linemap::Pose2;

namespace
{
bool sameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}

void expectSamePose(const Pose2& a, const Pose2& b)
{
  EXPECT_TRUE(sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.theta, b.theta))
      << a.x << " " << a.y << " " << a.theta << " vs " << b.x << " " << b.y << " " << b.theta;
}

void expectSameSlam(const SlamSession& a, const SlamSession& b)
{
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t i = 0; i < a.keyframes.size(); ++i)
  {
    const SlamKeyframe &x = a.keyframes[i], &y = b.keyframes[i];
    EXPECT_TRUE(sameBits(x.stamp, y.stamp) && sameBits(x.path, y.path));
    EXPECT_EQ(x.scan, y.scan);
    expectSamePose(x.local, y.local);
    ASSERT_EQ(x.points.size(), y.points.size());
    for (std::size_t p = 0; p < x.points.size(); ++p)
      EXPECT_TRUE(sameBits(x.points[p].x(), y.points[p].x()) && sameBits(x.points[p].y(), y.points[p].y()));
    ASSERT_EQ(x.joins.size(), y.joins.size());
    for (std::size_t j = 0; j < x.joins.size(); ++j)
      EXPECT_TRUE(sameBits(x.joins[j].start.x(), y.joins[j].start.x()) &&
                  sameBits(x.joins[j].end.y(), y.joins[j].end.y()));
  }
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) expectSamePose(a.nodes[i], b.nodes[i]);
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (std::size_t i = 0; i < a.edges.size(); ++i)
  {
    const PoseGraphEdge &x = a.edges[i], &y = b.edges[i];
    EXPECT_EQ(x.from, y.from);
    EXPECT_EQ(x.to, y.to);
    expectSamePose(x.measurement, y.measurement);
    EXPECT_TRUE(sameBits(x.sigma_xy, y.sigma_xy) && sameBits(x.sigma_theta, y.sigma_theta) &&
                sameBits(x.loss_scale, y.loss_scale));
    for (int k = 0; k < 4; ++k)
      EXPECT_TRUE(sameBits(x.translation_weights(k / 2, k % 2), y.translation_weights(k / 2, k % 2)));
    EXPECT_EQ(x.loop, y.loop);
  }
  ASSERT_EQ(a.scans.size(), b.scans.size());
  for (std::size_t i = 0; i < a.scans.size(); ++i)
  {
    EXPECT_TRUE(sameBits(a.scans[i].stamp, b.scans[i].stamp));
    EXPECT_EQ(a.scans[i].keyframe, b.scans[i].keyframe);
    expectSamePose(a.scans[i].relative, b.scans[i].relative);
  }
}

/// A small session with the doubles a text format would bend: -0, a subnormal, the largest finite,
/// one third; a loop edge with its own loss scale and a sheared translation shape; a scan before any
/// keyframe.
Session awkwardSession()
{
  Session s;
  SlamKeyframe a;
  a.stamp = 1.0 / 3.0;
  a.scan = 0;
  a.local = Pose2(-0.0, std::numeric_limits<double>::denorm_min(), 3.141592653589793);
  a.points = {{1.0, 2.0}, {std::numeric_limits<double>::max(), -1e-300}};
  a.joins = {linemap::Segment2({0.1, 0.2}, {0.3, 0.4})};
  SlamKeyframe b = a;
  b.stamp = 2.0;
  b.scan = 7;
  b.path = 0.2;
  b.points.clear();
  b.joins.clear();
  s.slam.keyframes = {a, b};
  s.slam.nodes = {Pose2(0.0, 0.0, 0.0), Pose2(0.2, -0.0, 1e-17)};
  PoseGraphEdge chain;
  chain.from = 0;
  chain.to = 1;
  chain.measurement = Pose2(0.2, 0.0, 0.0);
  PoseGraphEdge loop = chain;
  loop.from = 1;
  loop.to = 0;
  loop.loop = true;
  loop.loss_scale = 7.25;
  loop.translation_weights << 0.5, 0.25, 0.25, 1e-6;
  loop.sigma_xy = 0.05;
  loop.sigma_theta = 0.01;
  s.slam.edges = {chain, loop};
  s.slam.scans = {{0.1, static_cast<std::size_t>(-1), Pose2(0.0, 0.0, 0.0)},
                  {1.0 / 3.0, 0, Pose2(0.0, 0.0, 0.0)},
                  {2.0, 1, Pose2(0.01, -0.02, 0.003)}};
  s.line_map = "format_version: 3\nmethod: cae\n# any text, carried as it is\n";
  return s;
}

/// The CRC-32 of a record's payload sits 12 bytes into its header; after a change to a payload the
/// record is made valid again, so the test reaches the checks behind the checksum.
void refreshChecksum(std::string& bytes, std::size_t record_at);

std::size_t recordAt(const std::string& bytes, const std::string& tag)
{
  std::size_t at = 16 + 4;
  while (at + 16 <= bytes.size())
  {
    std::uint64_t size = 0;
    for (int i = 7; i >= 0; --i) size = (size << 8) | static_cast<unsigned char>(bytes[at + 4 + i]);
    if (bytes.compare(at, 4, tag) == 0) return at;
    at += 16 + size;
  }
  ADD_FAILURE() << "no record " << tag;
  return 0;
}

std::string errorOf(const std::string& bytes)
{
  try
  {
    decodeSession(bytes, "test.session");
  }
  catch (const SessionFileError& e)
  {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SessionFile, ReadsBackBitForBit)
{
  const Session s = awkwardSession();
  const Session back = decodeSession(encodeSession(s), "memory");
  expectSameSlam(s.slam, back.slam);
  EXPECT_EQ(back.line_map, s.line_map);
  // Through a file, written atomically (no temporary left beside it).
  const auto dir = std::filesystem::temp_directory_path() / ("linemap_session_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "run.session").string();
  line_map_merging::writeSessionFile(path, s);
  const Session from_file = line_map_merging::readSessionFile(path);
  expectSameSlam(s.slam, from_file.slam);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
  std::filesystem::remove_all(dir);
}

TEST(SessionFile, EveryCutIsRefusedAndNamed)
{
  const std::string bytes = encodeSession(awkwardSession());
  for (std::size_t cut = 0; cut < bytes.size(); ++cut)
  {
    const std::string error = errorOf(bytes.substr(0, cut));
    ASSERT_FALSE(error.empty()) << "a file cut at byte " << cut << " of " << bytes.size() << " was accepted";
    EXPECT_NE(error.find("test.session"), std::string::npos) << error;
  }
  // Cut inside the edges: the message names that record and says it is truncated.
  const std::size_t edges = recordAt(bytes, "EDGE");
  const std::string in_edges = errorOf(bytes.substr(0, edges + 30));
  EXPECT_NE(in_edges.find("record 'EDGE'"), std::string::npos) << in_edges;
  EXPECT_NE(in_edges.find("truncated"), std::string::npos) << in_edges;
  // Cut between records: no END record.
  EXPECT_NE(errorOf(bytes.substr(0, recordAt(bytes, "SCAN"))).find("no END record"), std::string::npos);
}

TEST(SessionFile, CorruptRecordsWrongVersionAndBadIndicesAreNamed)
{
  const std::string good = encodeSession(awkwardSession());
  // One bit flipped in a keyframe's point: the checksum catches it.
  std::string flipped = good;
  flipped[recordAt(good, "KEYF") + 16 + 40] ^= 0x10;
  const std::string corrupt = errorOf(flipped);
  EXPECT_NE(corrupt.find("record 'KEYF'"), std::string::npos) << corrupt;
  EXPECT_NE(corrupt.find("checksum"), std::string::npos) << corrupt;
  // A version this build does not know.
  std::string newer = good;
  newer[16] = 2;
  EXPECT_NE(errorOf(newer).find("format version 2 is not supported"), std::string::npos) << errorOf(newer);
  // Not a session file at all.
  EXPECT_NE(errorOf("format_version: 3\n").find("not a linemap session file"), std::string::npos);
  // An edge to a node the graph does not have, its checksum made valid: named by record and item.
  std::string bad_index = good;
  const std::size_t edges = recordAt(good, "EDGE");
  bad_index[edges + 16 + 8 + 8] = 99;  // the first edge's `to` (its low byte: little-endian)
  refreshChecksum(bad_index, edges);
  const std::string index = errorOf(bad_index);
  EXPECT_NE(index.find("record 'EDGE'"), std::string::npos) << index;
  EXPECT_NE(index.find("edge 0"), std::string::npos) << index;
  // A missing file.
  EXPECT_THROW(line_map_merging::readSessionFile("/nonexistent/dir/x.session"), SessionFileError);
}

namespace
{
void refreshChecksum(std::string& bytes, std::size_t record_at)
{
  std::uint64_t size = 0;
  for (int i = 7; i >= 0; --i) size = (size << 8) | static_cast<unsigned char>(bytes[record_at + 4 + i]);
  // Re-encode through the library: decode is not possible (the payload is what is broken), so the CRC
  // is recomputed here with the same polynomial zlib uses.
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < size; ++i)
  {
    crc ^= static_cast<unsigned char>(bytes[record_at + 16 + i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xffffffffu;
  for (int i = 0; i < 4; ++i) bytes[record_at + 12 + i] = static_cast<char>((crc >> (8 * i)) & 0xffu);
}

/// Two laps of a rectangle in the ray-cast room, odometry drifting in heading.
struct Drive
{
  std::vector<Pose2> truth, odom;
  Drive()
  {
    const std::vector<linemap::Vec2> corners = {{1.5, 4.0}, {7.0, 4.0}, {7.0, 1.0}, {1.5, 1.0}};
    std::vector<linemap::Vec2> goals;
    for (int lap = 0; lap < 2; ++lap)
      for (std::size_t c = 1; c <= corners.size(); ++c) goals.push_back(corners[c % corners.size()]);
    truth = slam_world::drive(Pose2(1.5, 4.0, 0.0), goals);
    odom = {truth[0]};
    for (std::size_t i = 1; i < truth.size(); ++i)
    {
      Pose2 step = truth[i - 1].inverse() * truth[i];
      step.theta += 0.03 * std::hypot(step.x, step.y);
      odom.push_back(odom.back() * step);
    }
  }
  /// The largest position error of a run's scan poses (the map frame is the first pose).
  double worstError(const std::vector<std::pair<double, Pose2>>& poses) const
  {
    double worst = 0.0;
    for (std::size_t i = 0; i < poses.size(); ++i)
    {
      const Pose2 p = truth[0] * poses[i].second;
      worst = std::max(worst, std::hypot(p.x - truth[i].x, p.y - truth[i].y));
    }
    return worst;
  }
  SlamScan scan(std::size_t i) const
  {
    SlamScan s;
    s.stamp = 1.0 + 0.2 * static_cast<double>(i);
    s.points = slam_world::scan(slam_world::room(), truth[i], 180, 20.0, 0.005, static_cast<unsigned>(i));
    s.odom = odom[i];
    return s;
  }
};
}  // namespace

TEST(SlamSession, RestoredRunHasTheSameTrajectoryAndMapsOn)
{
  const Drive drive;
  const std::size_t half = drive.truth.size() / 2;
  LaserSlam first;
  for (std::size_t i = 0; i < half; ++i) first.addScan(drive.scan(i));
  ASSERT_GT(first.counters().loops_accepted, 0u) << "the first lap should close";

  LaserSlam restored;
  restored.restore(decodeSession(encodeSession({first.session(), ""}), "memory").slam);
  expectSameSlam(first.session(), restored.session());
  const auto a = first.scanPoses(), b = restored.scanPoses();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) expectSamePose(a[i].second, b[i].second);

  // The second lap, on the restored run: every pose on the truth (the map frame is the first pose), as
  // an uninterrupted run keeps it; a front end that restarted at the origin would be metres off.
  for (std::size_t i = half; i < drive.truth.size(); ++i) restored.addScan(drive.scan(i));
  const auto poses = restored.scanPoses();
  ASSERT_EQ(poses.size(), drive.truth.size());
  EXPECT_LT(drive.worstError(poses), 0.1);
  EXPECT_GT(restored.keyframes().size(), first.keyframes().size());
}

TEST(SlamSession, AnInconsistentSessionLeavesTheRunAsItWas)
{
  const Drive drive;
  LaserSlam slam;
  for (std::size_t i = 0; i < 40; ++i) slam.addScan(drive.scan(i));
  const SlamSession before = slam.session();
  SlamSession broken = before;
  broken.nodes.pop_back();
  EXPECT_THROW(slam.restore(broken), std::invalid_argument);
  broken = before;
  broken.edges.front().to = 1000;
  EXPECT_THROW(slam.restore(broken), std::out_of_range);
  broken = before;
  broken.scans.back().keyframe = 1000;
  EXPECT_THROW(slam.restore(broken), std::invalid_argument);
  expectSameSlam(before, slam.session());
}

// A second run continues the first one's session: the robot restarted (its odometry from zero) at the
// second lap's start, which the caller knows only roughly (0.18 m and 0.04 rad off, as from a global
// localization). Its keyframes join the saved graph, closures to the saved keyframes pull the start right,
// and the joined trajectory lies on the truth. Ignoring the start (a new trajectory at the origin) puts the
// second lap metres off; without the closures to the saved keyframes the start's error stays.
TEST(SlamSession, AContinuedRunJoinsTheSavedGraph)
{
  const Drive drive;
  const std::size_t half = drive.truth.size() / 2;
  LaserSlam first;
  for (std::size_t i = 0; i < half; ++i) first.addScan(drive.scan(i));
  const SlamSession saved = decodeSession(encodeSession({first.session(), ""}), "memory").slam;

  LaserSlam second;
  const Pose2 true_start = drive.truth[0].inverse() * drive.truth[half];
  second.continueFrom(saved, true_start * Pose2(0.15, -0.1, 0.04), 0.2, 0.1);
  const Pose2 restart = drive.odom[half].inverse();
  for (std::size_t i = half; i < drive.truth.size(); ++i)
  {
    SlamScan s = drive.scan(i);
    s.odom = restart * *s.odom;  // the odometry starts again at zero
    second.addScan(s);
  }
  const auto poses = second.scanPoses();
  ASSERT_EQ(poses.size(), drive.truth.size());
  EXPECT_LT(drive.worstError(poses), 0.1);
  std::size_t across = 0;
  for (const auto& e : second.graph().edges())
    across += e.loop && std::min(e.from, e.to) < saved.keyframes.size() &&
              std::max(e.from, e.to) >= saved.keyframes.size();
  EXPECT_GE(across, 4u) << "the start's tie and closures between the runs";
}

// A second run mapped apart (its own frame: the odometry from zero) joins the saved session at its 20th
// scan, told where the saved frame lies in its own (as the session search finds it, 0.15 m and 0.04 rad off
// here). The saved scans then lie in the second run's frame, before its own, and the joined trajectory is
// one rigid motion from the truth: closures to the saved keyframes pull the tie right. Joined as if the
// frames were one, the first lap would be metres off; an inconsistent session changes nothing.
TEST(SlamSession, ARunMappedApartJoinsTheSavedSessionInItsOwnFrame)
{
  const Drive drive;
  const std::size_t half = drive.truth.size() / 2;
  LaserSlam first;
  for (std::size_t i = 0; i < half; ++i) first.addScan(drive.scan(i));
  const SlamSession saved = first.session();

  LaserSlam second;
  const Pose2 restart = drive.odom[half].inverse();
  const auto scan = [&](std::size_t i)
  {
    SlamScan s = drive.scan(i);
    s.odom = restart * *s.odom;  // the odometry starts again at zero
    return s;
  };
  const std::size_t join_at = half + 20;
  for (std::size_t i = half; i <= join_at; ++i) second.addScan(scan(i));
  // The second run's frame is its first pose: the saved frame (the first lap's first pose) lies there at
  // truth[half]^-1 * truth[0].
  const Pose2 saved_in_own = drive.truth[half].inverse() * drive.truth[0];
  SlamSession broken = saved;
  broken.edges.front().to = 1000;
  const SlamSession before = second.session();
  EXPECT_THROW(second.joinSession(broken, saved_in_own, 0.2, 0.1), std::out_of_range);
  expectSameSlam(before, second.session());

  second.joinSession(saved, saved_in_own * Pose2(0.15, -0.1, 0.04), 0.2, 0.1);
  EXPECT_EQ(second.keyframes().size(), saved.keyframes.size() + before.keyframes.size());
  for (std::size_t i = join_at + 1; i < drive.truth.size(); ++i) second.addScan(scan(i));
  const auto poses = second.scanPoses();
  ASSERT_EQ(poses.size(), drive.truth.size());
  // The graph's fixed node is now the first saved keyframe, placed by the tie: the frame may move by the
  // tie's error, so the trajectory is compared with the truth after one rigid fit.
  std::vector<std::pair<linemap::Vec2, linemap::Vec2>> pairs;
  for (std::size_t i = 0; i < poses.size(); ++i)
    pairs.emplace_back(poses[i].second.translation(), drive.truth[i].translation());
  const Pose2 fit = linemap::bestRigidFit(pairs);
  double worst = 0.0;
  for (const auto& [joined, truth] : pairs) worst = std::max(worst, (fit.apply(joined) - truth).norm());
  EXPECT_LT(worst, 0.1);
  // Where the fit put the second run's frame: its first pose, within the tie's error.
  const Pose2 own_origin = fit.inverse() * drive.truth[half];
  EXPECT_LT(std::hypot(own_origin.x, own_origin.y), 0.3);
  std::size_t across = 0;
  for (const auto& e : second.graph().edges())
    across += e.loop && std::min(e.from, e.to) < saved.keyframes.size() &&
              std::max(e.from, e.to) >= saved.keyframes.size();
  EXPECT_GE(across, 4u) << "the tie and closures between the runs";
}
