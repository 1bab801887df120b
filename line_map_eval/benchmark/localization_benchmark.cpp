// localization_benchmark: tracking time per scan and global localization success of the line-map
// localizer on a CARMEN log and a saved map of it. First the whole log is tracked from the first
// scan's pose (the reference trajectory, unless --reference gives one), then TRIALS times the
// localizer starts at a random scan from a random wrong pose (anywhere in the map's bounding box, any
// heading, at least 1 m off) and runs SCANS scans: a trial succeeds when the pose is localized and
// within 0.3 m and 5 degrees of the reference by then, and still at the last scan.
// Then KIDNAPPINGS times a localizer tracks the log from its first scan up to a random scan in its
// middle half, and the robot is carried at least 3 m away unknown to the odometry: the scans continue
// from another random scan of the log, with the odometry rebased to go on from where it stopped. A
// kidnapping is recovered when the pose is right again within SCANS scans and stays so.
//
//   rosrun line_map_eval localization_benchmark RAW_LOG MAP_FILE [--initial-pose X,Y,THETA]
//       [--reference FILE] [--trials N] [--kidnappings N] [--scans N] [--seed N] [--config FILE]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/datasets/localization_recording.hpp"
#include "linemap/small_helpers.hpp"

using namespace line_map_eval;
using linemap::percentile;

