// A map that follows the building (issue 35, item 5): the simulated office mapped, then driven again some
// months later (config/worlds/office_changed.yaml: walls removed and moved, new ones, a door closed), the
// second session continuing the first's map. On the true poses, so the figures are CAE-RLSM's own: the
// continued map must have retired the removed walls, hold the new ones, keep every unchanged wall that
// the map kept without retirement, and fit the building as it stands. Without see_through the removed
// walls stay (the floor's counter-check).
#include <gtest/gtest.h>

#include <cstdio>

#include "line_map_eval/batch/changed_world.hpp"

namespace
{
using namespace line_map_eval;

const ChangedWorldResult& officeChanged()
{
  static const ChangedWorldResult result = []
  {
    BatchOptions options;
    options.params = loadParameterFiles({LINEMAP_SOURCE_DIR "/config/line_extraction.yaml",
                                         LINEMAP_SOURCE_DIR "/config/line_map_merging.yaml",
                                         LINEMAP_SOURCE_DIR "/config/line_map_eval.yaml"});
    options.progress = false;
    options.figure_formats = 0;
    const auto slam = line_map_merging::LaserSlamParams::fromParams(
        loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}));
    const auto localizer = line_map_merging::LocalizerParams::fromParams(
        loadParameterFiles({LINEMAP_SOURCE_DIR "/config/localization.yaml"}));
    return runChangedWorld(loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/office.yaml"),
                           loadWorld(LINEMAP_SOURCE_DIR "/config/worlds/office_changed.yaml"), options,
                           ChangedWorldPoses::kTruth, slam, localizer,
                           ::testing::TempDir() + "changed_world");
  }();
  return result;
}

void print(const char* name, const ChangedWorldMap& m)
{
  std::printf("%-28s q %.2f %%, removed retired %.1f %%, added %.1f %%, unchanged %.1f %%\n", name, m.quality,
              m.changes.removed_retired, m.changes.added_coverage, m.changes.unchanged_coverage);
}

TEST(ChangedWorld, TheContinuedMapFollowsTheBuilding)
{
  const ChangedWorldResult& r = officeChanged();
  print("first session", r.first);
  print("continued", r.continued);
  print("continued, see_through off", r.kept);
  print("second session alone", r.fresh);
  // The world file's changes are in sight of the path: removed and added walls were seen.
  ASSERT_GT(r.first.changes.removed_length, 10.0);
  ASSERT_GT(r.first.changes.added_length, 5.0);
  EXPECT_GE(r.continued.changes.removed_retired, 95.0);
  EXPECT_GE(r.continued.changes.added_coverage, 95.0);
  EXPECT_GE(r.continued.changes.unchanged_coverage, r.kept.changes.unchanged_coverage - 0.5);
  EXPECT_GE(r.continued.quality, 97.0);
}

TEST(ChangedWorld, WithoutRetirementTheRemovedWallsStay)
{
  const ChangedWorldResult& r = officeChanged();
  EXPECT_LT(r.kept.changes.removed_retired, 20.0);
  EXPECT_EQ(r.kept.retired, 0u);
  EXPECT_GT(r.continued.retired, 0u);
  EXPECT_LT(r.kept.quality, r.continued.quality - 2.0);
}

}  // namespace
