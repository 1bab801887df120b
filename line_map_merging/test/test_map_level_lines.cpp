// Map-level lines against ray-cast scans of known walls: a far wall no single scan resolves gets a
// line with provenance to the keyframes that saw it, a wall seen only between panels in front of it lines
// where it was seen; clutter, a wall already mapped or explained by
// the keyframes' own segments gets none; and through the online mapper the line becomes originals
// of those keyframes that move with them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "line_map_merging/online/map_level_lines.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "line_map_merging/online/recent_scans.hpp"

using namespace line_map_merging;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
constexpr double kDeg = linemap::kPi / 180.0;

/// A 180 degree laser, 1 degree beams, 30 m: the coarse sensor of the large halls.
struct Laser
{
  double fov = 180.0 * kDeg, increment = 1.0 * kDeg, range_max = 30.0;
  double sigma0 = 0.01, sigma_per_m = 0.001;  // the sensor model's defaults
};

/// Casts every beam against the walls (thin, seen from both sides) and adds range noise.
KeyframeScan cast(const Pose2& laser, const std::vector<Segment2>& walls, const Laser& l, std::mt19937& rng)
{
  KeyframeScan scan;
  scan.angle_min = -0.5 * l.fov;
  scan.angle_increment = l.increment;
  scan.range_min = 0.05;
  scan.range_max = l.range_max;
  const int beams = static_cast<int>(std::lround(l.fov / l.increment)) + 1;
  for (int i = 0; i < beams; ++i)
  {
    const double a = laser.theta + scan.angle_min + i * l.increment;
    const Vec2 u(std::cos(a), std::sin(a)), o = laser.translation();
    double best = l.range_max;
    for (const Segment2& w : walls)
    {
      const Vec2 d = w.end - w.start, q = w.start - o;
      const double det = u.x() * (-d.y()) - u.y() * (-d.x());
      if (std::abs(det) < 1e-12) continue;
      const double s = (q.x() * (-d.y()) - q.y() * (-d.x())) / det;
      const double t = (u.x() * q.y() - u.y() * q.x()) / det;
      if (s > 0.0 && t >= 0.0 && t <= 1.0) best = std::min(best, s);
    }
    std::normal_distribution<double> noise(0.0, l.sigma0 + l.sigma_per_m * best);
    scan.ranges.push_back(best >= l.range_max ? l.range_max : static_cast<float>(best + noise(rng)));
  }
  return scan;
}

/// The robot driving along y at x = 0, facing +x: keyframes every 0.2 m over 10 m.
std::vector<KeyframeInfo> drive()
{
  std::vector<KeyframeInfo> keyframes;
  for (int k = 0; k <= 50; ++k)
  {
    KeyframeInfo info;
    info.index = static_cast<std::uint64_t>(k);
    info.pose = Pose2(0.0, -5.0 + 0.2 * k, 0.0);
    keyframes.push_back(info);
  }
  return keyframes;
}

/// The far wall, 25 m ahead, 16 m long, seen by every keyframe with about one beam per 0.44 m.
const Segment2 kFarWall(Vec2(25.0, -8.0), Vec2(25.0, 8.0));  // the robot (x < 25) on its left

MapLevelLines observed(const std::vector<KeyframeInfo>& keyframes, const std::vector<Segment2>& walls,
                       const MapLevelParams& params = MapLevelParams(), std::uint32_t seed = 1)
{
  std::mt19937 rng(seed);
  MapLevelLines lines(params);
  for (const KeyframeInfo& k : keyframes) lines.addKeyframe(k.index, cast(k.pose, walls, Laser(), rng), {});
  return lines;
}

double distanceToWall(const Vec2& p, const Segment2& wall)
{
  return linemap::distanceToSegment(p, wall.start, wall.end);
}
}  // namespace

