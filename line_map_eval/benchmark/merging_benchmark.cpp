// merging_benchmark: CAE-RLSM through the online path of linemap_batch (the OnlineMapper the nodelets
// run) on Intel and ACES raw + corrected and on the hall world, with the time of each of its steps;
// per-frame OTM-ILSM time on the Intel corrected keyframes and on a synthetic map grown to 1e5 map
// segments (1e6 leaves); MP-GMA time for 1e6 leaves on 1 and 2 threads. Prints the figures and
// writes them as JSON.
//
//   rosrun line_map_eval merging_benchmark [--intel PATH] [--datasets DIR] [--config-dir DIR]
//                                          [--json PATH] [--segments N] [--runs N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "linemap/small_helpers.hpp"

namespace
{
using line_map_eval::benchmark::Clock;
using line_map_eval::benchmark::intelKeyframes;
using line_map_eval::benchmark::millis;
using line_map_merging::CaeParams;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using linemap::percentile;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

/// CAE-RLSM on one dataset through the batch's online path: medians over the runs, and the share of
/// each step from one more run with the step timers on (they add a little time of their own).
struct OnlineFigures
{
  std::string name;
  std::size_t keyframes = 0, segments = 0, adjustments = 0;
  double frame_median = std::nan(""), frame_p99 = std::nan(""), total = std::nan(""), adjust = std::nan("");
  std::vector<line_map_merging::StepTime> steps;
};

OnlineFigures timeOnline(const std::string& name, const line_map_eval::BatchDataset& dataset,
                         const linemap::ParamSet& params, int runs)
{
  line_map_eval::BatchOptions options;
  options.mergers = {"cae"};
  options.params = params;
  options.progress = false;
  options.figure_formats = 0;
  OnlineFigures f;
  f.name = name;
  std::vector<double> medians, p99s, totals, adjusts;
  for (int r = 0; r <= runs; ++r)
  {
    options.time_steps = r == runs;
    const line_map_eval::MergerRun run = line_map_eval::runBatch(dataset, options).mergers.at(0);
    if (options.time_steps)
    {
      f.steps = run.step_ms;
      break;
    }
    medians.push_back(run.per_frame_ms);
    p99s.push_back(run.per_frame_p99_ms);
    totals.push_back(run.total_ms);
    adjusts.push_back(run.adjust_ms);
    f.keyframes = run.scans;
    f.segments = run.map_segments;
    f.adjustments = run.adjustments;
  }
  f.frame_median = linemap::median(medians);
  f.frame_p99 = linemap::median(p99s);
  f.total = linemap::median(totals);
  f.adjust = linemap::median(adjusts);
  double timed = 0.0;
  for (const auto& step : f.steps) timed += step.second;
  std::printf(
      "%s, cae online: %zu keyframes -> %zu segments; per keyframe median %.4f ms, p99 %.4f ms; "
      "%zu adjustments %.1f ms; total %.1f ms (medians of %d runs)\n  steps:",
      name.c_str(), f.keyframes, f.segments, f.frame_median, f.frame_p99, f.adjustments, f.adjust, f.total,
      runs);
  for (const auto& [step, ms] : f.steps)
    std::printf(" %s %.0f %%;", step.c_str(), timed > 0.0 ? 100.0 * ms / timed : 0.0);
  std::printf(" (of the merger's %.1f ms)\n", timed);
  return f;
}

/// Intel and ACES raw + corrected, and the hall world (1 degree laser), each skipped with a message
/// when it cannot be read.
std::vector<OnlineFigures> timeOnlinePath(const std::string& datasets, const std::string& config, int runs)
{
  std::vector<OnlineFigures> out;
  linemap::ParamSet params;
  try
  {
    params = line_map_eval::loadParameterFiles({config + "/line_extraction.yaml",
                                                config + "/line_map_merging.yaml",
                                                config + "/line_map_eval.yaml"});
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "merging_benchmark: online path skipped: %s\n", e.what());
    return out;
  }
  const auto run = [&](const std::string& name, const std::function<line_map_eval::BatchDataset()>& load)
  {
    try
    {
      out.push_back(timeOnline(name, load(), params, runs));
    }
    catch (const std::exception& e)
    {
      std::fprintf(stderr, "merging_benchmark: %s skipped: %s\n", name.c_str(), e.what());
    }
  };
  for (const char* log : {"intel", "aces"})
    run(std::string(log) + " raw + corrected",
        [&]
        {
          return line_map_eval::loadCarmenWithCorrection(datasets + "/" + log + ".clf.bz2",
                                                         datasets + "/" + log + "-corrected.log.gz");
        });
  run("hall world, 1 deg laser",
      [&]
      {
        return line_map_eval::simulatedDataset(line_map_eval::withSensorProfile(
            line_map_eval::loadWorld(config + "/worlds/hall.yaml"), config + "/sensors/laser_1deg_30m.yaml"));
      });
  return out;
}

