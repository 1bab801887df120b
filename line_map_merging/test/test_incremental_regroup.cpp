// Incremental regrouping: an adjustment resumes from the last regroup's state when the keyframes that
// regroup covered kept their poses, and the map is then the one regrouping from scratch makes, byte for
// byte (the reference is the same merger with incremental_regroup off).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "cae_test.hpp"
#include "synthetic_world.hpp"

namespace
{
namespace fs = std::filesystem;

std::string savedFile(const CaeRlsm& merger, const std::string& name)
{
  const fs::path path = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".yaml");
  merger.save(path.string());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  fs::remove(path);
  return text.str();
}

CaeRlsm makeMerger(bool incremental)
{
  CaeParams p;
  p.incremental_regroup = incremental;
  return CaeRlsm(p);
}

/// A corridor loop seen on drifting odometry, as a back end corrects it: every `every` keyframes the
/// true poses of all keyframes so far (the old ones unchanged, bit for bit).
struct CorrectedLoop
{
  std::vector<Pose2> truth, drifted;
  std::vector<Keyframe> keyframes;

  explicit CorrectedLoop(std::uint32_t seed)
  {
    synthetic::Corridor corridor;
    std::mt19937 rng(seed);
    truth = corridor.loop(0.5, 6.0);
    drifted = synthetic::drift(truth, 0.003, 0.002, 1.01, rng);
    keyframes = synthetic::observe(corridor.walls(), truth, drifted, 4.0, rng);
  }

  std::vector<std::pair<std::uint64_t, Pose2>> truthUpTo(std::size_t count) const
  {
    return indexedPoses(
        std::vector<Pose2>(truth.begin(), truth.begin() + static_cast<std::ptrdiff_t>(count)));
  }
};
}  // namespace

TEST(IncrementalRegroup, ResumesWhereNothingMovedAndSavesTheSameFileAsFromScratch)
{
  const CorrectedLoop loop(11);
  ASSERT_GT(loop.keyframes.size(), 60u);
  CaeRlsm incremental = makeMerger(true), scratch = makeMerger(false);
  std::size_t adjustments = 0;
  for (std::size_t k = 0; k < loop.keyframes.size(); ++k)
  {
    incremental.addKeyframe(loop.keyframes[k]);
    scratch.addKeyframe(loop.keyframes[k]);
    if ((k + 1) % 10 != 0) continue;
    incremental.adjust(loop.truthUpTo(k + 1));
    scratch.adjust(loop.truthUpTo(k + 1));
    ++adjustments;
    ASSERT_EQ(savedFile(incremental, "incremental"), savedFile(scratch, "scratch")) << "after keyframe " << k;
  }
  ASSERT_GE(adjustments, 6u);
  // The first regroup has nothing to resume from; every later one finds the old keyframes unmoved.
  EXPECT_EQ(incremental.resumedRegroups(), adjustments - 1);
  EXPECT_EQ(scratch.resumedRegroups(), 0u);
}

TEST(IncrementalRegroup, AnOldKeyframeThatMovedMakesItStartAgain)
{
  const CorrectedLoop loop(12);
  CaeRlsm incremental = makeMerger(true), scratch = makeMerger(false);
  const std::size_t half = loop.keyframes.size() / 2;
  for (std::size_t k = 0; k < half; ++k)
  {
    incremental.addKeyframe(loop.keyframes[k]);
    scratch.addKeyframe(loop.keyframes[k]);
  }
  incremental.adjust(loop.truthUpTo(half));
  scratch.adjust(loop.truthUpTo(half));
  for (std::size_t k = half; k < loop.keyframes.size(); ++k)
  {
    incremental.addKeyframe(loop.keyframes[k]);
    scratch.addKeyframe(loop.keyframes[k]);
  }
  // Keyframe 3 goes back to its drifted pose (a back end changing its mind about the old part): its
  // leaves fall elsewhere, so resuming from the checkpoint would keep a grouping that no longer holds.
  auto poses = loop.truthUpTo(loop.keyframes.size());
  poses[3].second = loop.drifted[3] * Pose2(0.0, 0.3, 0.05);
  incremental.adjust(poses);
  scratch.adjust(poses);
  EXPECT_EQ(incremental.resumedRegroups(), 0u);
  EXPECT_EQ(savedFile(incremental, "incremental"), savedFile(scratch, "scratch"));

  // The smallest change counts: one bit of one coordinate.
  poses[3].second.x = std::nextafter(poses[3].second.x, 1e9);
  incremental.adjust(poses);
  scratch.adjust(poses);
  EXPECT_EQ(incremental.resumedRegroups(), 0u);
  EXPECT_EQ(savedFile(incremental, "incremental"), savedFile(scratch, "scratch"));

  // Unchanged poses: resumed, with nothing new to merge.
  incremental.adjust(poses);
  scratch.adjust(poses);
  EXPECT_EQ(incremental.resumedRegroups(), 1u);
  EXPECT_EQ(savedFile(incremental, "incremental"), savedFile(scratch, "scratch"));
}

TEST(IncrementalRegroup, ResetAndLoadForgetTheCheckpoint)
{
  // A second map on the same keyframe indices and poses as the first, from other segments: a stale
  // checkpoint matches its poses and would bring the first map's groups back.
  const CorrectedLoop loop(13);
  const std::size_t n = 20;
  const auto other = [&](std::size_t k)
  {
    Keyframe kf = loop.keyframes[k + n];
    kf.index = k;
    kf.pose = loop.drifted[k];
    return kf;
  };
  CaeRlsm merger = makeMerger(true), fresh = makeMerger(false);
  for (std::size_t k = 0; k < n; ++k) merger.addKeyframe(loop.keyframes[k]);
  merger.adjust(loop.truthUpTo(n));

  merger.reset();
  for (std::size_t k = 0; k < n; ++k)
  {
    merger.addKeyframe(other(k));
    fresh.addKeyframe(other(k));
  }
  merger.adjust(loop.truthUpTo(n));
  fresh.adjust(loop.truthUpTo(n));
  EXPECT_EQ(merger.resumedRegroups(), 0u);
  const std::string second = savedFile(fresh, "fresh");
  EXPECT_EQ(savedFile(merger, "after_reset"), second);

  // Load: the first map again, its checkpoint made, then the second map's file over it.
  merger.reset();
  for (std::size_t k = 0; k < n; ++k) merger.addKeyframe(loop.keyframes[k]);
  merger.adjust(loop.truthUpTo(n));
  const fs::path file = fs::temp_directory_path() / ("second_" + std::to_string(::getpid()) + ".yaml");
  fresh.save(file.string());
  merger.load(file.string());
  fs::remove(file);
  merger.adjust(loop.truthUpTo(n));
  fresh.adjust(loop.truthUpTo(n));
  EXPECT_EQ(merger.resumedRegroups(), 0u);
  EXPECT_EQ(savedFile(merger, "after_load"), savedFile(fresh, "fresh"));
}
