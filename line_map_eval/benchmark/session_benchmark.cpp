// session_benchmark: how long loading a session file takes (linemap_batch LOG --slam --save-session F):
// reading and checking the file, restoring the SLAM from it, and loading its line map into CAE-RLSM;
// the median and slowest of RUNS loads.
//
//   rosrun line_map_eval session_benchmark SESSION_FILE [--runs N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/slam/laser_slam.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "linemap/small_helpers.hpp"

using line_map_eval::benchmark::Clock;
using line_map_eval::benchmark::millisSince;

int main(int argc, char** argv)
{
  const char* usage = "usage: session_benchmark SESSION_FILE [--runs N]";
  if (argc < 2 || argv[1][0] == '-')
  {
    std::fprintf(stderr, "%s\n", usage);
    return 2;
  }
  const std::string path = argv[1];
  std::size_t runs = 5;
  if (const auto stop = line_map_eval::benchmark::parseOptions(
          argc - 1, argv + 1, "session_benchmark", usage,
          {{"--runs", [&](const std::string& v) { runs = std::max<std::size_t>(1, std::stoul(v)); }}}))
    return *stop;
  std::vector<double> read_ms, restore_ms, map_ms, total_ms;
  std::size_t keyframes = 0, segments = 0;
  for (std::size_t r = 0; r < runs; ++r)
  {
    const auto start = Clock::now();
    const line_map_merging::Session session = line_map_merging::readSessionFile(path);
    read_ms.push_back(millisSince(start));
    auto t = Clock::now();
    line_map_merging::LaserSlam slam;
    slam.restore(session.slam);
    restore_ms.push_back(millisSince(t));
    t = Clock::now();
    line_map_merging::CaeRlsm merger;
    if (!session.line_map.empty()) merger.loadText(session.line_map, path);
    map_ms.push_back(millisSince(t));
    total_ms.push_back(millisSince(start));
    keyframes = slam.keyframes().size();
    segments = merger.segmentCount();
  }
  auto line = [](const char* what, const std::vector<double>& ms)
  {
    std::printf("  %-34s median %8.1f ms, slowest %8.1f ms\n", what, linemap::median(ms),
                *std::max_element(ms.begin(), ms.end()));
  };
  std::printf("session %s: %zu keyframes, %zu map segments, %zu loads\n", path.c_str(), keyframes, segments,
              runs);
  line("read and check the file", read_ms);
  line("restore the SLAM", restore_ms);
  line("load the line map (CAE-RLSM)", map_ms);
  line("total", total_ms);
  return 0;
}