/// Time of each addKeyframe() [ms], the merger fresh at the start.
std::vector<double> timeFrames(CaeRlsm& merger, const std::vector<Keyframe>& keyframes)
{
  std::vector<double> t;
  t.reserve(keyframes.size());
  for (const Keyframe& k : keyframes)
  {
    const auto t0 = Clock::now();
    merger.addKeyframe(k);
    t.push_back(millis(t0, Clock::now()));
  }
  return t;
}

/// `walls` random walls, one per 3 m grid cell, each seen 10 times, `per_frame` walls per keyframe:
/// blocks of 10 neighbouring walls are visited round-robin, so a keyframe sees distinct walls.
std::vector<Keyframe> syntheticKeyframes(std::size_t walls, std::size_t per_frame, std::uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  const std::size_t side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(walls))));
  std::vector<Segment2> w;
  for (std::size_t i = 0; i < walls; ++i)
  {
    const Vec2 c(3.0 * static_cast<double>(i % side), 3.0 * static_cast<double>(i / side));
    const double h = linemap::kPi * uni(rng);
    const Vec2 u(std::cos(h), std::sin(h));
    w.emplace_back(c - 0.9 * u, c + 0.9 * u);
  }
  std::vector<std::size_t> views;  // wall of each view, in visiting order
  for (std::size_t block = 0; block < walls; block += 10)
    for (int round = 0; round < 10; ++round)
      for (std::size_t i = block; i < std::min(walls, block + 10); ++i) views.push_back(i);
  std::vector<Keyframe> out;
  for (std::size_t v = 0; v < views.size(); v += per_frame)
  {
    Keyframe kf;
    kf.index = out.size();
    kf.stamp = static_cast<double>(kf.index);
    const Vec2 at = w[views[v]].midpoint();
    kf.pose = Pose2(at.x() + uni(rng), at.y() + uni(rng), linemap::kPi * uni(rng));
    const Pose2 inv = kf.pose.inverse();
    for (std::size_t j = v; j < std::min(views.size(), v + per_frame); ++j)
    {
      const Segment2& s = w[views[j]];
      const Vec2 u = (s.end - s.start).normalized(), n(-u.y(), u.x());
      const double off = 0.005 * noise(rng);
      const Segment2 seen(s.start + off * n + 0.05 * uni(rng) * u, s.end + off * n + 0.05 * uni(rng) * u);
      kf.segments.push_back(seen.transformed(inv));
    }
    out.push_back(std::move(kf));
  }
  return out;
}

struct GmaFigures
{
  double median_ms = 0.0;
  double next_frame_ms = 0.0;  ///< the first OTM frame after an adjustment (rebuilds the R-tree)
  std::size_t leaves = 0, segments = 0;
};