TEST(MapLevelLines, AFarWallNoScanResolvesGetsALineWithProvenanceToTheKeyframesThatSawIt)
{
  const std::vector<KeyframeInfo> keyframes = drive();
  MapLevelLines lines = observed(keyframes, {kFarWall});
  std::vector<Segment2> found;
  const std::vector<KeyframeOriginals> parts = lines.extract(keyframes, {}, &found);
  ASSERT_EQ(found.size(), 1u);
  // On the wall: its points' sigma at 25 m is 3.5 cm, the fit over hundreds of them far better.
  EXPECT_LT(distanceToWall(found[0].start, kFarWall), 0.03);
  EXPECT_LT(distanceToWall(found[0].end, kFarWall), 0.03);
  EXPECT_GT(found[0].length(), 0.8 * kFarWall.length());
  EXPECT_LT(std::abs(linemap::normalizeAngle(found[0].heading() - kFarWall.heading())), 1.0 * kDeg)
      << "observers on the left, as the wall is drawn";
  // Every keyframe saw it: each has a part, in its own laser frame, on the wall.
  EXPECT_EQ(parts.size(), keyframes.size());
  double longest = 0.0;
  for (const KeyframeOriginals& k : parts)
  {
    const Pose2& pose = keyframes[k.keyframe].pose;
    ASSERT_EQ(k.segments.size(), 1u);
    const Segment2 in_map = k.segments[0].transformed(pose);
    EXPECT_LT(distanceToWall(in_map.start, kFarWall), 0.03);
    EXPECT_LT(distanceToWall(in_map.end, kFarWall), 0.03);
    longest = std::max(longest, in_map.length());
  }
  // Each scan sees the whole wall (within 18 degrees of straight ahead): its part spans most of it.
  EXPECT_GT(longest, 10.0);
}

TEST(MapLevelLines, ClutterGetsNoLine)
{
  // Posts of 0.3 m at random spots 15-25 m ahead: points seen from many keyframes, but no wall.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(15.0, 25.0), y(-10.0, 10.0), a(0.0, linemap::kPi);
  std::vector<Segment2> posts;
  for (int i = 0; i < 60; ++i)
  {
    const Vec2 c(x(rng), y(rng)), d(0.15 * std::cos(a(rng)), 0.15 * std::sin(a(rng)));
    posts.emplace_back(c - d, c + d);
  }
  const std::vector<KeyframeInfo> keyframes = drive();
  MapLevelParams coarse;
  coarse.lines.coarse_beam_fill = true;
  for (const MapLevelParams& params : {MapLevelParams(), coarse})
  {
    MapLevelLines lines = observed(keyframes, posts, params);
    std::vector<Segment2> found;
    lines.extract(keyframes, {}, &found);
    for (const Segment2& s : found)
      EXPECT_LT(s.length(), 0.5) << "a line through posts (coarse_beam_fill " << params.lines.coarse_beam_fill
                                 << ")";
  }
}

/// Five keyframes over 0.8 m, and a wall 6 m long 15-20 m away seen at 45-55 degrees of incidence:
/// each scan has about 13 returns on it, 0.46 m apart along it (farther than max_gap, within the sensor
/// model's gap of 0.8 m at that range), so all five together put points in at most 65 of its 120 bins.
std::vector<KeyframeInfo> glimpse()
{
  std::vector<KeyframeInfo> keyframes = drive();
  keyframes.resize(5);
  return keyframes;
}
const Segment2 kGrazedWall(Vec2(16.0, 10.0), Vec2(10.0, 10.0));  // the robot (y < 10) on its left

