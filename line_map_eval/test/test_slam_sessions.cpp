// Mapping in two sessions on the simulated loop world (ground truth): the drive cut past its middle where
// it comes back to a place it saw, the second part's odometry starting again at zero, and its start given
// 0.18 m and 0.04 rad off the truth (as an initial pose from RViz would be). Its keyframes must join the
// first part's graph by closures to the saved keyframes, and the joined trajectory must be as good as one
// uninterrupted run: within 1.2x its relations error (the target). Without the closures between the
// sessions the start's error stays in the second part (2.5x the single run).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

#include "eval_test_helpers.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_robustness.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "linemap/atomic_file.hpp"

using namespace line_map_eval;
using line_map_eval::test_helpers::revisitPastTheMiddle;

namespace
{
RelationsError errorOf(const std::vector<Relation>& relations, const Recording& recording,
                       const std::vector<std::optional<Pose2>>& poses)
{
  std::vector<std::pair<double, Pose2>> trajectory;
  for (std::size_t i = 0; i < recording.scans.size(); ++i)
    if (poses[i]) trajectory.push_back({recording.scans[i].stamp, *poses[i]});
  return relationsError(relations, trajectory);
}
/// The farthest scan of `poses` from its true position after one rigid fit of all of them onto the truth, and
/// how many were compared.
std::pair<double, std::size_t> worstAfterRigidFit(const std::vector<CorrectedKeyframe>& truth,
                                                  const std::vector<std::optional<Pose2>>& poses)
{
  std::vector<std::pair<linemap::Vec2, linemap::Vec2>> pairs;  // (estimated, true) positions
  for (const CorrectedKeyframe& t : truth)
    if (const auto& p = poses.at(t.scan_index)) pairs.emplace_back(p->translation(), t.pose.translation());
  const Pose2 fit = linemap::bestRigidFit(pairs);
  double worst = 0.0;
  for (const auto& [estimated, true_position] : pairs)
    worst = std::max(worst, (fit.apply(estimated) - true_position).norm());
  return {worst, pairs.size()};
}

/// A world's drive cut at a revisit past its middle, with its true relations and keyframes, the default SLAM
/// and localization parameters, and one uninterrupted SLAM run's relations error.
struct CutDrive
{
  Recording recording;
  std::vector<Relation> relations;
  std::vector<CorrectedKeyframe> truth;
  std::size_t revisit = 0, cut = 0;
  line_map_merging::LaserSlamParams slam_params;
  line_map_merging::LocalizerParams localizer_params;
  RelationsError one;

  explicit CutDrive(const std::string& world_file)
      : recording(simulate(loadWorld(world_file)).recording),
        relations(truthRelations(recording)),
        truth(recording.keyframes),
        slam_params(line_map_merging::LaserSlamParams::fromParams(
            loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}))),
        localizer_params(line_map_merging::LocalizerParams::fromParams(
            loadParameterFiles({LINEMAP_SOURCE_DIR "/config/localization.yaml"})))
  {
    recording.keyframes.clear();
    revisit = revisitPastTheMiddle(truth, recording.scans.size());
    cut = truth[revisit].scan_index;
    const SlamRecordingResult single = runSlam(recording, slam_params);
    one = errorOf(relations, recording, {single.scan_poses.begin(), single.scan_poses.end()});
  }
};
}  // namespace

TEST(SlamSessions, TheSecondPartContinuesTheFirstPartsSession)
{
  const CutDrive d(LINEMAP_SOURCE_DIR "/config/worlds/loop.yaml");
  ASSERT_GT(d.revisit, 0u) << "the drive never comes back to a place it saw";
  const auto& [recording, relations, truth, k, cut, slam_params, localizer_params, one] = d;
  // The map frame is the first scan's pose.
  const Pose2 start = truth.front().pose.inverse() * truth[k].pose * Pose2(0.15, -0.1, 0.04);
  const TwoSessionRun two = runTwoSessions(recording, cut, slam_params, localizer_params, true, start);
  const RelationsError both = errorOf(relations, recording, two.scan_poses);
  std::printf(
      "single run %.4f m over %zu relations; two sessions cut at scan %zu of %zu: %.4f m over %zu, %zu "
      "closures between them\n",
      one.translation_mean, one.used, cut, recording.scans.size(), both.translation_mean, both.used,
      two.closures_between);
  EXPECT_EQ(both.used, one.used);
  EXPECT_LE(both.translation_mean, 1.2 * one.translation_mean);
  EXPECT_GE(two.closures_between, 5u);
}

