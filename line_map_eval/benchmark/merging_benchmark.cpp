// merging_benchmark: per-frame OTM-ILSM time on the Intel corrected keyframes and on a synthetic
// map grown to 1e5 map segments (1e6 leaves), and MP-GMA time for 1e6 leaves on 1 and 2 threads.
// Prints the figures and writes them as JSON.
//
//   rosrun line_map_eval merging_benchmark [--intel PATH] [--json PATH] [--segments N] [--runs N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "linemap/small_helpers.hpp"

namespace
{
using Clock = std::chrono::steady_clock;
using line_map_merging::CaeParams;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

double ms(Clock::time_point a, Clock::time_point b)
{
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double percentile(std::vector<double> v, double q)
{
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  // Nearest rank: the smallest value with at least q of the samples at or below it.
  const double rank = std::ceil(q * static_cast<double>(v.size()));
  return v[static_cast<std::size_t>(std::max(1.0, rank)) - 1];
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
    t.push_back(ms(t0, Clock::now()));
  }
  return t;
}

std::vector<Keyframe> intelKeyframes(const std::string& path)
{
  const line_map_eval::CarmenLog log = line_map_eval::readCarmenLog(path);
  if (log.scans.empty()) throw std::runtime_error(path + ": no scans");
  linemap::ParamSet params;  // the extraction defaults (srg)
  line_extraction::LineExtractor extractor(params);
  std::vector<Keyframe> out;
  for (std::size_t i = 0; i < log.scans.size(); ++i)
  {
    const auto& scan = log.scans[i];
    const auto geometry = line_map_eval::carmenBeamGeometry(scan.ranges.size(), 81.83);
    const line_extraction::ScanInput input = line_map_eval::scanInput(geometry, scan.ranges);
    const auto& result = extractor.extract(input);
    Keyframe k;
    k.index = i;
    k.stamp = scan.timestamp;
    k.pose = Pose2(scan.laser_pose.x, scan.laser_pose.y, scan.laser_pose.theta);
    for (const auto& s : result.segments) k.segments.emplace_back(s.start, s.end);
    out.push_back(std::move(k));
  }
  return out;
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

GmaFigures timeGma(const std::vector<Keyframe>& keyframes, int threads, bool consistent, int runs)
{
  CaeParams p;
  p.threads = threads;
  p.consistent_adjustment = consistent;
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
    t.push_back(ms(t0, Clock::now()));
    Keyframe probe;  // one segment far from the map
    probe.index = keyframes.size() + static_cast<std::size_t>(r);
    probe.segments.emplace_back(Vec2(-100.0 - 5.0 * r, -100.0), Vec2(-99.0 - 5.0 * r, -100.0));
    const auto t1 = Clock::now();
    merger.addKeyframe(probe);
    next.push_back(ms(t1, Clock::now()));
  }
  return {percentile(t, 0.5), percentile(next, 0.5), merger.leafCount(), merger.segmentCount()};
}

}  // namespace

