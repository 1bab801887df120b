// mergers_benchmark: every merger of line_map_merging (makeMerger names) on the simulated worlds
// (every scan a keyframe at its TRUE laser pose) and on the Intel corrected keyframes (GMapping
// poses), segments extracted with the default extractor (srg). One row per dataset and method: map
// segments, shortest/longest/mean segment length, total runtime (all addKeyframe calls + map()) and,
// for the online methods, the per-keyframe addKeyframe time (median, 99th percentile and maximum). Median
// over --runs runs. Prints a table and writes JSON. Targets: every method <= 1 s on Intel, online ones <= 20
// ms per keyframe.
//
//   rosrun line_map_eval mergers_benchmark [--intel PATH] [--worlds DIR] [--json PATH] [--runs N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "linemap/small_helpers.hpp"

namespace
{
using line_map_eval::benchmark::Clock;
using line_map_eval::benchmark::extractKeyframe;
using line_map_eval::benchmark::intelKeyframes;
using line_map_eval::benchmark::millis;
using line_map_merging::Keyframe;

struct Dataset
{
  std::string name;
  std::vector<Keyframe> keyframes;
  std::size_t segments = 0;
};

Dataset simulated(const std::string& path)
{
  const auto sim = line_map_eval::simulate(line_map_eval::loadWorld(path));
  Dataset d;
  d.name = "sim:" + sim.world.name;
  line_extraction::LineExtractor extractor{linemap::ParamSet()};
  for (std::size_t i = 0; i < sim.recording.scans.size(); ++i)
    d.keyframes.push_back(extractKeyframe(extractor, sim.recording.scans[i].ranges, sim.recording.geometry, i,
                                          sim.recording.scans[i].stamp, sim.truth.scans[i].pose));
  return d;
}

Dataset intel(const std::string& path)
{
  Dataset d;
  d.name = "intel-corrected";
  d.keyframes = intelKeyframes(path);
  return d;
}

struct Row
{
  std::string dataset, method;
  bool online = false;
  std::size_t keyframes = 0, leaves = 0, segments = 0;
  double shortest = 0.0, longest = 0.0, mean = 0.0;
  double total_ms = 0.0;
  double frame_median_ms = std::nan(""), frame_p99_ms = std::nan(""), frame_max_ms = std::nan("");
};

Row measure(const Dataset& d, const std::string& method, int runs)
{
  Row row;
  row.dataset = d.name;
  row.method = method;
  std::vector<double> totals, medians, p99s, maxima;
  for (int r = 0; r < runs; ++r)
  {
    auto merger = line_map_merging::makeMerger(method, linemap::ParamSet());
    std::vector<double> frames;
    frames.reserve(d.keyframes.size());
    const auto t0 = Clock::now();
    for (const Keyframe& k : d.keyframes)
    {
      const auto a = Clock::now();
      merger->addKeyframe(k);
      frames.push_back(millis(a, Clock::now()));
    }
    const auto map = merger->map();
    totals.push_back(millis(t0, Clock::now()));
    medians.push_back(linemap::median(frames));
    p99s.push_back(linemap::percentile(frames, 0.99));
    maxima.push_back(*std::max_element(frames.begin(), frames.end()));
    if (r == 0)
    {
      // Offline methods only store in addKeyframe: the map is their work.
      row.online = method == "cae" || method == "oto";
      row.keyframes = merger->keyframeCount();
      row.leaves = merger->leafCount();
      row.segments = map.size();
      double sum = 0.0;
      row.shortest = map.empty() ? 0.0 : std::numeric_limits<double>::infinity();
      for (const auto& m : map)
      {
        const double l = m.segment.length();
        row.shortest = std::min(row.shortest, l);
        row.longest = std::max(row.longest, l);
        sum += l;
      }
      row.mean = map.empty() ? 0.0 : sum / static_cast<double>(map.size());
    }
  }
  row.total_ms = linemap::median(totals);
  if (row.online)
  {
    row.frame_median_ms = linemap::median(medians);
    row.frame_p99_ms = linemap::median(p99s);
    row.frame_max_ms = linemap::median(maxima);
  }
  return row;
}

std::string jsonNumber(double v)
{
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// The simulated worlds and Intel, each skipped (with a message) when it cannot be read.
std::vector<Dataset> readDatasets(const std::string& worlds, const std::string& intel_path)
{
  std::vector<Dataset> datasets;
  for (const char* w : {"square_room", "loop", "office"})
  {
    try
    {
      datasets.push_back(simulated(worlds + "/" + w + ".yaml"));
    }
    catch (const std::exception& e)
    {
      std::fprintf(stderr, "mergers_benchmark: world %s skipped: %s\n", w, e.what());
    }
  }
  try
  {
    datasets.push_back(intel(intel_path));
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mergers_benchmark: Intel skipped: %s\n", e.what());
  }
  return datasets;
}

void printTable(const std::vector<Row>& rows)
{
  std::printf("%-18s %-12s %6s %7s %8s %8s %8s %8s %10s %11s %10s %10s\n", "dataset", "method", "kf",
              "leaves", "segments", "min [m]", "max [m]", "mean [m]", "total [ms]", "frame med", "frame p99",
              "frame max");
  for (const Row& r : rows)
  {
    std::printf("%-18s %-12s %6zu %7zu %8zu %8.3f %8.3f %8.3f %10.2f", r.dataset.c_str(), r.method.c_str(),
                r.keyframes, r.leaves, r.segments, r.shortest, r.longest, r.mean, r.total_ms);
    if (r.online)
      std::printf(" %11.4f %10.4f %10.4f\n", r.frame_median_ms, r.frame_p99_ms, r.frame_max_ms);
    else
      std::printf(" %11s %10s %10s\n", "-", "-", "-");
  }
}

bool writeJson(const std::vector<Row>& rows, int runs, const std::string& json)
{
  std::ofstream out(json);
  out << "{\n  \"runs\": " << runs << ",\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i)
  {
    const Row& r = rows[i];
    out << "    {\"dataset\": \"" << r.dataset << "\", \"method\": \"" << r.method
        << "\", \"online\": " << (r.online ? "true" : "false") << ", \"keyframes\": " << r.keyframes
        << ", \"leaves\": " << r.leaves << ", \"segments\": " << r.segments
        << ", \"shortest_m\": " << jsonNumber(r.shortest) << ", \"longest_m\": " << jsonNumber(r.longest)
        << ", \"mean_m\": " << jsonNumber(r.mean) << ", \"total_ms\": " << jsonNumber(r.total_ms)
        << ", \"frame_median_ms\": " << jsonNumber(r.frame_median_ms)
        << ", \"frame_p99_ms\": " << jsonNumber(r.frame_p99_ms)
        << ", \"frame_max_ms\": " << jsonNumber(r.frame_max_ms) << "}" << (i + 1 < rows.size() ? "," : "")
        << "\n";
  }
  out << "  ]\n}\n";
  return static_cast<bool>(out);
}
}  // namespace

int main(int argc, char** argv)
{
  // Defaults relative to this file: line_map_eval/benchmark/ -> repository root and the shared datasets.
  const std::string here = __FILE__;
  const std::string root = here.substr(0, here.rfind('/')) + "/../..";
  std::string intel_path = root + "/../shared/datasets/intel-corrected.log.gz";
  std::string worlds = root + "/config/worlds";
  std::string json = "mergers_benchmark.json";
  int runs = 3;
  if (const auto stop = line_map_eval::benchmark::parseOptions(
          argc, argv, "mergers_benchmark",
          "usage: mergers_benchmark [--intel PATH] [--worlds DIR] [--json PATH] [--runs N]",
          {{"--intel", [&](const std::string& v) { intel_path = v; }},
           {"--worlds", [&](const std::string& v) { worlds = v; }},
           {"--json", [&](const std::string& v) { json = v; }},
           {"--runs", [&](const std::string& v) { runs = std::max(1, std::atoi(v.c_str())); }}}))
    return *stop;

  const std::vector<Dataset> datasets = readDatasets(worlds, intel_path);
  if (datasets.empty())
  {
    std::fprintf(stderr, "mergers_benchmark: no dataset could be read\n");
    return 1;
  }
  std::vector<Row> rows;
  try
  {
    for (const Dataset& d : datasets)
      for (const std::string& m : line_map_merging::mergerNames()) rows.push_back(measure(d, m, runs));
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mergers_benchmark: %s\n", e.what());
    return 1;
  }
  printTable(rows);
  if (!writeJson(rows, runs, json))
  {
    std::fprintf(stderr, "mergers_benchmark: cannot write %s\n", json.c_str());
    return 1;
  }
  std::printf("JSON: %s\n", json.c_str());
  return 0;
}
