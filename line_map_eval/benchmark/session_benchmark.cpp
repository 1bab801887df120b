// session_benchmark: how long loading a session file takes (linemap_batch LOG --slam --save-session F):
// reading and checking the file, restoring the SLAM from it, and loading its line map into CAE-RLSM;
// the median and slowest of RUNS loads. With --continue LOG: what mapping LOG costs per scan when it
// continues the session (found by global localization first, as linemap_batch LOG --slam --session F) and
// when it is mapped alone, in CPU time of the SLAM (the search for the start apart).
//
//   rosrun line_map_eval session_benchmark SESSION_FILE [--runs N] [--continue LOG [--whole LOG]]   (from the
//   repository root)
// With --whole WHOLE (the uninterrupted log the session's log and LOG were cut from): what LOG's scans cost
// at the end of that one drive, where they revisit the first part's places as a continuation does.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/slam/laser_slam.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "linemap/small_helpers.hpp"

using line_map_eval::benchmark::Clock;
using line_map_eval::benchmark::millisSince;

namespace
{
/// Per scan, the SLAM's CPU time mapping `log` alone and continuing the session `path` with it.
/// `whole` (optional): the uninterrupted log the session's log and `log` were cut from; the same scans of
/// `log` then also cost what they cost at the end of one drive (the whole log's SLAM less its first part's).
void continuationCost(const std::string& path, const std::string& log, const std::string& whole)
{
  using namespace line_map_eval;
  const Recording run = fromCarmen(readCarmenLog(log), nullptr);
  // The shipped parameters: under $LINEMAP_ROOT, else the working directory (the repository's root).
  const char* root = std::getenv("LINEMAP_ROOT");
  const auto config = [root](const char* name)
  { return std::vector<std::string>{std::string(root ? root : ".") + "/config/" + name}; };
  const auto slam = line_map_merging::LaserSlamParams::fromParams(loadParameterFiles(config("slam.yaml")));
  const auto localizer =
      line_map_merging::LocalizerParams::fromParams(loadParameterFiles(config("localization.yaml")));
  const SlamRecordingResult alone = runSlam(run, slam);
  const SessionsRun continued =
      runSessions({run}, line_map_merging::readSessionFile(path).slam, slam, localizer, true);
  const double scans = static_cast<double>(run.scans.size());
  std::printf("mapping %s (%zu scans), SLAM CPU per scan:\n  alone                              %8.2f ms\n",
              log.c_str(), run.scans.size(), 1e3 * alone.cpu_seconds / scans);
  if (!continued.localized_at[0])
  {
    std::printf("  continuing the session: the start was not found\n");
    return;
  }
  std::printf("  continuing the session             %8.2f ms (%.2fx; found at scan %zu, search %.1f s CPU)\n",
              1e3 * continued.slam_cpu_seconds[0] / scans, continued.slam_cpu_seconds[0] / alone.cpu_seconds,
              *continued.localized_at[0], continued.cpu_seconds - continued.slam_cpu_seconds[0]);
  // Where the difference goes: the back end's work per scan (wall time of its steps).
  const auto parts = [scans](const char* what, const line_map_merging::SlamCounters& c)
  {
    std::printf("  %-34s optimisation %.2f ms (%zu runs), loop search %.2f ms (%zu attempts, %zu accepted)\n",
                what, c.total_optimization_ms / scans, c.optimizations, c.total_loop_ms / scans,
                c.loop_attempts, c.loops_accepted);
  };
  parts("alone, per scan:", alone.counters);
  parts("continuing, per scan:", continued.counters[0]);
  if (whole.empty()) return;
  const Recording drive = fromCarmen(readCarmenLog(whole), nullptr);
  if (drive.scans.size() <= run.scans.size())
  {
    std::printf("  %s is not longer than %s: no uninterrupted drive to compare with\n", whole.c_str(),
                log.c_str());
    return;
  }
  const SlamRecordingResult all = runSlam(drive, slam);
  const SlamRecordingResult before =
      runSlam(recordingPart(drive, 0, drive.scans.size() - run.scans.size(), false), slam);
  const double last = all.cpu_seconds - before.cpu_seconds;
  std::printf("  the same scans ending one drive (%s) %8.2f ms (continuing: %.2fx)\n", whole.c_str(),
              1e3 * last / scans, continued.slam_cpu_seconds[0] / last);
}
}  // namespace

int main(int argc, char** argv)
{
  const char* usage = "usage: session_benchmark SESSION_FILE [--runs N] [--continue LOG [--whole LOG]]";
  if (argc < 2 || argv[1][0] == '-')
  {
    std::fprintf(stderr, "%s\n", usage);
    return 2;
  }
  const std::string path = argv[1];
  std::size_t runs = 5;
  std::string log, whole;
  if (const auto stop = line_map_eval::benchmark::parseOptions(
          argc - 1, argv + 1, "session_benchmark", usage,
          {{"--runs", [&](const std::string& v) { runs = std::max<std::size_t>(1, std::stoul(v)); }},
           {"--continue", [&](const std::string& v) { log = v; }},
           {"--whole", [&](const std::string& v) { whole = v; }}}))
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
  if (!log.empty()) continuationCost(path, log, whole);
  return 0;
}
