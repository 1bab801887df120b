// changed_world_benchmark: a map that follows the building. The robot maps a world, then drives the same
// path in the world after its changes and continues the first session (SLAM and CAE-RLSM). Prints, per
// map, q against the second session's scans and the ground-truth figures of the removed, added and
// unchanged walls: the first session's map, the continued one, the continued one with see_through off
// (every old wall kept), and the second session mapped alone.
//
//   rosrun line_map_eval changed_world_benchmark [BEFORE.yaml AFTER.yaml] [--poses slam|truth]
//       [--start X,Y,THETA] [--param key=value]... [--seed N] [--out DIR]
// --poses truth: the keyframes at their true poses (the map's own behaviour, without the SLAM's error).
//   (from the repository root; default config/worlds/office.yaml config/worlds/office_changed.yaml)
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "benchmark_common.hpp"
#include "line_map_eval/batch/changed_world.hpp"
#include "line_map_eval/batch/figures.hpp"

int main(int argc, char** argv)
{
  using namespace line_map_eval;
  const char* usage =
      "usage: changed_world_benchmark [BEFORE.yaml AFTER.yaml] [--poses slam|truth] [--start X,Y,THETA] "
      "[--param key=value]... [--seed N] [--out DIR]";
  const char* root_env = std::getenv("LINEMAP_ROOT");
  const std::string root = root_env ? root_env : ".";
  std::string before = root + "/config/worlds/office.yaml",
              after = root + "/config/worlds/office_changed.yaml";
  int first_option = 1;
  if (argc >= 3 && argv[1][0] != '-' && argv[2][0] != '-')
  {
    before = argv[1];
    after = argv[2];
    first_option = 3;
  }
  std::optional<linemap::Pose2> start;
  ChangedWorldPoses poses = ChangedWorldPoses::kSlam;
  std::vector<std::string> overrides;
  std::optional<std::uint32_t> seed;
  std::string out = "changed_world_out";
  if (const auto stop = benchmark::parseOptions(
          argc - first_option + 1, argv + first_option - 1, "changed_world_benchmark", usage,
          {{"--start",
            [&](const std::string& v)
            {
              linemap::Pose2 p;
              if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &p.x, &p.y, &p.theta) != 3)
                throw std::invalid_argument("--start: '" + v + "' is not X,Y,THETA");
              start = p;
            }},
           {"--out", [&](const std::string& v) { out = v; }},
           {"--param", [&](const std::string& v) { overrides.push_back(v); }},
           {"--seed", [&](const std::string& v) { seed = static_cast<std::uint32_t>(std::stoul(v)); }},
           {"--poses", [&](const std::string& v)
            {
              if (v != "slam" && v != "truth")
                throw std::invalid_argument("--poses: '" + v + "' is not slam or truth");
              poses = v == "slam" ? ChangedWorldPoses::kSlam : ChangedWorldPoses::kTruth;
            }}}))
    return *stop;
  const auto config = [&](const char* name) { return root + "/config/" + name; };
  BatchOptions options;
  options.params = loadParameterFiles(
      {config("line_extraction.yaml"), config("line_map_merging.yaml"), config("line_map_eval.yaml")});
  for (const std::string& o : overrides) applyOverride(options.params, o);
  options.progress = false;
  options.figure_formats = kFigurePng;
  const auto slam = line_map_merging::LaserSlamParams::fromParams(loadParameterFiles({config("slam.yaml")}));
  const auto localizer =
      line_map_merging::LocalizerParams::fromParams(loadParameterFiles({config("localization.yaml")}));
  World before_world = loadWorld(before), after_world = loadWorld(after);
  if (seed)  // other noise in both sessions (the second's is its world's seed plus one)
    before_world.seed = after_world.seed = *seed;
  const ChangedWorldResult r =
      runChangedWorld(before_world, after_world, options, poses, slam, localizer, out, start);

  std::printf("%s -> %s (figures and maps under %s/)\n", before.c_str(), after.c_str(), out.c_str());
  if (poses == ChangedWorldPoses::kTruth)
    std::printf("keyframes at their true poses\n");
  else if (r.localized_at)
    std::printf("second session placed at scan %zu, %zu closures to the first session's keyframes\n",
                *r.localized_at, r.closures_between);
  else
    std::printf("second session never placed in the first: no continued map\n");
  const ChangeScores& c = r.first.changes;
  std::printf("seen walls: removed %.1f m, added %.1f m, unchanged %.1f m\n", c.removed_length,
              c.added_length, c.unchanged_length);
  std::printf(
      "| map | q (building now) | removed walls retired | added walls covered | unchanged walls covered | "
      "coverage of its world | segments | originals retired |\n|---|---|---|---|---|---|---|---|\n");
  const auto row = [](const char* name, const ChangedWorldMap& m)
  {
    std::printf("| %s | %.2f %% | %.1f %% | %.1f %% | %.1f %% | %.1f %% | %zu | %zu |\n", name, m.quality,
                m.changes.removed_retired, m.changes.added_coverage, m.changes.unchanged_coverage,
                m.truth_coverage, m.segments, m.retired);
  };
  row("first session", r.first);
  if (r.localized_at)
  {
    row("continued", r.continued);
    row("continued, see_through off", r.kept);
  }
  row("second session alone", r.fresh);
  return 0;
}
