// Map files: round trip, load then adjust, every kind of bad file leaving the map untouched, and the
// stored file of each format version (test/map_files/).
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "synthetic_world.hpp"

using line_map_merging::CaeParams;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using line_map_merging::MapFileError;
using line_map_merging::MapSegment;
using linemap::Pose2;

namespace
{
std::string tempPath(const std::string& name)
{
  return (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) + "merge_test_" +
         std::to_string(::getpid()) + "_" + name;
}

std::string slurp(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void spit(const std::string& path, const std::string& text)
{
  std::ofstream out(path, std::ios::binary);
  out << text;
}

struct Fixture
{
  std::vector<Pose2> truth, drifted;
  std::vector<Keyframe> keyframes;
  Fixture()
  {
    synthetic::Corridor corridor;
    std::mt19937 rng(11);
    truth = corridor.loop(0.5, 6.0);
    drifted = synthetic::drift(truth, 0.003, 0.002, 1.01, rng);
    keyframes = synthetic::observe(corridor.walls(), truth, drifted, 4.0, rng);
    for (auto& k : keyframes) k.mount = Pose2(0.1, 0.0, 0.0);
  }
  std::vector<std::pair<std::uint64_t, Pose2>> truePoses() const
  {
    std::vector<std::pair<std::uint64_t, Pose2>> p;
    for (std::size_t i = 0; i < truth.size(); ++i) p.emplace_back(i, truth[i]);
    return p;
  }
};

void expectSameMap(const std::vector<MapSegment>& a, const std::vector<MapSegment>& b, double tol)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].merged_count, b[i].merged_count);
    EXPECT_NEAR((a[i].segment.start - b[i].segment.start).norm(), 0.0, tol);
    EXPECT_NEAR((a[i].segment.end - b[i].segment.end).norm(), 0.0, tol);
  }
}
}  // namespace

TEST(MapFile, SaveLoadSaveGivesIdenticalFiles)
{
  const Fixture f;
  CaeRlsm merger;
  for (const Keyframe& k : f.keyframes) merger.addKeyframe(k);
  const std::string first = tempPath("first.yaml"), second = tempPath("second.yaml");
  merger.save(first);
  CaeRlsm loaded;
  loaded.load(first);
  expectSameMap(loaded.map(), merger.map(), 0.0);
  EXPECT_EQ(loaded.leafCount(), merger.leafCount());
  EXPECT_EQ(loaded.keyframeCount(), merger.keyframeCount());
  EXPECT_EQ(loaded.nextId(), merger.nextId());
  EXPECT_EQ(loaded.keyframes().front().mount.x, 0.1);
  loaded.save(second);
  const std::string a = slurp(first), b = slurp(second);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
  EXPECT_EQ(a.rfind("format_version: 4", 0), 0u) << "format_version must come first";
  std::remove(first.c_str());
  std::remove(second.c_str());
}

TEST(MapFile, LoadThenAdjustMatchesAdjustingTheOriginal)
{
  const Fixture f;
  CaeRlsm merger;
  for (const Keyframe& k : f.keyframes) merger.addKeyframe(k);
  const std::string path = tempPath("adjust.yaml");
  merger.save(path);
  CaeRlsm loaded;
  loaded.load(path);
  merger.adjust(f.truePoses());
  loaded.adjust(f.truePoses());
  expectSameMap(loaded.map(), merger.map(), 1e-9);
  // New keyframes continue with fresh ids after a load.
  Keyframe extra;
  extra.index = 5000;
  extra.segments.push_back({linemap::Vec2(50, 50), linemap::Vec2(51, 50)});
  loaded.addKeyframe(extra);
  EXPECT_EQ(loaded.map().back().id, merger.nextId());
  std::remove(path.c_str());
}

TEST(MapFile, BadFilesLeaveTheMapUntouched)
{
  const Fixture f;
  CaeRlsm source;
  for (std::size_t i = 0; i < 40; ++i) source.addKeyframe(f.keyframes[i]);
  const std::string good = tempPath("good.yaml");
  source.save(good);
  const std::string text = slurp(good);

  CaeRlsm merger;  // a different, non-empty current map
  for (std::size_t i = 60; i < 80; ++i) merger.addKeyframe(f.keyframes[i]);
  const auto before = merger.map();
  const std::size_t before_leaves = merger.leafCount();

  const std::string bad = tempPath("bad.yaml");
  auto expectRejected = [&](const std::string& content, const std::string& what, const std::string& needle)
  {
    spit(bad, content);
    try
    {
      merger.load(bad);
      ADD_FAILURE() << what << ": accepted";
    }
    catch (const MapFileError& e)
    {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << what << ": " << e.what();
    }
    expectSameMap(merger.map(), before, 0.0);
    EXPECT_EQ(merger.leafCount(), before_leaves) << what;
  };

  try
  {
    merger.load(tempPath("missing.yaml"));
    ADD_FAILURE() << "missing file accepted";
  }
  catch (const MapFileError& e)
  {
    EXPECT_NE(std::string(e.what()).find("missing.yaml"), std::string::npos) << e.what();
  }
  expectSameMap(merger.map(), before, 0.0);

  expectRejected(text.substr(0, text.size() / 2), "truncated mid-file", bad);
  // Cut at a line boundary: still valid YAML, caught by the counts / end marker.
  const std::size_t cut = text.rfind('\n', text.size() * 3 / 4);
  expectRejected(text.substr(0, cut + 1), "truncated at a line", bad);
  expectRejected("", "empty", bad);
  expectRejected(std::string("\x01\x02garbage: [unclosed\n"), "garbage", bad);
  std::string wrong_version = text;
  wrong_version.replace(0, std::string("format_version: 4").size(), "format_version: 5");
  expectRejected(wrong_version, "wrong version", "format_version 5");
  std::string corrupt = text;
  const std::size_t pos = corrupt.find("segment: [") + 10;
  corrupt.replace(pos, 1, "x");
  expectRejected(corrupt, "corrupt number", "segments/segment");
  std::string dangling = text;
  const std::size_t leaves = dangling.find("leaves:");
  const std::size_t first = dangling.find("- [", leaves) + 3;
  dangling.insert(first, "77777");  // a keyframe index that does not exist
  expectRejected(dangling, "unknown keyframe", "keyframe");

  // And the good file still loads.
  merger.load(good);
  expectSameMap(merger.map(), source.map(), 0.0);
  std::remove(good.c_str());
  std::remove(bad.c_str());
}