// A run that global localization cannot place in time (here: it gives up after one scan) is mapped apart in
// its own frame while the search goes on; found later, it joins the saved graph. In the changed office (the
// office's and the loop world's rings look alike half a turn away, and the search accepts the place there)
// the joined trajectory must be where the ground truth has it:
// every keyframe of both parts within kJoinedWorst of its true position after one rigid fit. Left out, or
// joined at a wrong place, the second part's keyframes would be metres off.
constexpr double kJoinedWorst = 0.15;  // [m]: a wrong join puts keyframes metres off (18 m in the office)

TEST(SlamSessions, ARunNotFoundInTimeJoinsWhenFoundLater)
{
  const CutDrive d(LINEMAP_SOURCE_DIR "/config/worlds/office_changed.yaml");
  ASSERT_GT(d.revisit, 0u) << "the drive never comes back to a place it saw";
  const auto& [recording, relations, truth, k, cut, slam_params, localizer_params, one] = d;
  const TwoSessionRun two =
      runTwoSessions(recording, cut, slam_params, localizer_params, true, std::nullopt, 1);
  ASSERT_FALSE(two.localized_at.has_value()) << "placed within one scan: nothing mapped apart to join";
  ASSERT_TRUE(two.joined_at.has_value()) << "the second part was never found and joined";
  const RelationsError both = errorOf(relations, recording, two.scan_poses);
  const auto [worst, compared] = worstAfterRigidFit(truth, two.scan_poses);
  std::printf(
      "single run %.4f m; cut at scan %zu, the second part mapped apart and joined at its scan %zu (%zu "
      "places "
      "refused as ambiguous), %zu closures between them: %.4f m over %zu relations, worst keyframe %.3f m "
      "from "
      "the truth\n",
      one.translation_mean, cut, *two.joined_at, two.refused_as_ambiguous, two.closures_between,
      both.translation_mean, both.used, worst);
  EXPECT_GT(compared, truth.size() * 9 / 10);
  EXPECT_LE(worst, kJoinedWorst);
  EXPECT_GE(two.closures_between, 2u);  // the tie at the join and closures to the saved keyframes after it
  EXPECT_LE(both.translation_mean, 1.5 * one.translation_mean);
}

// The same in the office as it stood: its corridor ring looks alike half a turn away, and the search after
// giving up found and held the place there over 5 m (the join was 18 m off). The join is judged by everything
// the run mapped apart (PlacementJudge): it may join where the truth has it, or not at all; never elsewhere.
TEST(SlamSessions, ARunMappedApartDoesNotJoinALookAlikePlace)
{
  const CutDrive d(LINEMAP_SOURCE_DIR "/config/worlds/office.yaml");
  ASSERT_GT(d.revisit, 0u) << "the drive never comes back to a place it saw";
  const TwoSessionRun two =
      runTwoSessions(d.recording, d.cut, d.slam_params, d.localizer_params, true, std::nullopt, 1);
  ASSERT_FALSE(two.localized_at.has_value()) << "placed within one scan: nothing mapped apart to join";
  if (!two.joined_at)
  {
    std::printf("not joined: %zu places refused as ambiguous\n", two.refused_as_ambiguous);
    EXPECT_GE(two.refused_as_ambiguous, 1u) << "never found, rather than found and refused";
    return;
  }
  const auto [worst, compared] = worstAfterRigidFit(d.truth, two.scan_poses);
  std::printf(
      "joined at scan %zu of the second part (%zu places refused as ambiguous); worst keyframe %.3f m "
      "from the truth over %zu\n",
      *two.joined_at, two.refused_as_ambiguous, worst, compared);
  EXPECT_LE(worst, kJoinedWorst);
}