/// `consistent`: with the consistency pass (the default: regrouping); `crossings`: crossing resolution
/// after it (serial; not in the paper).
GmaFigures timeGma(const std::vector<Keyframe>& keyframes, int threads, bool consistent, bool crossings,
                   int runs)
{
  CaeParams p;
  p.threads = threads;
  p.consistent_adjustment = consistent;
  p.resolve_crossings = crossings;
  CaeRlsm merger(p);
  for (const Keyframe& k : keyframes) merger.addKeyframe(k);
  // Two pose sets 1 cm / 0.05 deg apart, alternated so every run moves every leaf.
  std::vector<std::pair<std::uint64_t, Pose2>> a, b;
  for (const Keyframe& k : keyframes)
  {
    a.emplace_back(k.index, Pose2(k.pose.x + 0.01, k.pose.y, k.pose.theta + 0.0009));
    b.emplace_back(k.index, k.pose);
  }
  std::vector<double> t, next;
  for (int r = 0; r < runs; ++r)
  {
    const auto t0 = Clock::now();
    merger.adjust(r % 2 == 0 ? a : b);
    t.push_back(millis(t0, Clock::now()));
    Keyframe probe;  // one segment far from the map
    probe.index = keyframes.size() + static_cast<std::size_t>(r);
    probe.segments.emplace_back(Vec2(-100.0 - 5.0 * r, -100.0), Vec2(-99.0 - 5.0 * r, -100.0));
    const auto t1 = Clock::now();
    merger.addKeyframe(probe);
    next.push_back(millis(t1, Clock::now()));
  }
  return {percentile(t, 0.5), percentile(next, 0.5), merger.leafCount(), merger.segmentCount()};
}

/// MP-GMA on 1 and 2 threads: the paper's (g), then with crossing resolution (x), then with the
/// consistency pass, the defaults (c).
struct GmaSet
{
  GmaFigures g1, g2, x1, x2, c1, c2;
};

GmaSet timeGmaSet(const std::vector<Keyframe>& synthetic, int runs)
{
  GmaSet s{timeGma(synthetic, 1, false, false, runs), timeGma(synthetic, 2, false, false, runs),
           timeGma(synthetic, 1, false, true, runs),  timeGma(synthetic, 2, false, true, runs),
           timeGma(synthetic, 1, true, true, runs),   timeGma(synthetic, 2, true, true, runs)};
  std::printf(
      "MP-GMA (paper), %zu leaves / %zu segments: 1 thread %.1f ms, 2 threads %.1f ms, speed-up %.2fx; "
      "next OTM frame (R-tree rebuild) %.1f ms\n",
      s.g1.leaves, s.g1.segments, s.g1.median_ms, s.g2.median_ms, s.g1.median_ms / s.g2.median_ms,
      s.g2.next_frame_ms);
  std::printf("MP-GMA + crossing resolution: 1 thread %.1f ms, 2 threads %.1f ms, speed-up %.2fx\n",
              s.x1.median_ms, s.x2.median_ms, s.x1.median_ms / s.x2.median_ms);
  std::printf("MP-GMA + consistency pass: 1 thread %.1f ms, 2 threads %.1f ms, speed-up %.2fx\n",
              s.c1.median_ms, s.c2.median_ms, s.c1.median_ms / s.c2.median_ms);
  return s;
}

/// OTM per frame on the Intel corrected keyframes, `runs` times.
struct IntelFigures
{
  double median = std::nan(""), p99 = std::nan("");
  std::size_t frames = 0, segments = 0, leaves = 0;
};

/// `min_length`: srg's shortest segment [m]; 0 = the default. With the paper's 0.6 m the input is the
/// size of the one the CAE-RLSM authors' own code was timed on.
IntelFigures timeIntel(const std::string& intel, int runs, double min_length = 0.0)
{
  IntelFigures f;
  try
  {
    linemap::ParamSet params;
    if (min_length > 0.0) params.set("srg/min_length", std::to_string(min_length));
    const auto keyframes = intelKeyframes(intel, params);
    std::vector<double> all;
    for (int r = 0; r < runs; ++r)
    {
      CaeRlsm merger;
      const auto t = timeFrames(merger, keyframes);
      all.insert(all.end(), t.begin(), t.end());
      f.segments = merger.segmentCount();
      f.leaves = merger.leafCount();
    }
    f.frames = keyframes.size();
    f.median = percentile(all, 0.5);
    f.p99 = percentile(all, 0.99);
    std::printf(
        "Intel corrected%s: %zu keyframes, %zu leaves -> %zu map segments; OTM per frame median %.4f ms, "
        "p99 %.4f ms (%d runs)\n",
        min_length > 0.0 ? (", srg min_length " + std::to_string(min_length).substr(0, 3) + " m").c_str()
                         : "",
        f.frames, f.leaves, f.segments, f.median, f.p99, runs);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "merging_benchmark: Intel part skipped: %s\n", e.what());
  }
  return f;
}