// ---- Stored files of every format version (test/map_files/map_v<N>.yaml) ----
namespace
{
const std::string kMapFiles = std::string(LINEMAP_SOURCE_DIR) + "/test/map_files/";

/// The tiny map stored as test/map_files/map_v1.yaml: keyframes 0, 1 and 5 (indices need not be
/// contiguous); the walls x = 1 and y = 1.5 seen from keyframes 0 and 1 fuse, two pieces stay alone.
std::vector<Keyframe> handBuiltKeyframes()
{
  std::vector<Keyframe> k(3);
  k[0].index = 0;
  k[0].stamp = 10.0;
  k[0].pose = Pose2(0.0, 0.0, 0.0);
  k[0].segments = {{linemap::Vec2(1, -2), linemap::Vec2(1, 2)},
                   {linemap::Vec2(-2, 1.5), linemap::Vec2(3, 1.5)}};
  k[1].index = 1;
  k[1].stamp = 11.0;
  k[1].pose = Pose2(0.5, 0.0, 0.0);
  k[1].segments = {{linemap::Vec2(0.5, -1.5), linemap::Vec2(0.5, 1.8)},
                   {linemap::Vec2(-2, 1.5), linemap::Vec2(2, 1.5)},
                   {linemap::Vec2(2, -1), linemap::Vec2(3, -1)}};
  k[2].index = 5;
  k[2].stamp = 12.5;
  k[2].pose = Pose2(0.0, 3.0, 0.0);
  k[2].segments = {{linemap::Vec2(4, 0), linemap::Vec2(4, 1)}};
  for (auto& f : k) f.mount = Pose2(0.1, 0.0, 0.0);
  return k;
}

CaeRlsm handBuiltMap()
{
  CaeRlsm m;
  for (const Keyframe& k : handBuiltKeyframes()) m.addKeyframe(k);
  return m;
}

/// The first line of a file saved by this build, "format_version: N".
int currentFormatVersion()
{
  const std::string path = tempPath("version.yaml");
  handBuiltMap().save(path);
  const std::string text = slurp(path);
  std::remove(path.c_str());
  return std::stoi(text.substr(text.find(':') + 1));
}

std::vector<std::string> keysOf(const YAML::Node& map)
{
  std::vector<std::string> keys;
  for (const auto& kv : map) keys.push_back(kv.first.as<std::string>());
  return keys;
}
}  // namespace

// Set LINEMAP_WRITE_MAP_FILE=1 to (re)write the stored file of the current version from the
// hand-built map; only do so when bumping the format version, never to make this test pass.
TEST(MapFileVersions, StoredFileOfTheCurrentVersionMatchesWhatThisBuildWrites)
{
  const int version = currentFormatVersion();
  const std::string stored = kMapFiles + "map_v" + std::to_string(version) + ".yaml";
  if (std::getenv("LINEMAP_WRITE_MAP_FILE")) handBuiltMap().save(stored);
  ASSERT_TRUE(std::ifstream(stored).good())
      << "format version " << version << " has no stored file " << stored
      << ": keep one map file of each version (see the comment above this test)";
  // Same layout as a fresh save: a change of the format without a version bump shows here.
  const std::string fresh = tempPath("fresh.yaml");
  handBuiltMap().save(fresh);
  const YAML::Node a = YAML::LoadFile(stored), b = YAML::LoadFile(fresh);
  EXPECT_EQ(keysOf(a), keysOf(b));
  EXPECT_EQ(keysOf(a["parameters"]), keysOf(b["parameters"]));
  ASSERT_EQ(a["segments"].size(), b["segments"].size());
  for (std::size_t i = 0; i < a["segments"].size(); ++i)
  {
    EXPECT_EQ(keysOf(a["segments"][i]), keysOf(b["segments"][i]));
    EXPECT_EQ(YAML::Dump(a["segments"][i]["leaves"]), YAML::Dump(b["segments"][i]["leaves"]));
  }
  EXPECT_EQ(YAML::Dump(a["keyframes"]), YAML::Dump(b["keyframes"]));
  std::remove(fresh.c_str());
}