namespace
{
/// The loop world, its drive cut at a revisit past the middle (as above), and the batch's view of it.
struct LoopWorldRuns
{
  SimulationResult sim;
  Pose2 to_world;  ///< the SLAM's map frame (the first scan's true pose) in the world
  std::size_t cut = 0;
  Pose2 second_start;           ///< the second run's first base pose in the SLAM's map frame, 0.18 m off
  std::vector<Recording> runs;  ///< the two parts, the second's odometry starting again at zero
  line_map_merging::LaserSlamParams slam;
  line_map_merging::LocalizerParams localizer;
  BatchOptions options;
};

const LoopWorldRuns& loopWorldRuns()
{
  static const LoopWorldRuns runs = []
  {
    LoopWorldRuns r;
    r.sim = simulate(loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/loop.yaml"));
    const std::vector<CorrectedKeyframe> truth = r.sim.recording.keyframes;
    r.sim.recording.keyframes.clear();
    r.to_world = truth.front().pose;
    const std::size_t k = revisitPastTheMiddle(truth, r.sim.recording.scans.size());
    r.cut = truth[k].scan_index;
    r.second_start = r.to_world.inverse() * truth[k].pose * Pose2(0.15, -0.1, 0.04);
    r.runs = {recordingPart(r.sim.recording, 0, r.cut, false),
              recordingPart(r.sim.recording, r.cut, r.sim.recording.scans.size(), true)};
    r.slam = line_map_merging::LaserSlamParams::fromParams(
        loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}));
    r.localizer = line_map_merging::LocalizerParams::fromParams(
        loadParameterFiles({LINEMAP_SOURCE_DIR "/config/localization.yaml"}));
    r.options.params = loadParameterFiles({LINEMAP_SOURCE_DIR "/config/line_extraction.yaml",
                                           LINEMAP_SOURCE_DIR "/config/line_map_merging.yaml",
                                           LINEMAP_SOURCE_DIR "/config/line_map_eval.yaml"});
    r.options.mergers = {"cae"};
    r.options.progress = false;
    r.options.figure_formats = 0;
    return r;
  }();
  return runs;
}

/// A SLAM-made recording as a batch dataset in the world frame, with the world's ground truth.
BatchDataset worldDataset(Recording recording, const Pose2& to_world, const GroundTruth& truth)
{
  for (auto& k : recording.keyframes) k.pose = to_world * k.pose;
  for (auto& s : recording.scans) s.odom = to_world * s.odom;
  BatchDataset d = datasetFromRecording(std::move(recording), "loop", "runs+slam");
  d.truth = truth;
  return d;
}

struct MapFigures
{
  double quality = 0.0, coverage = 0.0;  ///< [%]
};

MapFigures figuresOf(const BatchResult& result)
{
  const MergerRun& cae = result.mergers.at(0);
  return {cae.quality.quality, 100.0 * cae.ground_truth.value().coverage};
}

MapFigures oneDrive()
{
  const LoopWorldRuns& w = loopWorldRuns();
  const SlamRecordingResult single = runSlam(w.sim.recording, w.slam);
  const MapFigures f = figuresOf(
      runBatch(worldDataset(withSlamKeyframes(w.sim.recording, single), w.to_world, w.sim.truth), w.options));
  std::printf("one drive: q %.2f %%, ground-truth coverage %.2f %%\n", f.quality, f.coverage);
  return f;
}

/// The two runs mapped together (linemap_batch RUN1 RUN2 --slam).
struct TwoRuns
{
  SessionsRun joined;
  BatchResult result;
};

const TwoRuns& twoRuns()
{
  static const TwoRuns two = []
  {
    const LoopWorldRuns& w = loopWorldRuns();
    TwoRuns t;
    t.joined = runSessions(w.runs, std::nullopt, w.slam, w.localizer, true, {std::nullopt, w.second_start});
    t.result =
        runBatch(worldDataset(joinedRecording(w.runs, t.joined, true), w.to_world, w.sim.truth), w.options);
    return t;
  }();
  return two;
}
}  // namespace

