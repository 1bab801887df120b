// Structure coverage against the ground truth (issue 36): in the simulated hall seen with the 1 deg
// laser, with and without a registration error of the keyframe poses like a corrected log's, the share
// of straight structure the map covers agrees with the ground truth's coverage of the faces the robot
// saw, within 5 points: for CAE-RLSM's map, and for the same map with the segments of a third of the
// seen faces taken out (so a measure that ignores missing walls, or counts smeared ones as clutter,
// fails here).
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/metrics/map_metrics.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;
namespace fs = std::filesystem;
using linemap::Segment2;

namespace
{
const std::string kRoot = LINEMAP_SOURCE_DIR;

linemap::ParamSet defaultParams()
{
  std::vector<std::string> files;
  for (const char* name : {"line_extraction.yaml", "line_map_merging.yaml", "line_map_eval.yaml"})
    files.push_back(kRoot + "/config/" + name);
  return loadParameterFiles(files);
}

struct Agreement
{
  double structure = 0.0;     ///< structure coverage of the map
  double ground_truth = 0.0;  ///< ground-truth coverage of the seen faces
};

/// Both coverages of `map` over the registered points of `result`.
Agreement measure(const BatchDataset& dataset, const BatchResult& result, const std::vector<Segment2>& map,
                  const linemap::ParamSet& params)
{
  const CoverageParams coverage = CoverageParams::fromParams(params);
  const double sigma = params.getDouble("eval/sigma", 0.05);
  const double radius = coverage.point_sigmas * sigma;
  const StructurePoints structure = classifyStructure(result.registered_points, sigma, coverage.structure);
  const StructureCoverage covered = computeStructureCoverage(
      structure, computePointCoverage(result.registered_points, map, radius), map, radius);
  const GroundTruthResult truth =
      evaluateAgainstGroundTruth(*dataset.truth, map, GroundTruthParams::fromParams(params));
  return {covered.fraction(), truth.coverage};
}

void expectAgreement(const RegistrationModel& registration)
{
  World hall = withSensorProfile(loadWorld(kRoot + "/config/worlds/hall.yaml"),
                                 kRoot + "/config/sensors/laser_1deg_30m.yaml");
  hall.registration = registration;
  const BatchDataset dataset = simulatedDataset(hall);
  ASSERT_TRUE(dataset.truth);
  BatchOptions options;
  options.params = defaultParams();
  options.progress = false;
  options.mergers = {"cae"};
  const BatchResult result = runBatch(dataset, options);
  ASSERT_EQ(result.mergers.size(), 1u);
  const std::vector<Segment2>& map = result.mergers[0].final_map;
  ASSERT_FALSE(result.registered_points.empty());

  const Agreement full = measure(dataset, result, map, options.params);
  EXPECT_NEAR(full.structure, full.ground_truth, 0.05);
  // The batch reports the same figures.
  EXPECT_NEAR(result.mergers[0].structure_coverage.fraction(), full.structure, 1e-12);

  // Every third seen face loses the map segments associated with it.
  const GroundTruthResult scored =
      evaluateAgainstGroundTruth(*dataset.truth, map, GroundTruthParams::fromParams(options.params));
  std::vector<bool> drop(map.size(), false);
  const GroundTruthParams gt_params = GroundTruthParams::fromParams(options.params);
  const SeenParts seen = unionOfSeenParts(
      seenParts(*dataset.truth, gt_params.min_seen_length, gt_params.min_seen_beams),
      accumulatedSeenParts(*dataset.truth, gt_params.min_seen_length, gt_params.min_seen_beams));
  const std::vector<double> slack = registrationSlack(*dataset.truth, gt_params.registration_sigmas);
  std::size_t seen_faces = 0;
  for (std::size_t w = 0; w < dataset.truth->walls.size(); ++w)
  {
    if (seen[w].empty() || seen_faces++ % 3 != 0) continue;
    // The segments this face alone would associate (scored with its slack).
    std::vector<std::vector<std::pair<double, double>>> only(dataset.truth->walls.size());
    only[w] = seen[w];
    std::vector<Segment2> one_face{dataset.truth->walls[w]};
    for (std::size_t m = 0; m < map.size(); ++m)
    {
      const GroundTruthResult r =
          evaluateAgainstGroundTruth(one_face, {seen[w]}, {map[m]}, gt_params, {}, {slack[w]});
      if (!r.walls.empty() && r.walls[0].associated > 0) drop[m] = true;
    }
  }
  std::vector<Segment2> thinned;
  for (std::size_t m = 0; m < map.size(); ++m)
    if (!drop[m]) thinned.push_back(map[m]);
  ASSERT_LT(thinned.size(), map.size());
  const Agreement removed = measure(dataset, result, thinned, options.params);
  EXPECT_LT(removed.ground_truth, scored.coverage - 0.15) << "the removal takes out a third of the walls";
  EXPECT_NEAR(removed.structure, removed.ground_truth, 0.05);
}

}  // namespace

TEST(StructureValidation, HallWithExactPoses)
{
  expectAgreement({});
}

TEST(StructureValidation, HallWithRegistrationError)
{
  RegistrationModel registration;
  registration.position = 0.04;
  registration.heading = 0.4 * linemap::kPi / 180.0;
  expectAgreement(registration);
}
