// structure_benchmark: how long classifying the registered points of a corrected log as straight
// structure takes (structure_coverage.hpp: the fine scale alone, and with the smeared scale, the
// default), once per lookup table in the evaluator nodelet and once per batch run; the median and slowest
// of RUNS, with the structure length each finds.
//
//   rosrun line_map_eval structure_benchmark CORRECTED_LOG... [--runs N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/structure_coverage.hpp"
#include "linemap/small_helpers.hpp"

using line_map_eval::benchmark::Clock;
using line_map_eval::benchmark::millisSince;

int main(int argc, char** argv)
{
  const char* usage = "usage: structure_benchmark CORRECTED_LOG... [--runs N]";
  std::vector<std::string> logs;
  int first_option = 1;
  while (first_option < argc && argv[first_option][0] != '-') logs.push_back(argv[first_option++]);
  if (logs.empty())
  {
    std::fprintf(stderr, "%s\n", usage);
    return 2;
  }
  std::size_t runs = 5;
  if (const auto stop = line_map_eval::benchmark::parseOptions(
          argc - first_option + 1, argv + first_option - 1, "structure_benchmark", usage,
          {{"--runs", [&](const std::string& v) { runs = std::max<std::size_t>(1, std::stoul(v)); }}}))
    return *stop;
  const double sigma = line_map_eval::LookupTableParams().sigma;
  line_map_eval::StructureParams fine_only;
  fine_only.smear_band = 0.0;
  std::printf("%-28s %9s %22s %22s\n", "log", "points", "fine scale: ms (m)", "with smeared: ms (m)");
  for (const std::string& log : logs)
  {
    // Every scan at its corrected pose (the batch tool registers its keyframes only: fewer points).
    const std::vector<linemap::Vec2> points =
        line_map_eval::registeredScanPoints(line_map_eval::loadCarmenRegistered(log).recording);
    std::vector<double> fine_ms, full_ms;
    double fine_length = 0.0, full_length = 0.0;
    for (std::size_t r = 0; r < runs; ++r)
    {
      auto t = Clock::now();
      fine_length = line_map_eval::classifyStructure(points, sigma, fine_only).length;
      fine_ms.push_back(millisSince(t));
      t = Clock::now();
      full_length = line_map_eval::classifyStructure(points, sigma, {}).length;
      full_ms.push_back(millisSince(t));
    }
    std::printf("%-28s %9zu %8.1f / %6.1f (%5.0f) %8.1f / %6.1f (%5.0f)\n", linemap::fileStem(log).c_str(),
                points.size(), linemap::median(fine_ms), *std::max_element(fine_ms.begin(), fine_ms.end()),
                fine_length, linemap::median(full_ms), *std::max_element(full_ms.begin(), full_ms.end()),
                full_length);
  }
  std::printf("(median / slowest of %zu runs; in brackets the metres of straight structure found)\n", runs);
  return 0;
}
