// Two sessions in a building that changed between them (changed_world.hpp).
#include "line_map_eval/batch/changed_world.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "linemap/atomic_file.hpp"

namespace line_map_eval
{
namespace
{
/// The simulated run as the SLAM gets it: scans and drifting odometry, no true poses; `rezero`: the
/// odometry starts at zero, as after a restart.
Recording slamInput(const SimulationResult& sim, bool rezero)
{
  Recording r = sim.recording;
  r.keyframes.clear();
  return recordingPart(r, 0, r.scans.size(), rezero);
}

/// Where a SLAM-made recording's map frame lies in the world: the rigid transform that best fits its
/// keyframes' positions to their true ones (least squares, as the absolute trajectory error is measured).
/// The SLAM knows nothing of the world frame; pinning its frame to one scan's true pose would let that
/// one pose's error shift the whole map against the ground truth.
Pose2 worldFrameOf(const Recording& slam_made, const Recording& truth)
{
  std::unordered_map<std::size_t, Pose2> true_pose;
  for (const CorrectedKeyframe& k : truth.keyframes) true_pose.emplace(k.scan_index, k.pose);
  std::vector<std::pair<linemap::Vec2, linemap::Vec2>> pairs;  // (SLAM, true) positions
  for (const CorrectedKeyframe& k : slam_made.keyframes)
    if (const auto it = true_pose.find(k.scan_index); it != true_pose.end())
      pairs.emplace_back(k.pose.translation(), it->second.translation());
  if (pairs.size() < 2)
    throw std::runtime_error("changed world: fewer than two SLAM keyframes to place the map by");
  return linemap::bestRigidFit(pairs);
}

/// A SLAM-made recording as a batch dataset in the world frame, scored against `truth`.
BatchDataset worldDataset(Recording recording, const Pose2& to_world, const GroundTruth& truth,
                          const std::string& name)
{
  for (auto& k : recording.keyframes) k.pose = to_world * k.pose;
  for (auto& s : recording.scans) s.odom = to_world * s.odom;
  BatchDataset d = datasetFromRecording(std::move(recording), name, "runs+slam");
  d.truth = truth;
  return d;
}

BatchOptions cae(const BatchOptions& options, const std::string& out_dir)
{
  BatchOptions o = options;
  o.mergers = {"cae"};
  o.out_dir = out_dir;
  return o;
}

/// `points` less those on walls removed since the first session: the building as it stands, as far as the
/// scans saw it. A wall the second session no longer sees (behind a door closed since, or a new cabinet)
/// still stands and keeps its points.
std::vector<linemap::Vec2> standingPoints(const std::vector<linemap::Vec2>& points,
                                          const ChangePieces& pieces)
{
  // Beyond the range noise of a point on the wall, within the wall's thickness: the point was on it.
  constexpr double kOnWall = 0.1;
  std::vector<linemap::Vec2> out;
  out.reserve(points.size());
  for (const linemap::Vec2& p : points)
  {
    bool removed = false;
    for (const linemap::Segment2& s : pieces.removed)
      if (linemap::distanceToSegment(p, s.start, s.end) < kOnWall)
      {
        removed = true;
        break;
      }
    if (!removed) out.push_back(p);
  }
  return out;
}

/// The map `text` (a first session's, on true poses) for a dataset to continue: its keyframes at their
/// base poses, the first session's scan points for the evaluation.
BatchDataset::SavedMap savedOnTruePoses(const std::string& text, const std::vector<linemap::Vec2>& points)
{
  BatchDataset::SavedMap out;
  out.text = text;
  out.origin = "the first session";
  line_map_merging::CaeRlsm map;
  map.loadText(text, out.origin);
  for (const auto& k : map.keyframes()) out.keyframe_poses.emplace_back(k.stamp, k.pose * k.mount.inverse());
  out.points = points;
  return out;
}

/// What both kinds of run share: the two simulations, the change pieces, and how a map is scored.
struct ChangedWorldRun
{
  const World& after;
  const BatchOptions& options;
  const std::string& work_dir;
  SimulationResult first_sim, second_sim;
  GroundTruthParams truth_params;
  ChangePieces pieces;
  LookupTableParams table_params;
  QualityParams quality;

