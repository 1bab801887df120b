// Fault injection into the laser SLAM (the shipped config/slam.yaml): the front end slips by 0.3 m and 5
// degrees at a random scan of the first half of a simulated drive, as after a false match it cannot see;
// the rest of the drive passes the places before the slip again. The closures across the slip must
// repair it. Measured against the relations of the ground truth. A SLAM whose loop gate trusts the
// slipped chain over the closures refuses them (each disagrees with the chain beyond its covariance), and
// one whose loop search looks for the revisit where the slipped chain puts it misses them: the slip stays.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_robustness.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;
using linemap::Pose2;

namespace
{
struct Drive
{
  Recording recording;
  std::vector<Relation> relations;
};

Drive simulated(const std::string& world_file)
{
  const World world = loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/" + world_file);
  Drive out;
  out.recording = simulate(world).recording;
  out.relations = truthRelations(out.recording);
  out.recording.keyframes.clear();
  return out;
}

double relationsErrorOf(const Drive& run, const SlamRecordingResult& slam)
{
  std::vector<std::pair<double, Pose2>> trajectory;
  for (std::size_t i = 0; i < slam.scan_poses.size(); ++i)
    trajectory.push_back({run.recording.scans[i].stamp, slam.scan_poses[i]});
  const RelationsError e = relationsError(run.relations, trajectory);
  EXPECT_GT(e.used, run.relations.size() / 2);
  return e.translation_mean;
}

/// How many of 20 seeded slips (the benchmark's: 0.3 m in a random direction and 5 degrees either way, at
/// a random scan of the first half) end within `factor` times the clean run's error.
std::size_t repairedOf20(const Drive& run, double factor, double clean_at_most)
{
  const auto params = line_map_merging::LaserSlamParams::fromParams(
      loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}));
  const double clean = relationsErrorOf(run, runSlam(run.recording, params));
  // The clean run itself is accurate, so a few times its error is a bound a kept slip breaks.
  EXPECT_LT(clean, clean_at_most);
  std::size_t repaired = 0;
  for (std::uint32_t seed = 1; seed <= 20; ++seed)
  {
    const FaultyRecording faulty = withFault(run.recording, InputFault::kFrontEndSlip, seed);
    EXPECT_TRUE(faulty.slip.has_value());
    if (!faulty.slip) continue;
    const SlamRecordingResult slam = runSlam(faulty.recording, params, true, faulty.slip);
    const double error = relationsErrorOf(run, slam);
    const bool ok = error <= factor * clean;
    repaired += ok ? 1 : 0;
    std::printf("slip at scan %zu of %zu (%+.2f, %+.2f, %+.0f deg): %.4f m (clean %.4f m)%s; %s\n",
                faulty.slip->scan, run.recording.scans.size(), faulty.slip->slip.x, faulty.slip->slip.y,
                faulty.slip->slip.theta * 180.0 / linemap::kPi, error, clean, ok ? "" : " NOT REPAIRED",
                line_map_merging::closureSummary(slam.counters).c_str());
  }
  return repaired;
}
}  // namespace

// The simulated office: a loop around the building's core with excursions into rooms, closed where it
// started, so closures after the slip span it. The target: 2x the clean error in 19 of 20 seeds.
// Without the chain edges widened by their disagreement with the odometry, 11 of 20 (the gate refuses the
// closures across the slip, or they bend the loop); with them but the loop search's window not widened
// for the suspect edge, 14 of 20 (the loop's end, turned 5 degrees about the slip, lies outside it).
TEST(SlamSlip, OfficeSlipsAreRepairedByLaterClosures)
{
  EXPECT_GE(repairedOf20(simulated("office.yaml"), 2.0, 0.01), 19u);
}

// The square room: one lap of 2 x 2 m, every closure ambiguous in part (a square's walls), the few
// accepted ones each 5 cm certain: closures alone repaired a slip to 2-3.5x a clean error of millimetres,
// none of 20 within 2x. The slipped keyframe edge on the odometry's motion, which the two keyframes' scans
// fit better than the slipped match (graph/suspect_edge_follows_odometry), leaves nothing to repair.
TEST(SlamSlip, SquareRoomSlipsAreRepairedByTheScanPair)
{
  EXPECT_GE(repairedOf20(simulated("square_room.yaml"), 2.0, 0.01), 19u);
}