/// OTM per frame while a map grows to `walls` map segments, over its first and last frames.
struct GrowthFigures
{
  std::size_t keyframes = 0, per_frame = 0, leaves = 0, segments = 0, tail = 0;
  double first_median = 0.0, last_median = 0.0, last_p99 = 0.0;
};

GrowthFigures timeGrowth(CaeRlsm& grown, const std::vector<Keyframe>& synthetic, std::size_t per_frame)
{
  const auto t = timeFrames(grown, synthetic);
  const std::size_t tail = std::min<std::size_t>(1000, t.size());
  const std::vector<double> first(t.begin(), t.begin() + tail), last(t.end() - tail, t.end());
  const GrowthFigures f{synthetic.size(),
                        per_frame,
                        grown.leafCount(),
                        grown.segmentCount(),
                        tail,
                        percentile(first, 0.5),
                        percentile(last, 0.5),
                        percentile(last, 0.99)};
  std::printf(
      "Synthetic: %zu keyframes of %zu segments, %zu leaves -> %zu map segments; OTM per frame median "
      "%.4f ms (first %zu frames) / %.4f ms, p99 %.4f ms (last %zu frames)\n",
      f.keyframes, f.per_frame, f.leaves, f.segments, f.first_median, f.tail, f.last_median, f.last_p99,
      f.tail);
  return f;
}

/// The copy ConcurrentMapper takes on the merge thread before adjusting in the background.
void timeCopy(const CaeRlsm& grown, int runs)
{
  std::vector<double> copy_ms;
  for (int r = 0; r < std::max(3, runs); ++r)
  {
    const auto c0 = std::chrono::steady_clock::now();
    const auto copy = grown.clone();
    copy_ms.push_back(linemap::millisecondsSince(c0));
  }
  std::printf("Copy of that map for a background adjustment (merge thread): median %.1f ms\n",
              percentile(copy_ms, 0.5));
}

void writeJson(const std::string& json, const std::vector<OnlineFigures>& online, const IntelFigures& intel,
               const IntelFigures& intel_paper_input, const GrowthFigures& growth, const GmaSet& gma)
{
  const GmaFigures &g1 = gma.g1, &g2 = gma.g2, &x1 = gma.x1, &x2 = gma.x2, &c1 = gma.c1, &c2 = gma.c2;
  std::ofstream out(json);
  out << "{\n  \"online\": [";
  for (const OnlineFigures& f : online)
  {
    out << (&f == &online.front() ? "\n" : ",\n") << "    {\"dataset\": \"" << f.name
        << "\", \"keyframes\": " << f.keyframes << ", \"map_segments\": " << f.segments
        << ", \"frame_median_ms\": " << f.frame_median << ", \"frame_p99_ms\": " << f.frame_p99
        << ", \"adjustments\": " << f.adjustments << ", \"adjust_ms\": " << f.adjust
        << ", \"total_ms\": " << f.total << ", \"step_ms\": {";
    for (const auto& [step, ms] : f.steps)
      out << (&step == &f.steps.front().first ? "" : ", ") << "\"" << step << "\": " << ms;
    out << "}}";
  }
  out << "\n  ],\n"
      << "  \"intel\": {\"keyframes\": " << intel.frames << ", \"leaves\": " << intel.leaves
      << ", \"map_segments\": " << intel.segments << ", \"otm_median_ms\": " << intel.median
      << ", \"otm_p99_ms\": " << intel.p99 << "},\n"
      << "  \"intel_srg_min_length_0_6\": {\"leaves\": " << intel_paper_input.leaves
      << ", \"map_segments\": " << intel_paper_input.segments
      << ", \"otm_median_ms\": " << intel_paper_input.median << ", \"otm_p99_ms\": " << intel_paper_input.p99
      << "},\n"
      << "  \"synthetic\": {\"keyframes\": " << growth.keyframes << ", \"leaves\": " << growth.leaves
      << ", \"segments_per_keyframe\": " << growth.per_frame << ", \"map_segments\": " << growth.segments
      << ", \"otm_median_ms_first\": " << growth.first_median
      << ", \"otm_median_ms_last\": " << growth.last_median << ", \"otm_p99_ms_last\": " << growth.last_p99
      << "},\n"
      << "  \"gma\": {\"leaves\": " << g1.leaves << ", \"ms_1_thread\": " << g1.median_ms
      << ", \"ms_2_threads\": " << g2.median_ms << ", \"next_frame_ms\": " << g2.next_frame_ms
      << ", \"with_crossings_ms_1_thread\": " << x1.median_ms
      << ", \"with_crossings_ms_2_threads\": " << x2.median_ms
      << ", \"consistent_ms_1_thread\": " << c1.median_ms << ", \"consistent_ms_2_threads\": " << c2.median_ms
      << "}\n"
      << "}\n";
}
}  // namespace