namespace
{
bool near(const Pose2& a, const Pose2& b)
{
  return std::hypot(a.x - b.x, a.y - b.y) <= 0.3 &&
         std::fabs(linemap::normalizeAngle(a.theta - b.theta)) <= 5.0 * linemap::kPi / 180.0;
}
/// Scans after `start` from which the pose stayed localized and right up to the last one fed.
struct RecoveryWatch
{
  static constexpr std::size_t kNever = static_cast<std::size_t>(-1);
  std::size_t good_since = kNever;
  void observe(std::size_t scans_since_start, bool right)
  {
    if (right && good_since == kNever) good_since = scans_since_start;
    if (!right) good_since = kNever;
  }
  bool recovered() const { return good_since != kNever; }
};

void runKidnappings(const Recording& recording, const std::vector<linemap::Segment2>& segments,
                    const line_map_merging::LocalizerParams& params, const Pose2& initial,
                    const std::vector<Pose2>& ref, std::size_t kidnappings, std::size_t scans,
                    std::mt19937& rng)
{
  const std::size_t n = recording.scans.size();
  std::uniform_int_distribution<std::size_t> at(n / 4, 3 * n / 4), to(0, n - scans - 1);
  std::size_t recovered = 0;
  std::vector<double> recovery_scans;
  for (std::size_t t = 0; t < kidnappings; ++t)
  {
    const std::size_t kidnap = at(rng);
    std::size_t resume;
    do resume = to(rng);
    while (std::hypot(ref[resume].x - ref[kidnap].x, ref[resume].y - ref[kidnap].y) < 3.0);
    line_map_merging::LineMapLocalizer localizer(segments, params);
    localizer.setPose(initial);
    for (std::size_t i = 0; i < kidnap; ++i) localizer.addScan(localizerScan(recording, i));
    const bool tracked_before =
        localizer.localized() && near(localizer.addScan(localizerScan(recording, kidnap)).pose, ref[kidnap]);
    // The odometry goes on from its reading at the kidnapping: the carrying was not driven.
    const auto odom_at = [&](std::size_t i) { return localizerScan(recording, i).odom; };
    const std::optional<Pose2> odom_kidnap = odom_at(kidnap), odom_resume = odom_at(resume);
    const double stamp_shift = recording.scans[kidnap].stamp + 0.1 - recording.scans[resume].stamp;
    RecoveryWatch watch;
    for (std::size_t i = resume; i < resume + scans; ++i)
    {
      line_map_merging::LocalizerScan scan = localizerScan(recording, i);
      scan.stamp += stamp_shift;
      if (scan.odom && odom_kidnap && odom_resume)
        scan.odom = *odom_kidnap * odom_resume->inverse() * *scan.odom;
      const auto r = localizer.addScan(scan);
      watch.observe(i - resume, r.localized && near(r.pose, ref[i]));
    }
    recovered += watch.recovered();
    if (watch.recovered()) recovery_scans.push_back(static_cast<double>(watch.good_since));
    std::printf("kidnapping %2zu: at scan %5zu (%s before) to scan %5zu, %.1f m away: %s", t, kidnap,
                tracked_before ? "tracked" : "NOT tracked", resume,
                std::hypot(ref[resume].x - ref[kidnap].x, ref[resume].y - ref[kidnap].y),
                watch.recovered() ? "recovered" : "NOT recovered");
    if (watch.recovered()) std::printf(" after %zu scans", watch.good_since);
    std::printf(" (lost %zu, recovered %zu, replaced by a rival %zu)\n", localizer.counters().lost,
                localizer.counters().recovered, localizer.counters().replaced);
  }
  std::printf("kidnapping: %zu of %zu recovered within %zu scans; median %.0f scans to recover\n", recovered,
              kidnappings, scans, percentile(recovery_scans, 0.5));
}
struct Arguments
{
  std::vector<std::string> positional;
  std::string reference, config;
  Pose2 initial;
  std::size_t trials = 20, kidnappings = 20, scans = 200;
  unsigned seed = 1;
};

/// The command line; the exit code when it is wrong.
std::optional<int> parseArguments(int argc, char** argv, Arguments& a)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--initial-pose" && has_value)
    {
      char c1 = 0, c2 = 0;
      std::istringstream f(argv[++i]);
      f >> a.initial.x >> c1 >> a.initial.y >> c2 >> a.initial.theta;
    }
    else if (arg == "--reference" && has_value)
      a.reference = argv[++i];
    else if (arg == "--config" && has_value)
      a.config = argv[++i];
    else if (arg == "--trials" && has_value)
      a.trials = std::stoul(argv[++i]);
    else if (arg == "--kidnappings" && has_value)
      a.kidnappings = std::stoul(argv[++i]);
    else if (arg == "--scans" && has_value)
      a.scans = std::stoul(argv[++i]);
    else if (arg == "--seed" && has_value)
      a.seed = static_cast<unsigned>(std::stoul(argv[++i]));
    else if (!arg.empty() && arg[0] == '-')
    {
      std::cerr << "localization_benchmark: unknown option " << arg << "\n";
      return 2;
    }
    else
      a.positional.push_back(arg);
  }
  if (a.positional.size() != 2)
  {
    std::cerr
        << "usage: localization_benchmark RAW_LOG MAP_FILE [--initial-pose X,Y,THETA] [--reference FILE]\n"
           "       [--trials N] [--kidnappings N] [--scans N] [--seed N] [--config FILE]\n";
    return 2;
  }
  return std::nullopt;
}

/// 'timestamp x y theta' per line in scan order (linemap_relations --write), one per scan.
std::vector<Pose2> readReference(const std::string& reference, std::size_t scans)
{
  std::ifstream in(reference);
  std::vector<Pose2> ref;
  double t, x, y, th;
  while (in >> t >> x >> y >> th) ref.push_back({x, y, th});
  if (ref.size() != scans)
    throw std::runtime_error(reference + ": " + std::to_string(ref.size()) + " poses for " +
                             std::to_string(scans) + " scans");
  return ref;
}

void printTracking(const LocalizationRunResult& tracked, std::size_t segments)
{
  std::printf(
      "tracking: %zu scans, %zu map segments, per scan median %.3f ms, mean %.3f ms, p95 %.3f ms, "
      "max %.2f ms; %zu lost\n",
      tracked.scan_ms.size(), segments, percentile(tracked.scan_ms, 0.5),
      std::accumulate(tracked.scan_ms.begin(), tracked.scan_ms.end(), 0.0) /
          std::max<std::size_t>(1, tracked.scan_ms.size()),
      percentile(tracked.scan_ms, 0.95), percentile(tracked.scan_ms, 1.0), tracked.counters.lost);
}