TEST(MapLevelLines, AWallSampledCoarselyByEveryScanIsFilledBetweenNeighbouringBeamsWhenAskedTo)
{
  const std::vector<KeyframeInfo> keyframes = glimpse();
  std::vector<Segment2> found;
  observed(keyframes, {kGrazedWall}).extract(keyframes, {}, &found);
  EXPECT_TRUE(found.empty()) << "its points alone fill at most 54 % of the bins, below min_fill";

  MapLevelParams coarse;
  coarse.lines.coarse_beam_fill = true;
  found.clear();
  observed(keyframes, {kGrazedWall}, coarse).extract(keyframes, {}, &found);
  ASSERT_EQ(found.size(), 1u);
  // Its points' sigma at 20 m is 5.4 cm across (range and registration), the fit over 65 of them better.
  EXPECT_LT(distanceToWall(found[0].start, kGrazedWall), 0.05);
  EXPECT_LT(distanceToWall(found[0].end, kGrazedWall), 0.05);
  EXPECT_GT(found[0].length(), 0.8 * kGrazedWall.length());
  EXPECT_LT(std::abs(linemap::normalizeAngle(found[0].heading() - kGrazedWall.heading())), 2.0 * kDeg);

  // Posts 0.3 m wide every 0.8 m along the same line: close enough for one run of points, but the
  // beams between them return nothing, so no two neighbouring beams end on the line across a gap.
  std::vector<Segment2> posts;
  for (double x = 10.0; x <= 16.01; x += 0.8) posts.emplace_back(Vec2(x + 0.15, 10.0), Vec2(x - 0.15, 10.0));
  found.clear();
  observed(keyframes, posts, coarse).extract(keyframes, {}, &found);
  for (const Segment2& s : found) EXPECT_LT(s.length(), 0.5) << "a line through a row of posts";
}

TEST(MapLevelLines, AWallSeenBetweenPanelsInFrontOfItGetsLinesWhereItWasSeen)
{
  // The far wall behind panels 1 m wide, 1 m in front of it, every 2.5 m. Over the 10 m drive each
  // panel's shadow on the wall moves by 0.42 m, so a stretch of about 0.6 m behind each one is never seen,
  // and the 2 m between is seen by every keyframe. The hidden stretches are narrower than the gap one
  // surface's neighbouring 1 degree beams may leave at 25 m (about 0.9 m): the wall's points make one run
  // along it, which fills too little of its length (a quarter hidden) to pass min_fill as a whole.
  std::vector<Segment2> walls{kFarWall};
  std::vector<double> hidden_centres;
  for (double y = -7.0; y <= 7.01; y += 2.5)
  {
    walls.emplace_back(Vec2(24.0, y + 0.5), Vec2(24.0, y - 0.5));
    hidden_centres.push_back(y * 25.0 / 24.0);  // seen from the drive's middle, y = 0
  }
  const std::vector<KeyframeInfo> keyframes = drive();
  std::vector<Segment2> found;
  observed(keyframes, walls).extract(keyframes, {}, &found);
  double on_wall = 0.0;
  for (const Segment2& s : found)
  {
    if (distanceToWall(s.start, kFarWall) > 0.05 || distanceToWall(s.end, kFarWall) > 0.05) continue;
    on_wall += s.length();
    const double lo = std::min(s.start.y(), s.end.y()), hi = std::max(s.start.y(), s.end.y());
    for (double c : hidden_centres)
      EXPECT_FALSE(lo < c - 0.1 && hi > c + 0.1) << "a line across the stretch hidden behind the panel at y "
                                                 << c * 24.0 / 25.0 << ": " << lo << " to " << hi;
  }
  // The wall's seen stretches between its ends (y -8 to 8, the panels' hidden 0.6 m each aside): about
  // 12 m; the lines end within a gap's width of each stretch's end.
  EXPECT_GT(on_wall, 8.0);
}

