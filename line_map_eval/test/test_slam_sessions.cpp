// Mapping in two sessions on the simulated loop world (ground truth): the drive cut past its middle where
// it comes back to a place it saw, the second part's odometry starting again at zero, and its start given
// 0.18 m and 0.04 rad off the truth (as an initial pose from RViz would be). Its keyframes must join the
// first part's graph by closures to the saved keyframes, and the joined trajectory must be as good as one
// uninterrupted run: within 1.2x its relations error (the target). Without the closures between the
// sessions the start's error stays in the second part (2.5x the single run).
#include <gtest/gtest.h>

#include <cstdio>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_robustness.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"

using namespace line_map_eval;

namespace
{
/// The first keyframe past the middle of the drive where the robot is back in a place the first part saw
/// (within 1 m of a true position at least 5 m of path before): a session is continued where it can be
/// found. 0: none.
std::size_t revisitPastTheMiddle(const std::vector<CorrectedKeyframe>& truth, std::size_t scans)
{
  for (std::size_t k = 0; k < truth.size(); ++k)
  {
    if (truth[k].scan_index < scans / 2) continue;
    double path = 0.0;
    for (std::size_t j = k; j-- > 0;)
    {
      path += (truth[j + 1].pose.translation() - truth[j].pose.translation()).norm();
      if (path >= 5.0 && (truth[j].pose.translation() - truth[k].pose.translation()).norm() <= 1.0) return k;
    }
  }
  return 0;
}

RelationsError errorOf(const std::vector<Relation>& relations, const Recording& recording,
                       const std::vector<std::optional<Pose2>>& poses)
{
  std::vector<std::pair<double, Pose2>> trajectory;
  for (std::size_t i = 0; i < recording.scans.size(); ++i)
    if (poses[i]) trajectory.push_back({recording.scans[i].stamp, *poses[i]});
  return relationsError(relations, trajectory);
}
}  // namespace

TEST(SlamSessions, TheSecondPartContinuesTheFirstPartsSession)
{
  const World world = loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/loop.yaml");
  Recording recording = simulate(world).recording;
  const std::vector<Relation> relations = truthRelations(recording);
  const std::vector<CorrectedKeyframe> truth = recording.keyframes;
  recording.keyframes.clear();
  const std::size_t k = revisitPastTheMiddle(truth, recording.scans.size());
  ASSERT_GT(k, 0u) << "the drive never comes back to a place it saw";
  const std::size_t cut = truth[k].scan_index;
  // The map frame is the first scan's pose.
  const Pose2 start = truth.front().pose.inverse() * truth[k].pose * Pose2(0.15, -0.1, 0.04);

  const auto slam_params = line_map_merging::LaserSlamParams::fromParams(
      loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}));
  const auto localizer_params = line_map_merging::LocalizerParams::fromParams(
      loadParameterFiles({LINEMAP_SOURCE_DIR "/config/localization.yaml"}));
  const SlamRecordingResult single = runSlam(recording, slam_params);
  const RelationsError one =
      errorOf(relations, recording, {single.scan_poses.begin(), single.scan_poses.end()});
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