int main(int argc, char** argv)
{
  // Default: the shared datasets next to the repository (this file is line_map_eval/benchmark/...).
  const std::string here = __FILE__;
  std::string intel = here.substr(0, here.rfind('/')) + "/../../../shared/datasets/intel-corrected.log.gz";
  std::string json = "merging_benchmark.json";
  std::size_t walls = 100000;
  int runs = 5;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto value = [&]() -> std::string
    {
      if (i + 1 >= argc)
      {
        std::fprintf(stderr, "merging_benchmark: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--intel")
      intel = value();
    else if (a == "--json")
      json = value();
    else if (a == "--segments")
      walls = std::strtoul(value().c_str(), nullptr, 10);
    else if (a == "--runs")
      runs = std::max(1, std::atoi(value().c_str()));
    else
    {
      std::fprintf(stderr,
                   "usage: merging_benchmark [--intel PATH] [--json PATH] [--segments N] [--runs N]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (walls < 100)
  {
    std::fprintf(stderr, "merging_benchmark: --segments must be >= 100\n");
    return 2;
  }

  try
  {
    // 1. Intel corrected keyframes, extracted with the default extractor (srg).
    double intel_median = std::nan(""), intel_p99 = std::nan("");
    std::size_t intel_frames = 0, intel_segments = 0, intel_leaves = 0;
    try
    {
      const auto keyframes = intelKeyframes(intel);
      std::vector<double> all;
      for (int r = 0; r < runs; ++r)
      {
        CaeRlsm merger;
        const auto t = timeFrames(merger, keyframes);
        all.insert(all.end(), t.begin(), t.end());
        intel_segments = merger.segmentCount();
        intel_leaves = merger.leafCount();
      }
      intel_frames = keyframes.size();
      intel_median = percentile(all, 0.5);
      intel_p99 = percentile(all, 0.99);
      std::printf(
          "Intel corrected: %zu keyframes, %zu leaves -> %zu map segments; OTM per frame median %.4f ms, "
          "p99 %.4f ms (%d runs)\n",
          intel_frames, intel_leaves, intel_segments, intel_median, intel_p99, runs);
    }
    catch (const std::exception& e)
    {
      std::fprintf(stderr, "merging_benchmark: Intel part skipped: %s\n", e.what());
    }

    // 2. Synthetic map grown to `walls` map segments (10 leaves each).
    // As many segments per keyframe as the Intel keyframes have on average (3 when unknown).
    const std::size_t per_frame =
        intel_frames > 0 ? std::max<std::size_t>(1, (intel_leaves + intel_frames / 2) / intel_frames) : 3;
    const auto synthetic = syntheticKeyframes(walls, per_frame, 7);
    CaeRlsm grown;
    const auto t = timeFrames(grown, synthetic);
    const std::size_t tail = std::min<std::size_t>(1000, t.size());
    const std::vector<double> first(t.begin(), t.begin() + tail), last(t.end() - tail, t.end());
    std::printf(
        "Synthetic: %zu keyframes of %zu segments, %zu leaves -> %zu map segments; OTM per frame median "
        "%.4f ms (first %zu frames) / %.4f ms, p99 %.4f ms (last %zu frames)\n",
        synthetic.size(), per_frame, grown.leafCount(), grown.segmentCount(), percentile(first, 0.5), tail,
        percentile(last, 0.5), percentile(last, 0.99), tail);

    // The copy ConcurrentMapper takes on the merge thread before adjusting in the background.
    std::vector<double> copy_ms;
    for (int r = 0; r < std::max(3, runs); ++r)
    {
      const auto c0 = std::chrono::steady_clock::now();
      const auto copy = grown.clone();
      copy_ms.push_back(linemap::millisecondsSince(c0));
    }
    std::printf("Copy of that map for a background adjustment (merge thread): median %.1f ms\n",
                percentile(copy_ms, 0.5));

    // 3. MP-GMA over all leaves, 1 and 2 threads, with and without the consistency pass.
    const GmaFigures g1 = timeGma(synthetic, 1, false, runs);
    const GmaFigures g2 = timeGma(synthetic, 2, false, runs);
    const GmaFigures c1 = timeGma(synthetic, 1, true, runs);
    const GmaFigures c2 = timeGma(synthetic, 2, true, runs);
    std::printf(
        "MP-GMA (paper), %zu leaves / %zu segments: 1 thread %.1f ms, 2 threads %.1f ms, speed-up %.2fx; "
        "next OTM frame (R-tree rebuild) %.1f ms\n",
        g1.leaves, g1.segments, g1.median_ms, g2.median_ms, g1.median_ms / g2.median_ms, g2.next_frame_ms);
    std::printf("MP-GMA + consistency pass: 1 thread %.1f ms, 2 threads %.1f ms, speed-up %.2fx\n",
                c1.median_ms, c2.median_ms, c1.median_ms / c2.median_ms);

    std::ofstream out(json);
    out << "{\n"
        << "  \"intel\": {\"keyframes\": " << intel_frames << ", \"leaves\": " << intel_leaves
        << ", \"map_segments\": " << intel_segments << ", \"otm_median_ms\": " << intel_median
        << ", \"otm_p99_ms\": " << intel_p99 << "},\n"
        << "  \"synthetic\": {\"keyframes\": " << synthetic.size() << ", \"leaves\": " << grown.leafCount()
        << ", \"segments_per_keyframe\": " << per_frame << ", \"map_segments\": " << grown.segmentCount()
        << ", \"otm_median_ms_first\": " << percentile(first, 0.5)
        << ", \"otm_median_ms_last\": " << percentile(last, 0.5)
        << ", \"otm_p99_ms_last\": " << percentile(last, 0.99) << "},\n"
        << "  \"gma\": {\"leaves\": " << g1.leaves << ", \"ms_1_thread\": " << g1.median_ms
        << ", \"ms_2_threads\": " << g2.median_ms << ", \"next_frame_ms\": " << g2.next_frame_ms
        << ", \"consistent_ms_1_thread\": " << c1.median_ms
        << ", \"consistent_ms_2_threads\": " << c2.median_ms << "}\n"
        << "}\n";
    std::printf("wrote %s\n", json.c_str());
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "merging_benchmark: %s\n", e.what());
    return 1;
  }
  return 0;
}