// Two runs of the loop world in one graph and one map (linemap_batch RUN1 RUN2 --slam): the map must be as
// good as one uninterrupted drive's, its ground-truth coverage and quality within 0.5 points (the issue's
// target for several runs). Were the second run's odometry left in its own frame, or its keyframes not
// joined to the first run's graph, its walls would land beside the first run's.
TEST(SlamSessions, TwoRunsMakeOneMapAsGoodAsOneDrive)
{
  const MapFigures one = oneDrive();
  const TwoRuns& t = twoRuns();
  ASSERT_TRUE(t.joined.localized_at[1].has_value());
  EXPECT_GE(t.joined.closures_to_earlier[1], 5u);
  const MapFigures two = figuresOf(t.result);
  std::printf("two runs, one map: q %.2f %%, ground-truth coverage %.2f %%\n", two.quality, two.coverage);
  EXPECT_GE(two.quality, one.quality - 0.5);
  EXPECT_GE(two.coverage, one.coverage - 0.5);
}

// The second run continues the first run's saved session, map included (linemap_batch RUN --slam --session
// F): CAE-RLSM starts from the saved map with its provenance, merges the new keyframes into it, and after the
// joined graph's trajectory re-fuses the whole map. Every saved keyframe must sit at its pose in the joined
// graph, and the map must be the one both runs mapped together make: its q against their scans and its
// ground-truth coverage within 0.5 points. Without the saved map, the walls only the first run saw would be
// missing (coverage falls by tens of points); with the saved keyframes left where the first session put
// them, their walls would not move with the joined graph.
TEST(SlamSessions, AContinuedSessionGoesOnWithItsMap)
{
  const LoopWorldRuns& w = loopWorldRuns();
  // The first session: its graph and its map file.
  const SessionsRun first = runSessions({w.runs[0]}, std::nullopt, w.slam, w.localizer, true);
  BatchOptions first_options = w.options;
  first_options.out_dir = ::testing::TempDir() + "slam_sessions_first";
  runBatch(worldDataset(joinedRecording({w.runs[0]}, first, true), w.to_world, w.sim.truth), first_options);
  const std::string map_text = linemap::readWholeFile(first_options.out_dir + "/cae/map.yaml", "map file");

  const SessionsRun joined =
      runSessions({w.runs[1]}, first.session, w.slam, w.localizer, true, {w.second_start});
  ASSERT_TRUE(joined.localized_at[0].has_value());
  BatchDataset dataset = worldDataset(joinedRecording({w.runs[1]}, joined, true), w.to_world, w.sim.truth);
  line_map_merging::Session loaded;
  loaded.slam = first.session;
  loaded.line_map = map_text;
  const BatchDataset::SavedMap saved = continuedMap(loaded, joined.session, "the first session", w.to_world);
  dataset.saved_map = saved;
  BatchOptions options = w.options;
  options.out_dir = ::testing::TempDir() + "slam_sessions_continued";
  const BatchResult result = runBatch(dataset, options);

  // Measured against the scans of both runs mapped together (the saved keyframes keep only the SLAM's
  // points, within its range).
  const TwoRuns& t = twoRuns();
  const LookupTable table =
      LookupTable::build(t.result.registered_points, LookupTableParams::fromParams(w.options.params));
  const QualityParams quality = QualityParams::fromParams(w.options.params);
  const double together = computeMapQuality(table, t.result.mergers.at(0).final_map, quality).quality;
  const double continued = computeMapQuality(table, result.mergers.at(0).final_map, quality).quality;
  const double together_coverage = figuresOf(t.result).coverage;
  const double continued_coverage = figuresOf(result).coverage;
  std::printf(
      "against both runs' scans: mapped together q %.2f %%, continued q %.2f %%; ground-truth coverage "
      "%.2f / %.2f %%\n",
      together, continued, together_coverage, continued_coverage);
  EXPECT_GE(continued, together - 0.5);
  EXPECT_GE(continued_coverage, together_coverage - 0.5);
  line_map_merging::CaeRlsm before, after;
  before.loadText(map_text, "first");
  after.load(options.out_dir + "/cae/map.yaml");
  std::map<double, Pose2> joined_pose(saved.keyframe_poses.begin(), saved.keyframe_poses.end());
  std::size_t kept = 0;
  for (const auto& k : after.keyframes())
  {
    const auto it = joined_pose.find(k.stamp);
    if (it == joined_pose.end()) continue;
    ++kept;
    const Pose2 expected = it->second * k.mount;
    EXPECT_NEAR((k.pose.translation() - expected.translation()).norm(), 0.0, 1e-6) << "keyframe " << k.index;
    EXPECT_NEAR(linemap::normalizeAngle(k.pose.theta - expected.theta), 0.0, 1e-6) << "keyframe " << k.index;
  }
  EXPECT_EQ(kept, before.keyframeCount()) << "every saved keyframe is in the continued map";
  EXPECT_GT(after.keyframeCount(), before.keyframeCount());
}