TEST(MapFileVersions, Version1FileLoadsWithTheHandBuiltContent)
{
  CaeRlsm m;
  m.load(kMapFiles + "map_v1.yaml");
  // Values of the hand-built map, not of a re-run of the merger.
  ASSERT_EQ(m.segmentCount(), 4u);
  EXPECT_EQ(m.leafCount(), 6u);
  EXPECT_EQ(m.nextId(), 4u);
  const auto map = m.map();
  const std::vector<std::uint64_t> ids{0, 1, 2, 3};
  const std::vector<std::uint32_t> counts{2, 2, 1, 1};
  const std::vector<std::array<double, 4>> ends{
      {1, -2, 1, 2}, {-2, 1.5, 3, 1.5}, {2.5, -1, 3.5, -1}, {4, 3, 4, 4}};
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    EXPECT_EQ(map[i].id, ids[i]);
    EXPECT_EQ(map[i].merged_count, counts[i]) << "segment " << i;
    EXPECT_NEAR(map[i].segment.start.x(), ends[i][0], 1e-9) << "segment " << i;
    EXPECT_NEAR(map[i].segment.start.y(), ends[i][1], 1e-9) << "segment " << i;
    EXPECT_NEAR(map[i].segment.end.x(), ends[i][2], 1e-9) << "segment " << i;
    EXPECT_NEAR(map[i].segment.end.y(), ends[i][3], 1e-9) << "segment " << i;
  }
  const auto built = handBuiltKeyframes();
  const auto kf = m.keyframes();
  ASSERT_EQ(kf.size(), built.size());
  for (std::size_t i = 0; i < kf.size(); ++i)
  {
    EXPECT_EQ(kf[i].index, built[i].index);
    EXPECT_EQ(kf[i].stamp, built[i].stamp);
    EXPECT_EQ(kf[i].pose.x, built[i].pose.x);
    EXPECT_EQ(kf[i].pose.y, built[i].pose.y);
    EXPECT_EQ(kf[i].pose.theta, built[i].pose.theta);
    EXPECT_EQ(kf[i].mount.x, 0.1);
  }
  // Provenance: the wall y = 1.5 holds the original segments of keyframes 0 and 1, as extracted.
  const auto leaves = m.leaves(1);
  ASSERT_EQ(leaves.size(), 2u);
  EXPECT_EQ(leaves[0].keyframe, 0u);
  EXPECT_EQ(leaves[0].segment.end.x(), 3.0);
  EXPECT_EQ(leaves[1].keyframe, 1u);
  EXPECT_EQ(leaves[1].segment.start.x(), -2.0);
}

TEST(MapFileVersions, Version2FileLoadsWithoutAbsorbingContainedSegments)
{
  // Version 2 predates absorb_contained: its maps were merged by the fusion conditions alone, and
  // adjust so after loading; a save writes the current version with the flag.
  CaeParams params;
  ASSERT_TRUE(params.absorb_contained);
  CaeRlsm m(params);
  m.load(kMapFiles + "map_v2.yaml");
  EXPECT_TRUE(m.params().map_merge);
  EXPECT_FALSE(m.params().absorb_contained);
  EXPECT_EQ(m.segmentCount(), 4u);
  const std::string path = tempPath("v2_resaved.yaml");
  m.save(path);
  const YAML::Node saved = YAML::LoadFile(path);
  std::remove(path.c_str());
  EXPECT_EQ(saved["format_version"].as<int>(), currentFormatVersion());
  EXPECT_FALSE(saved["parameters"]["absorb_contained"].as<bool>());
}

TEST(MapFileVersions, UnknownVersionAndDamagedCopiesNameTheFileAndKeepTheMap)
{
  const std::string text = slurp(kMapFiles + "map_v1.yaml");
  ASSERT_EQ(text.rfind("format_version: 1\n", 0), 0u);
  CaeRlsm merger = handBuiltMap();
  Keyframe extra;  // makes the current map differ from the file's
  extra.index = 9;
  extra.segments = {{linemap::Vec2(-5, -5), linemap::Vec2(-5, -4)}};
  merger.addKeyframe(extra);
  const auto before = merger.map();
  const std::string bad = tempPath("v99.yaml");
  auto expectRejected = [&](const std::string& content, const std::string& needle)
  {
    spit(bad, content);
    try
    {
      merger.load(bad);
      ADD_FAILURE() << needle << ": accepted";
    }
    catch (const MapFileError& e)
    {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    expectSameMap(merger.map(), before, 0.0);
    EXPECT_EQ(merger.leafCount(), 7u);
    EXPECT_EQ(merger.keyframeCount(), 4u);
  };
  expectRejected("format_version: 99\n" + text.substr(text.find('\n') + 1), "format_version 99");
  expectRejected(text.substr(0, text.size() * 2 / 3), "");
  std::remove(bad.c_str());
}
