// Map files: round trip, load then adjust, and every kind of bad file leaving the map untouched.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "line_map_merging/cae_rlsm.hpp"
#include "synthetic_world.hpp"

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
  EXPECT_EQ(a.rfind("format_version: 1", 0), 0u) << "format_version must come first";
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
  wrong_version.replace(0, std::string("format_version: 1").size(), "format_version: 2");
  expectRejected(wrong_version, "wrong version", "format_version 2");
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