  ChangedWorldMap score(const BatchResult& batch, const LookupTable& table) const
  {
    const std::vector<linemap::Segment2>& map = batch.mergers.at(0).final_map;
    const auto& truth = batch.mergers.at(0).ground_truth;
    return ChangedWorldMap{computeMapQuality(table, map, quality).quality,
                           truth ? 100.0 * truth->coverage : 0.0, scoreChanges(pieces, map, truth_params),
                           map.size(), batch.mergers.at(0).retired};
  }
  LookupTable tableOf(const std::vector<linemap::Vec2>& points) const
  {
    return LookupTable::build(standingPoints(points, pieces), table_params);
  }
  std::string mapText(const std::string& dir) const
  {
    return linemap::readWholeFile(dir + "/cae/map.yaml", "map file");
  }
  BatchOptions keepAll() const
  {
    BatchOptions keep_all = cae(options, work_dir + "/kept");
    applyOverride(keep_all.params, "see_through=false");
    return keep_all;
  }
};

ChangedWorldResult onTruePoses(const ChangedWorldRun& run)
{
  const auto dataset = [](const SimulationResult& sim, const std::string& name)
  {
    BatchDataset d = datasetFromRecording(sim.recording, name, "world");
    d.truth = sim.truth;
    return d;
  };
  std::vector<linemap::Vec2> both = registeredScanPoints(run.first_sim.recording);
  const std::vector<linemap::Vec2> second_points = registeredScanPoints(run.second_sim.recording);
  both.insert(both.end(), second_points.begin(), second_points.end());
  const LookupTable table = run.tableOf(both);
  const std::string& name = run.after.name;
  ChangedWorldResult result;
  const BatchResult first_batch =
      runBatch(dataset(run.first_sim, name + " session 1"), cae(run.options, run.work_dir + "/first"));
  result.first = run.score(first_batch, table);
  result.fresh = run.score(
      runBatch(dataset(run.second_sim, name + " alone"), cae(run.options, run.work_dir + "/fresh")), table);
  BatchDataset continued = dataset(run.second_sim, name + " continued");
  continued.saved_map = savedOnTruePoses(run.mapText(run.work_dir + "/first"), first_batch.registered_points);
  result.localized_at = 0;
  result.continued = run.score(runBatch(continued, cae(run.options, run.work_dir + "/continued")), table);
  result.kept = run.score(runBatch(continued, run.keepAll()), table);
  return result;
}

ChangedWorldResult onSlamPoses(const ChangedWorldRun& run, const line_map_merging::LaserSlamParams& slam,
                               const line_map_merging::LocalizerParams& localizer,
                               const std::optional<linemap::Pose2>& start)
{
  const std::string& name = run.after.name;
  const std::vector<Recording> first_run{slamInput(run.first_sim, false)},
      second_run{slamInput(run.second_sim, true)};
  ChangedWorldResult result;
  // The first session: its graph and its map file.
  const SessionsRun first = runSessions(first_run, std::nullopt, slam, localizer, true);
  const Recording first_made = joinedRecording(first_run, first, true);
  const Pose2 to_world = worldFrameOf(first_made, run.first_sim.recording);
  const std::string first_dir = run.work_dir + "/first";
  const BatchResult first_batch =
      runBatch(worldDataset(first_made, to_world, run.first_sim.truth, name + " session 1"),
               cae(run.options, first_dir));
  line_map_merging::Session saved;
  saved.slam = first.session;
  saved.line_map = run.mapText(first_dir);

  // The second session from nothing, scored in its own frame against its own scans.
  const SessionsRun alone = runSessions(second_run, std::nullopt, slam, localizer, true);
  const Recording alone_made = joinedRecording(second_run, alone, true);
  const BatchResult fresh_batch =
      runBatch(worldDataset(alone_made, worldFrameOf(alone_made, run.second_sim.recording),
                            run.second_sim.truth, name + " alone"),
               cae(run.options, run.work_dir + "/fresh"));
  result.fresh = run.score(fresh_batch, run.tableOf(fresh_batch.registered_points));

  // The second session continuing the first. The other maps are scored in the joined graph's frame, against
  // both sessions' scans as it registered them.
  const SessionsRun joined = runSessions(second_run, first.session, slam, localizer, true, {start});
  result.localized_at = joined.localized_at.at(0);
  result.closures_between = joined.closures_to_earlier.at(0);
  if (!result.localized_at)
  {
    result.first = run.score(first_batch, run.tableOf(first_batch.registered_points));
    return result;
  }
  // The joined graph's frame is the first session's, its keyframes moved a little by the joined optimisation.
  const Recording joined_made = joinedRecording(second_run, joined, true);
  const Pose2 joined_to_world = worldFrameOf(joined_made, run.second_sim.recording);
  BatchDataset continued =
      worldDataset(joined_made, joined_to_world, run.second_sim.truth, name + " continued");
  continued.saved_map = continuedMap(saved, joined.session, "the first session", joined_to_world);
  const BatchResult continued_batch = runBatch(continued, cae(run.options, run.work_dir + "/continued"));
  const LookupTable table = run.tableOf(continued_batch.registered_points);
  result.first = run.score(first_batch, table);
  result.continued = run.score(continued_batch, table);
  result.kept = run.score(runBatch(continued, run.keepAll()), table);
  return result;
}

}  // namespace

ChangedWorldResult runChangedWorld(const World& before, const World& after, const BatchOptions& options,
                                   ChangedWorldPoses poses, const line_map_merging::LaserSlamParams& slam,
                                   const line_map_merging::LocalizerParams& localizer,
                                   const std::string& work_dir, const std::optional<linemap::Pose2>& start)
{
  SimulationResult first_sim = simulate(before);
  SimulationOptions later;
  later.seed = after.seed + 1;                                         // other noise, as on another day
  later.start_time = first_sim.recording.scans.back().stamp + 3600.0;  // an hour later: one time line
  SimulationResult second_sim = simulate(after, later);
  const GroundTruthParams truth_params = GroundTruthParams::fromParams(options.params);
  ChangePieces pieces = changePieces(first_sim.truth, second_sim.truth, truth_params);
  const ChangedWorldRun run{after,
                            options,
                            work_dir,
                            std::move(first_sim),
                            std::move(second_sim),
                            truth_params,
                            std::move(pieces),
                            LookupTableParams::fromParams(options.params),
                            QualityParams::fromParams(options.params)};
  return poses == ChangedWorldPoses::kTruth ? onTruePoses(run) : onSlamPoses(run, slam, localizer, start);
}

}  // namespace line_map_eval