TEST(MapLevelLines, AWallTheMapOrTheKeyframesOwnSegmentsHoldGetsNoLine)
{
  const std::vector<KeyframeInfo> keyframes = drive();
  // Mapped, its face turned to the keyframes.
  MapLevelLines lines = observed(keyframes, {kFarWall});
  std::vector<Segment2> found;
  lines.extract(keyframes, {{0, kFarWall, 1}}, &found);
  EXPECT_TRUE(found.empty());
  // Mapped only on its other face (reversed): this face is still unmapped.
  MapLevelLines other = observed(keyframes, {kFarWall});
  found.clear();
  other.extract(keyframes, {{0, Segment2(kFarWall.end, kFarWall.start), 1}}, &found);
  EXPECT_EQ(found.size(), 1u);
  // Explained by each keyframe's own segment.
  std::mt19937 rng(1);
  MapLevelLines own{MapLevelParams()};
  for (const KeyframeInfo& k : keyframes)
    own.addKeyframe(k.index, cast(k.pose, {kFarWall}, Laser(), rng),
                    {kFarWall.transformed(k.pose.inverse())});
  found.clear();
  own.extract(keyframes, {}, &found);
  EXPECT_TRUE(found.empty());
}

TEST(MapLevelLines, AKeyframeSearchedFromIsSearchedAgainOnlyWhenNewOrMoved)
{
  const std::vector<KeyframeInfo> keyframes = drive();
  MapLevelLines lines = observed(keyframes, {kFarWall});
  std::vector<Segment2> found;
  lines.extract(keyframes, {}, &found);
  ASSERT_EQ(found.size(), 1u);
  // Nothing moved, nothing new: the same points give no seed (the wall is not drawn again).
  found.clear();
  lines.extract(keyframes, {}, &found);
  EXPECT_TRUE(found.empty());
  // Nudged by 0.1 m, as a back end nudges poses with each trajectory: not sought again.
  std::vector<KeyframeInfo> nudged = keyframes;
  for (KeyframeInfo& k : nudged) k.pose.x += 0.1;
  found.clear();
  lines.extract(nudged, {}, &found);
  EXPECT_TRUE(found.empty());
  // Every keyframe moved by a metre (a loop closed): the wall is sought again, and found where they now
  // see it.
  std::vector<KeyframeInfo> moved = keyframes;
  for (KeyframeInfo& k : moved) k.pose.x += 1.0;
  found.clear();
  lines.extract(moved, {}, &found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].start.x(), 26.0, 0.03);
}

TEST(MapLevelLines, ThroughTheMapperTheLineIsOriginalsOfItsKeyframesAndMovesWithThem)
{
  OnlineMapperParams params;
  params.keyframe_source = KeyframeSource::kTf;
  params.gate.distance = 0.1;
  params.map_level.every_keyframes = 0;  // the pass is called below
  OnlineMapper mapper(makeMerger("cae", linemap::ParamSet()), params);
  std::mt19937 rng(3);
  const std::vector<KeyframeInfo> keyframes = drive();
  for (const KeyframeInfo& k : keyframes)
  {
    StampedScan scan;
    scan.stamp = 1.0 + static_cast<double>(k.index);
    scan.laser = k.pose;
    scan.beams = std::make_shared<KeyframeScan>(cast(k.pose, {kFarWall}, Laser(), rng));
    ASSERT_EQ(mapper.addScan(scan), ScanOutcome::kKeyframe);
  }
  EXPECT_TRUE(mapper.merger().map().empty()) << "no scan gave a segment";
  EXPECT_TRUE(mapper.extractMapLevel());
  const std::vector<MapSegment> map = mapper.merger().map();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_LT(distanceToWall(map[0].segment.start, kFarWall), 0.03);
  EXPECT_LT(distanceToWall(map[0].segment.end, kFarWall), 0.03);
  std::set<std::uint64_t> seen_by;
  for (const Leaf& leaf : mapper.merger().leaves(map[0].id)) seen_by.insert(leaf.keyframe);
  EXPECT_GE(seen_by.size(), 40u) << "provenance to the keyframes that saw the wall";
  EXPECT_EQ(mapper.counters().map_level_lines, 1u);
  EXPECT_FALSE(mapper.extractMapLevel()) << "found once";

  // The keyframes move 0.5 m back: the wall, made of their originals, moves with them.
  std::vector<std::pair<std::uint64_t, Pose2>> moved;
  for (const KeyframeInfo& k : mapper.merger().keyframes())
    moved.emplace_back(k.index, Pose2(k.pose.x - 0.5, k.pose.y, k.pose.theta));
  mapper.merger().adjust(moved);
  const std::vector<MapSegment> after = mapper.merger().map();
  ASSERT_EQ(after.size(), 1u);
  EXPECT_NEAR(after[0].segment.start.x(), 24.5, 0.03);
  EXPECT_NEAR(after[0].segment.end.x(), 24.5, 0.03);
}

