// Every line extractor on noisy simulated office scans, judged against the
// simulator's ground truth: TruePos floors and FalsePos ceilings per algorithm.
// The bounds sit a little outside the figures measured when they were set
// (noted beside each), so a regression in any extractor makes this fail.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/segment_matching.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;

namespace
{
struct Bounds
{
  double min_true_pos;
  double max_false_pos;
};

/// Simulated office, 40 scans of 361 beams, 2 cm range noise and 5 % spurious readings.
const SimulationResult& noisyOffice()
{
  static const SimulationResult sim = []
  {
    SimulationOptions opt;
    opt.seed = 5;
    opt.scans = 40;
    opt.beams = 361;
    opt.sigma = 0.02;
    opt.spurious = 0.05;
    return simulate(loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/office.yaml"), opt);
  }();
  return sim;
}

line_extraction::MatchStatistics evaluate(const std::string& algorithm, bool clustering)
{
  const SimulationResult& sim = noisyOffice();
  linemap::ParamSet params;
  params.set("algorithm", algorithm);
  params.set("clustering", clustering ? "true" : "false");
  line_extraction::LineExtractor extractor(params);
  const line_extraction::TruthRule rule;
  line_extraction::MatchStatistics stats;
  std::vector<line_extraction::LinePiece> extracted, truth;
  std::vector<bool> counted;
  const ScanGeometry& g = sim.recording.geometry;
  for (std::size_t k = 0; k < sim.recording.scans.size(); ++k)
  {
    const line_extraction::ScanInput scan = line_map_eval::scanInput(g, sim.recording.scans[k].ranges);
    extracted.clear();
    for (const line_extraction::Segment& s : extractor.extract(scan).segments)
      extracted.push_back({{s.angle, s.radius}, {s.start, s.end}});
    truth.clear();
    counted.clear();
    for (const VisibleWall& v : sim.truth.scans[k].visible)
    {
      truth.push_back({line_extraction::lineInLaserFrame(sim.truth.scans[k].pose, v.segment),
                       line_extraction::pieceInLaserFrame(sim.truth.scans[k].pose, v.segment)});
      counted.push_back(rule.counts(v.beams, v.segment.length()));
    }
    stats.add(extracted.size(), truth.size(), line_extraction::matchSegments(extracted, truth), counted);
  }
  return stats;
}

}  // namespace

TEST(ExtractionAccuracy, SimulationMatchesTheRecording)
{
  const SimulationResult& sim = noisyOffice();
  ASSERT_EQ(sim.recording.scans.size(), 40u);
  ASSERT_EQ(sim.truth.scans.size(), 40u);
}

TEST(ExtractionAccuracy, EveryExtractorMeetsItsBounds)
{
  // {TruePos floor, FalsePos ceiling} without and with breakpoint clustering; measured
  // TruePos/FalsePos beside them (LINEMAP_PRINT_ACCURACY=1 prints them; matched with
  // matchSegments, which credits a segment to the collinear true piece it lies on). Uniform spurious readings
  // cut the walls into many breakpoint clusters, so with clustering the walls come out in pieces of which
  // only one matches (one-to-one): FalsePos is much higher there.
  const std::map<std::string, std::pair<Bounds, Bounds>> bounds = {
      // srg with the adaptive thresholds and min_length 0.2 m (before: 0.440/0.250, 0.431/0.254); the
      // short segments are more often false (CAE-RLSM shows one only once two keyframes saw it).
      {"srg", {{0.70, 0.45}, {0.69, 0.45}}},              // 0.747/0.402, 0.742/0.405
      {"split_merge", {{0.88, 0.67}, {0.88, 0.64}}},      // 0.931/0.612, 0.935/0.588
      {"iepf", {{0.79, 0.77}, {0.78, 0.77}}},             // 0.841/0.714, 0.836/0.713
      {"smsm", {{0.79, 0.76}, {0.79, 0.77}}},             // 0.845/0.706, 0.845/0.711
      {"incremental", {{0.87, 0.68}, {0.87, 0.68}}},      // 0.922/0.623, 0.922/0.624
      {"line_regression", {{0.67, 0.73}, {0.68, 0.73}}},  // 0.720/0.677, 0.733/0.674
      {"hough", {{0.87, 0.14}, {0.85, 0.55}}},            // 0.918/0.086, 0.905/0.495
      {"ransac", {{0.88, 0.15}, {0.87, 0.56}}},           // 0.935/0.091, 0.918/0.506
      {"em", {{0.88, 0.17}, {0.87, 0.61}}},               // 0.931/0.115, 0.918/0.556
      {"wsac_ge", {{0.86, 0.19}, {0.86, 0.61}}},          // 0.914/0.131, 0.914/0.558
  };
  ASSERT_FALSE(line_extraction::extractorNames().empty());
  for (const std::string& name : line_extraction::extractorNames())
  {
    const auto it = bounds.find(name);
    ASSERT_NE(it, bounds.end()) << "no accuracy bounds for extractor '" << name << "': measure and add them";
    for (bool clustering : {false, true})
    {
      const Bounds& b = clustering ? it->second.second : it->second.first;
      const line_extraction::MatchStatistics s = evaluate(name, clustering);
      if (std::getenv("LINEMAP_PRINT_ACCURACY"))
        std::printf("%s clustering %d: %.3f/%.3f\n", name.c_str(), clustering, s.truePositiveRate(),
                    s.falsePositiveRate());
      EXPECT_GT(s.counted(), 100u);  // enough required true lines to make the rates meaningful
      EXPECT_GE(s.truePositiveRate(), b.min_true_pos) << name << " clustering " << clustering;
      EXPECT_LE(s.falsePositiveRate(), b.max_false_pos) << name << " clustering " << clustering;
    }
  }
}