// Runs joined into one recording, by hand: the second run's odometry restarts at zero; the graph put its
// first scan at (10, 0, pi/2). Its odometry is moved there (so it goes on from where the map has the robot),
// its keyframes follow the first run's scans, and a run that was never placed is left out.
TEST(SlamSessions, JoinedRecordingPutsEachRunsOdometryWhereTheGraphPutIt)
{
  auto run = [](double t0, const std::vector<Pose2>& odometry)
  {
    Recording r;
    r.geometry.beam_count = 1;
    r.base_to_laser = Pose2(0.1, 0.0, 0.0);
    for (std::size_t i = 0; i < odometry.size(); ++i)
      r.scans.push_back({t0 + 0.5 * static_cast<double>(i), {1.0f}, odometry[i]});
    return r;
  };
  std::vector<Recording> runs{run(10.0, {Pose2(), Pose2(1, 0, 0)}), run(0.0, {Pose2(), Pose2(2, 0, 0)}),
                              run(50.0, {Pose2()})};
  const std::vector<double> shifts = followInTime(runs);
  EXPECT_EQ(shifts[0], 0.0);
  EXPECT_DOUBLE_EQ(shifts[1], 11.5);  // 10.5 + 1 s
  EXPECT_EQ(shifts[2], 0.0);
  EXPECT_DOUBLE_EQ(runs[1].scans[0].stamp, 11.5);

  SessionsRun joined;
  joined.scan_poses = {
      {Pose2(), Pose2(1, 0, 0)}, {Pose2(10, 0, linemap::kPi / 2), std::nullopt}, {std::nullopt}};
  joined.keyframes = {{{0, Pose2()}}, {{0, Pose2(10, 0, linemap::kPi / 2)}}, {}};
  joined.localized_at = {0, 3, std::nullopt};
  const Recording out = joinedRecording(runs, joined, true);
  ASSERT_EQ(out.scans.size(), 4u);
  // The second run's second scan: 2 m ahead of (10, 0) facing +y, whatever the SLAM made of it.
  EXPECT_NEAR(out.scans[3].odom.x, 10.0, 1e-12);
  EXPECT_NEAR(out.scans[3].odom.y, 2.0, 1e-12);
  EXPECT_NEAR(out.scans[3].odom.theta, linemap::kPi / 2, 1e-12);
  ASSERT_EQ(out.keyframes.size(), 2u);
  EXPECT_EQ(out.keyframes[1].scan_index, 2u);
  // Without odometry each scan takes its SLAM pose, one without the last posed scan's.
  const Recording laser_only = joinedRecording(runs, joined, false);
  EXPECT_NEAR(laser_only.scans[3].odom.x, 10.0, 1e-12);
  EXPECT_NEAR(laser_only.scans[3].odom.y, 0.0, 1e-12);

  runs[1].base_to_laser = Pose2(0.2, 0.0, 0.0);
  EXPECT_THROW(joinedRecording(runs, joined, true), std::invalid_argument);
}