/// Global localization from random wrong poses at random scans (see the top of this file).
void runTrials(const Recording& recording, const std::vector<linemap::Segment2>& segments,
               const line_map_merging::LocalizerParams& params, const std::vector<Pose2>& ref,
               std::size_t trials, std::size_t scans, std::mt19937& rng)
{
  line_map_merging::LineMapLocalizer probe(segments, params);
  const auto lo = probe.index().lower(), hi = probe.index().upper();
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y()),
      ut(-linemap::kPi, linemap::kPi);
  std::uniform_int_distribution<std::size_t> us(0, recording.scans.size() - scans - 1);
  std::size_t successes = 0;
  std::vector<double> search_ms, recovery_scans;
  for (std::size_t t = 0; t < trials; ++t)
  {
    const std::size_t first = us(rng);
    Pose2 wrong;
    do wrong = {ux(rng), uy(rng), ut(rng)};
    while (std::hypot(wrong.x - ref[first].x, wrong.y - ref[first].y) < 1.0);
    line_map_merging::LineMapLocalizer localizer(segments, params);
    localizer.setPose(wrong);
    RecoveryWatch watch;
    std::size_t searches_seen = 0;
    for (std::size_t i = first; i < first + scans; ++i)
    {
      const auto r = localizer.addScan(localizerScan(recording, i));
      if (localizer.counters().global_searches > searches_seen)
      {
        searches_seen = localizer.counters().global_searches;
        search_ms.push_back(localizer.counters().last_global_search_ms);
      }
      watch.observe(i - first, r.localized && near(r.pose, ref[i]));
    }
    const bool success = watch.recovered();
    const std::size_t good_since = watch.good_since;
    successes += success;
    if (success) recovery_scans.push_back(static_cast<double>(good_since));
    std::printf("trial %2zu: scan %5zu, wrong pose (%.2f, %.2f, %.0f deg): %s", t, first, wrong.x, wrong.y,
                wrong.theta * 180.0 / linemap::kPi, success ? "recovered" : "NOT recovered");
    if (success) std::printf(" after %zu scans", good_since);
    std::printf(" (lost %zu, recovered %zu, replaced by a rival %zu, global searches %zu)\n",
                localizer.counters().lost, localizer.counters().recovered, localizer.counters().replaced,
                localizer.counters().global_searches);
  }
  std::printf(
      "global localization: %zu of %zu recovered within %zu scans; median %.0f scans to recover; "
      "global search median %.0f ms, max %.0f ms\n",
      successes, trials, scans, percentile(recovery_scans, 0.5), percentile(search_ms, 0.5),
      percentile(search_ms, 1.0));
}
}  // namespace

int main(int argc, char** argv)
{
  Arguments args;
  if (const auto stop = parseArguments(argc, argv, args)) return *stop;
  try
  {
    const CarmenLog raw = readCarmenLog(args.positional[0]);
    const Recording recording = fromCarmen(raw, nullptr);
    const auto segments = line_map_merging::loadLineMapSegments(args.positional[1]);
    std::vector<std::string> files;
    if (!args.config.empty()) files.push_back(args.config);
    const auto params = line_map_merging::LocalizerParams::fromParams(loadParameterFiles(files));

    const LocalizationRunResult tracked = runLocalization(recording, segments, params, args.initial);
    printTracking(tracked, segments.size());
    const std::vector<Pose2> ref =
        args.reference.empty() ? tracked.scan_poses : readReference(args.reference, recording.scans.size());
    std::mt19937 rng(args.seed);
    runTrials(recording, segments, params, ref, args.trials, args.scans, rng);
    runKidnappings(recording, segments, params, args.initial, ref, args.kidnappings, args.scans, rng);
  }
  catch (const std::exception& e)
  {
    std::cerr << "localization_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