int main(int argc, char** argv)
{
  // Default: the shared datasets next to the repository (this file is line_map_eval/benchmark/...).
  const std::string here = __FILE__;
  const std::string root = here.substr(0, here.rfind('/')) + "/../..";
  std::string datasets = root + "/../shared/datasets", config = root + "/config";
  std::string intel;
  std::string json = "merging_benchmark.json";
  std::size_t walls = 100000;
  int runs = 5;
  if (const auto stop = line_map_eval::benchmark::parseOptions(
          argc, argv, "merging_benchmark",
          "usage: merging_benchmark [--intel PATH] [--datasets DIR] [--config-dir DIR] [--json PATH]\n"
          "                         [--segments N] [--runs N]",
          {{"--intel", [&](const std::string& v) { intel = v; }},
           {"--datasets", [&](const std::string& v) { datasets = v; }},
           {"--config-dir", [&](const std::string& v) { config = v; }},
           {"--json", [&](const std::string& v) { json = v; }},
           {"--segments", [&](const std::string& v) { walls = std::strtoul(v.c_str(), nullptr, 10); }},
           {"--runs", [&](const std::string& v) { runs = std::max(1, std::atoi(v.c_str())); }}}))
    return *stop;
  if (walls < 100)
  {
    std::fprintf(stderr, "merging_benchmark: --segments must be >= 100\n");
    return 2;
  }
  if (intel.empty()) intel = datasets + "/intel-corrected.log.gz";
  try
  {
    // 0. The online path with its adjustments, step by step.
    const std::vector<OnlineFigures> online = timeOnlinePath(datasets, config, runs);

    // 1. Intel corrected keyframes, extracted with the default extractor (srg).
    const IntelFigures intel_figures = timeIntel(intel, runs);
    const IntelFigures intel_paper_input = timeIntel(intel, runs, 0.6);

    // 2. Synthetic map grown to `walls` map segments (10 leaves each).
    // As many segments per keyframe as the Intel keyframes have on average (3 when unknown).
    const std::size_t per_frame =
        intel_figures.frames > 0
            ? std::max<std::size_t>(1,
                                    (intel_figures.leaves + intel_figures.frames / 2) / intel_figures.frames)
            : 3;
    const auto synthetic = syntheticKeyframes(walls, per_frame, 7);
    CaeRlsm grown;
    const GrowthFigures growth = timeGrowth(grown, synthetic, per_frame);
    timeCopy(grown, runs);

    // 3. MP-GMA over all leaves, 1 and 2 threads.
    const GmaSet gma = timeGmaSet(synthetic, runs);
    writeJson(json, online, intel_figures, intel_paper_input, growth, gma);
    std::printf("wrote %s\n", json.c_str());
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "merging_benchmark: %s\n", e.what());
    return 1;
  }
  return 0;
}
