// Crash safety of saving: a process killed (SIGKILL) at a random moment while saving a map over an
// existing file leaves either the old or the new file, never a mix or a truncated one.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>
#include <tuple>

#include "line_map_merging/mergers/merger.hpp"

using line_map_merging::Keyframe;
using line_map_merging::Merger;

namespace
{
using Clock = std::chrono::steady_clock;

std::string slurp(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Inode, size and modification time: changes when a file is replaced or rewritten.
std::tuple<ino_t, off_t, long, long> fileId(const std::string& path)
{
  struct stat st
  {
  };
  if (::stat(path.c_str(), &st) != 0) return {};
  return {st.st_ino, st.st_size, st.st_mtim.tv_sec, st.st_mtim.tv_nsec};
}

double secondsSince(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// A map of `keyframes` x 10 leaves: keyframe k sees walls 10k .. 10k + 9 (mod 10^4) of a grid of
/// 2 m walls, from a pose jittered by a centimetre, so every wall fuses about keyframes / 1000
/// leaves (a map of 1e4 segments saves in about half the time of one of 1e5).
std::unique_ptr<Merger> wallGridMap(std::size_t keyframes, unsigned seed)
{
  auto merger = line_map_merging::makeMerger("cae", linemap::ParamSet());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  for (std::size_t i = 0; i < keyframes; ++i)
  {
    Keyframe k;
    k.index = i;
    k.stamp = static_cast<double>(i);
    k.pose = linemap::Pose2(jitter(rng), jitter(rng), 0.1 * jitter(rng));
    for (std::size_t j = 0; j < 10; ++j)
    {
      const std::size_t w = (10 * i + j) % 10000;
      const linemap::Vec2 a(5.0 * static_cast<double>(w % 100), 0.5 * static_cast<double>(w / 100));
      k.segments.emplace_back(a, a + linemap::Vec2(2.0, 0.0));
    }
    merger->addKeyframe(k);
  }
  return merger;
}
}  // namespace

TEST(SaveKill, KilledSaveLeavesTheOldOrTheNewFile)
{
  const std::string dir = (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) +
                          "save_kill_" + std::to_string(::getpid()) + "_";
  const std::string target = dir + "map.yaml", ref_a = dir + "a.yaml", ref_b = dir + "b.yaml";

  // Two maps of >= 1e5 leaves that differ from the first segment on (different seeds).
  const auto a = wallGridMap(10000, 1), b = wallGridMap(10001, 2);
  ASSERT_GE(a->leafCount(), 100000u);
  ASSERT_GE(b->leafCount(), 100000u);
  auto t0 = Clock::now();
  a->save(ref_a);
  const double save_s = secondsSince(t0);
  b->save(ref_b);
  const std::string bytes_a = slurp(ref_a), bytes_b = slurp(ref_b);
  ASSERT_NE(bytes_a, bytes_b);
  // Saving is deterministic, so a file byte-equal to a reference loads as that reference does:
  // load each reference once (a full load of 1e5 leaves takes about as long as a save) and
  // compare bytes after every kill.
  for (const auto& [path, merger] : {std::make_pair(ref_a, a.get()), std::make_pair(ref_b, b.get())})
  {
    auto loaded = line_map_merging::makeMerger("cae", linemap::ParamSet());
    loaded->load(path);
    EXPECT_EQ(loaded->leafCount(), merger->leafCount());
    EXPECT_EQ(loaded->segmentCount(), merger->segmentCount());
    EXPECT_EQ(loaded->map().front().segment.start.x(), merger->map().front().segment.start.x());
  }

  a->save(target);  // the "old" file
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> delay(0.0, save_s);
  int runs = 0, kept_old = 0, got_new = 0, temp_left = 0, in_write = 0;
  bool holds_a = true;
  t0 = Clock::now();
  while (runs < 30 || (secondsSince(t0) < 20.0 && runs < 200))
  {
    // The child saves the map the file does not hold, so every kill interrupts a real replacement.
    const Merger& next = holds_a ? *b : *a;
    const auto before = fileId(target);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0)
    {
      try
      {
        next.save(target);
      }
      catch (...)
      {
        ::_exit(2);
      }
      ::_exit(0);
    }
    // A save spends most of its time encoding in memory, before any file is touched. Every other run
    // therefore waits until the temporary file appears (or the target changes, should a save write
    // it in place) and kills within the next 1 % of the save time: the write, fsync and rename.
    // A save killed between creating and renaming its temporary file leaves "<target>.tmp<pid of
    // the saving process>" behind (the target itself is never touched until the rename).
    const std::string temp = target + ".tmp" + std::to_string(child);
    int status = 0;
    bool reaped = false;
    if (runs % 2 == 1)
    {
      // Waits for the event itself, however slow a loaded machine makes the child: the temporary
      // file appearing, or the child having finished.
      bool touched = false;
      while (!touched && !reaped)
      {
        std::this_thread::sleep_for(std::chrono::microseconds(50));
        touched = ::access(temp.c_str(), F_OK) == 0 || fileId(target) != before;
        if (!touched)
        {
          const pid_t done = ::waitpid(child, &status, WNOHANG);
          ASSERT_GE(done, 0);
          reaped = done == child;
        }
      }
      if (touched) ++in_write;
      if (!reaped) std::this_thread::sleep_for(std::chrono::duration<double>(0.01 * delay(rng)));
    }
    else
      std::this_thread::sleep_for(std::chrono::duration<double>(delay(rng)));
    if (!reaped)
    {
      ::kill(child, SIGKILL);
      ASSERT_EQ(::waitpid(child, &status, 0), child);
    }
    ASSERT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0)) << status;
    ++runs;

    const std::string now = slurp(target);
    const bool is_a = now == bytes_a, is_b = now == bytes_b;
    ASSERT_TRUE(is_a || is_b) << "run " << runs << ": " << target << " (" << now.size()
                              << " bytes) is neither the old nor the new map";
    if (is_a == holds_a)
      ++kept_old;
    else
      ++got_new;
    holds_a = is_a;
    if (std::remove(temp.c_str()) == 0) ++temp_left;
  }
  std::printf(
      "save %.3f s (%zu leaves); %d kills in %.1f s (%d after the temporary file appeared): %d kept "
      "the old file, %d left the new one, %d left a temporary file\n",
      save_s, a->leafCount(), runs, secondsSince(t0), in_write, kept_old, got_new, temp_left);
  EXPECT_GT(in_write, 0) << "no kill came after the save began writing";
  for (const std::string& p : {target, ref_a, ref_b}) std::remove(p.c_str());
}
