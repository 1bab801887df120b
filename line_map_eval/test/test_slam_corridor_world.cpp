// The laser SLAM (the shipped config/slam.yaml) in the corridor world: 40 m of corridor with doors on both
// sides, beyond the laser's reach from its middle, driven out and back. Closures between the two passes see
// the corridor from opposite ends; their matches slide along its axis between look-alike stretches, which
// the matches' curvature says (a direction of weight near 0). Measured against the world's ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_robustness.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;

namespace
{
struct CorridorRun
{
  RobustnessRun run;
  std::size_t relations = 0;  ///< the truth's relations the run was measured by
};

/// The shipped SLAM with `overrides` (and an input `fault` of the benchmark's `seed`) in the corridor world,
/// measured against its truth.
CorridorRun corridorRun(const std::vector<std::string>& overrides,
                        std::optional<InputFault> fault = std::nullopt, std::uint32_t seed = 0)
{
  const World world = loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/corridor.yaml");
  const Recording recording = simulate(world).recording;
  std::vector<double> stamps;
  for (const auto& s : recording.scans) stamps.push_back(s.stamp);
  const std::vector<Relation> relations = truthRelations(recording);
  const linemap::ParamSet defaults = loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"});
  RobustnessVariant variant;
  variant.label = overrides.empty() ? "defaults" : overrides.front();
  variant.overrides = overrides;
  variant.fault = fault;
  variant.seed = seed;
  return {runVariant(recording, stamps, relations, defaults, variant, true), relations.size()};
}
}  // namespace

// A closure slid along the axis used to go in with its slid position, weakly held: a few of them moved
// the return pass by a metre (relations error 0.18 m, two false closures). The front end alone
// (no closures) is good to 0.015 m here, so closures that only add what their matches determine keep the
// run near that, with no false closure among them.
TEST(SlamCorridorWorld, ClosuresDoNotSlideThePassesAlongTheAxis)
{
  const auto [run, relations] = corridorRun({});
  EXPECT_GT(run.error.used, relations / 2);
  EXPECT_LT(run.error.translation_mean, 0.03);
  EXPECT_EQ(run.false_closures, 0u);
}

// Matched on the in-view points alone, a scan of the return pass facing back keeps only the walls beside it
// (the stretch it faces, the submap never saw): its heading rests on a lever arm under a metre. Held as
// sure as a whole scan's, such a closure went in 1.4 degrees off; with the heading's certainty from its
// lever arm no closure is false and the run stays near the front end's.
TEST(SlamCorridorWorld, InViewClosuresAreAsSureOfTheHeadingAsTheirLeverArm)
{
  const auto [run, relations] = corridorRun({"loop/in_view_only=true"});
  EXPECT_GT(run.error.used, relations / 2);
  EXPECT_LT(run.error.translation_mean, 0.03);
  EXPECT_GE(run.counters.loops_accepted, 1u);
  EXPECT_EQ(run.false_closures, 0u);
}

// A front-end slip of 0.3 m and 5 degrees (the benchmark's first seed, in the outward pass) turns all that
// follows. The return pass's closures all slide along the corridor. Across the slip's suspect edge the slid
// ones count across the axis and in heading, and repair the turn: the relations' rotation error within 1.5x
// the clean run's. Refused as ambiguous (loop/ridge_closures off), the turn stays: over 3x the clean run's.
// (The slip's shift along the axis stays: no closure here fixes the axis.)
TEST(SlamCorridorWorld, ASlipsTurnIsRepairedByTheCorridorsSlidClosures)
{
  // The slipped edge on the front end's match, as when the scan pair cannot tell the two apart.
  const std::string on_match = "graph/suspect_edge_follows_odometry=false";
  const auto clean = corridorRun({on_match});
  const auto repaired = corridorRun({on_match}, InputFault::kFrontEndSlip, 1);
  const auto kept = corridorRun({on_match, "loop/ridge_closures=false"}, InputFault::kFrontEndSlip, 1);
  std::printf("rotation error: clean %.3f deg, slip repaired %.3f deg, slip kept %.3f deg\n",
              clean.run.error.rotation_mean * 180.0 / linemap::kPi,
              repaired.run.error.rotation_mean * 180.0 / linemap::kPi,
              kept.run.error.rotation_mean * 180.0 / linemap::kPi);
  EXPECT_LE(repaired.run.error.rotation_mean, 1.5 * clean.run.error.rotation_mean);
  EXPECT_GE(kept.run.error.rotation_mean, 3.0 * clean.run.error.rotation_mean);
  // Along the axis the slid closures keep the estimate: what they repair is the turn, and the error with it.
  EXPECT_LT(repaired.run.error.translation_mean, kept.run.error.translation_mean);
}
