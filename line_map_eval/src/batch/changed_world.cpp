// Two sessions in a building that changed between them (changed_world.hpp).
#include "line_map_eval/batch/changed_world.hpp"

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

}  // namespace

ChangedWorldResult runChangedWorld(const World& before, const World& after, const BatchOptions& options,
                                   ChangedWorldPoses poses, const line_map_merging::LaserSlamParams& slam,
                                   const line_map_merging::LocalizerParams& localizer,
                                   const std::string& work_dir, const std::optional<linemap::Pose2>& start)
{
  const SimulationResult first_sim = simulate(before);
  SimulationOptions later;
  later.seed = after.seed + 1;                                         // other noise, as on another day
  later.start_time = first_sim.recording.scans.back().stamp + 3600.0;  // an hour later: one time line
  const SimulationResult second_sim = simulate(after, later);
  const GroundTruthParams truth_params = GroundTruthParams::fromParams(options.params);
  const ChangePieces pieces = changePieces(first_sim.truth, second_sim.truth, truth_params);
  const LookupTable table = LookupTable::build(registeredScanPoints(second_sim.recording),
                                               LookupTableParams::fromParams(options.params));
  const QualityParams quality = QualityParams::fromParams(options.params);
  const auto score = [&](const BatchResult& batch)
  {
    const std::vector<linemap::Segment2>& map = batch.mergers.at(0).final_map;
    const auto& truth = batch.mergers.at(0).ground_truth;
    return ChangedWorldMap{computeMapQuality(table, map, quality).quality,
                           truth ? 100.0 * truth->coverage : 0.0, scoreChanges(pieces, map, truth_params),
                           map.size()};
  };
  const auto mapText = [](const std::string& dir)
  { return linemap::readWholeFile(dir + "/cae/map.yaml", "map file"); };
  BatchOptions keep_all = cae(options, work_dir + "/kept");
  applyOverride(keep_all.params, "see_through=false");
  ChangedWorldResult result;

  if (poses == ChangedWorldPoses::kTruth)
  {
    const auto dataset = [](const SimulationResult& sim, const std::string& name)
    {
      BatchDataset d = datasetFromRecording(sim.recording, name, "world");
      d.truth = sim.truth;
      return d;
    };
    const BatchResult first_batch =
        runBatch(dataset(first_sim, after.name + " session 1"), cae(options, work_dir + "/first"));
    result.first = score(first_batch);
    result.fresh =
        score(runBatch(dataset(second_sim, after.name + " alone"), cae(options, work_dir + "/fresh")));
    BatchDataset continued = dataset(second_sim, after.name + " continued");
    continued.saved_map = savedOnTruePoses(mapText(work_dir + "/first"), first_batch.registered_points);
    result.localized_at = 0;
    result.continued = score(runBatch(continued, cae(options, work_dir + "/continued")));
    result.kept = score(runBatch(continued, keep_all));
    return result;
  }

  const Pose2 to_world = first_sim.recording.keyframes.front().pose;
  const std::vector<Recording> first_run{slamInput(first_sim, false)},
      second_run{slamInput(second_sim, true)};
  // The first session: its graph and its map file.
  const SessionsRun first = runSessions(first_run, std::nullopt, slam, localizer, true);
  const std::string first_dir = work_dir + "/first";
  result.first = score(runBatch(worldDataset(joinedRecording(first_run, first, true), to_world,
                                             first_sim.truth, after.name + " session 1"),
                                cae(options, first_dir)));
  line_map_merging::Session saved;
  saved.slam = first.session;
  saved.line_map = mapText(first_dir);

  // The second session from nothing.
  const SessionsRun alone = runSessions(second_run, std::nullopt, slam, localizer, true);
  result.fresh = score(runBatch(
      worldDataset(joinedRecording(second_run, alone, true), second_sim.recording.keyframes.front().pose,
                   second_sim.truth, after.name + " alone"),
      cae(options, work_dir + "/fresh")));

  // The second session continuing the first.
  const SessionsRun joined = runSessions(second_run, first.session, slam, localizer, true, {start});
  result.localized_at = joined.localized_at.at(0);
  result.closures_between = joined.closures_to_earlier.at(0);
  if (!result.localized_at) return result;
  BatchDataset continued = worldDataset(joinedRecording(second_run, joined, true), to_world, second_sim.truth,
                                        after.name + " continued");
  continued.saved_map = continuedMap(saved, joined.session, "the first session", to_world);
  result.continued = score(runBatch(continued, cae(options, work_dir + "/continued")));
  result.kept = score(runBatch(continued, keep_all));
  return result;
}

}  // namespace line_map_eval