TEST(MapLevelLines, TheMapperSearchesEveryFiftyKeyframesWithoutATrajectory)
{
  OnlineMapperParams params;
  params.keyframe_source = KeyframeSource::kTf;
  params.gate.distance = 0.1;
  ASSERT_EQ(params.map_level.every_keyframes, 50);
  OnlineMapper mapper(makeMerger("cae", linemap::ParamSet()), params);
  std::mt19937 rng(3);
  for (const KeyframeInfo& k : drive())
  {
    StampedScan scan;
    scan.stamp = 1.0 + static_cast<double>(k.index);
    scan.laser = k.pose;
    scan.beams = std::make_shared<KeyframeScan>(cast(k.pose, {kFarWall}, Laser(), rng));
    mapper.addScan(scan);
    // The pass comes with the 50th keyframe, not before.
    EXPECT_EQ(mapper.counters().map_level_passes, k.index + 1 >= 50 ? 1u : 0u) << "keyframe " << k.index;
  }
  EXPECT_EQ(mapper.merger().map().size(), 1u);
}

TEST(MapLevelLines, BadParametersAreNamed)
{
  linemap::ParamSet ps;
  ps.set("map_level/min_keyframes", "1");
  try
  {
    MapLevelParams::fromParams(ps);
    FAIL() << "min_keyframes 1 accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("map_level/min_keyframes"), std::string::npos) << e.what();
  }
  linemap::ParamSet sensor;
  sensor.set("map_level/range_sigma", "-1");
  try
  {
    MapLevelParams::fromParams(sensor);
    FAIL() << "a negative range_sigma accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("map_level"), std::string::npos) << e.what();
  }
}

TEST(MapLevelLines, SegmentSetsWaitForTheirScanAndLeaveInOrder)
{
  const auto scan = [](double stamp)
  {
    StampedScan s;
    s.stamp = stamp;
    return s;
  };
  const auto beams = std::make_shared<KeyframeScan>();
  // No scan ever came (nothing publishes them): every set leaves at once, without.
  ScanPairing<int> none;
  none.addSegments(scan(1.0), 1);
  ASSERT_EQ(none.ready().size(), 1u);
  // A set before its scan waits; the scan releases it with its beams, and the set after it waits.
  ScanPairing<int> pairing;
  pairing.addScan(1.0, beams);
  auto out = pairing.ready();
  pairing.addSegments(scan(1.0), 1);
  out = pairing.ready();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].first.beams, beams);
  pairing.addSegments(scan(2.0), 2);
  pairing.addSegments(scan(3.0), 3);
  EXPECT_TRUE(pairing.ready().empty()) << "scan 2 has not come";
  pairing.addScan(2.0, beams);
  out = pairing.ready();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].second, 2);
  // Scan 3 lost: scan 4 comes first, and set 3 leaves without a scan.
  pairing.addScan(4.0, beams);
  out = pairing.ready();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].second, 3);
  EXPECT_EQ(out[0].first.beams, nullptr);
  // At most max_waiting sets wait.
  ScanPairing<int> bounded(200, 2);
  bounded.addScan(0.5, beams);
  for (int i = 1; i <= 3; ++i) bounded.addSegments(scan(i), i);
  out = bounded.ready();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].second, 1);
}
