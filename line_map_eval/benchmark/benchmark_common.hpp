// What the benchmarks share: timing, the Intel corrected keyframes and the `--name value` options.
#pragma once

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace line_map_eval::benchmark
{
using Clock = std::chrono::steady_clock;

inline double millis(Clock::time_point a, Clock::time_point b)
{
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Milliseconds since `start`.
inline double millisSince(Clock::time_point start)
{
  return millis(start, Clock::now());
}

/// The keyframe of one scan at `laser_pose`, its segments from `extractor`.
inline line_map_merging::Keyframe extractKeyframe(line_extraction::LineExtractor& extractor,
                                                  const std::vector<float>& ranges, const ScanGeometry& g,
                                                  std::size_t index, double stamp,
                                                  const linemap::Pose2& laser_pose)
{
  const line_extraction::ScanInput input = scanInput(g, ranges);
  line_map_merging::Keyframe k;
  k.index = index;
  k.stamp = stamp;
  k.pose = laser_pose;
  for (const auto& s : extractor.extract(input).segments) k.segments.emplace_back(s.start, s.end);
  return k;
}

/// Every scan of a corrected CARMEN log as a keyframe at its laser pose, segments extracted with the
/// default extractor (srg) under `params` (the built-in defaults when empty).
inline std::vector<line_map_merging::Keyframe> intelKeyframes(const std::string& path,
                                                              const linemap::ParamSet& params = {})
{
  const CarmenLog log = readCarmenLog(path);
  if (log.scans.empty()) throw std::runtime_error(path + ": no scans");
  line_extraction::LineExtractor extractor{params};
  std::vector<line_map_merging::Keyframe> out;
  for (std::size_t i = 0; i < log.scans.size(); ++i)
  {
    const auto& scan = log.scans[i];
    // Intel writes no-return readings as 81.83 m (datasets README).
    const ScanGeometry g = carmenBeamGeometry(scan.ranges.size(), 81.83);
    out.push_back(extractKeyframe(extractor, scan.ranges, g, i, scan.timestamp, scan.laser_pose));
  }
  return out;
}

/// Option name -> what to do with its value.
using OptionHandlers = std::map<std::string, std::function<void(const std::string&)>>;

/// Reads `--name value` pairs. Returns the exit code when the program should stop: 0 after --help, 2
/// on anything unknown (both print `usage`); exits with 2 when a value is missing.
inline std::optional<int> parseOptions(int argc, char** argv, const char* program, const char* usage,
                                       const OptionHandlers& options)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    const auto handler = options.find(a);
    if (handler == options.end())
    {
      std::fprintf(stderr, "%s\n", usage);
      return a == "--help" ? 0 : 2;
    }
    if (i + 1 >= argc)
    {
      std::fprintf(stderr, "%s: %s needs a value\n", program, a.c_str());
      std::exit(2);
    }
    handler->second(argv[++i]);
  }
  return std::nullopt;
}
}  // namespace line_map_eval::benchmark
