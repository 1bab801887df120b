// linemap_batch: extraction -> keyframe gating -> merging -> evaluation without a ROS master, for
// one or several mergers sharing one extraction; prints the comparison table and writes the
// reports, figures and map files.
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "config_files.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/progress.hpp"
#include "line_map_eval/batch/report.hpp"
#include "line_map_eval/batch/slam_figure.hpp"
#include "line_map_eval/datasets/bag_reader.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/online/bag_replay.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/slam/session_file.hpp"
#include "linemap/atomic_file.hpp"
#include "linemap/small_helpers.hpp"
#include "tool_main.hpp"

namespace fs = std::filesystem;
using namespace line_map_eval;

namespace
{

void usage(std::ostream& out)
{
  out << "usage: linemap_batch DATASET [--corrected LOG | --slam [--relations FILE] [--save-session F]]\n"
         "       linemap_batch RUN... --slam [--session F] [--save-session F]\n"
         "                     [--extractor NAME] [--merger NAME]...\n"
         "                     [--param key=value]... [--config FILE]... [--config-dir DIR] [--out DIR]\n"
         "                     [--every N] [--sensor FILE] [--pose-noise P,H[,L]] [--no-progress] "
         "[--no-figures] [--time-steps]\n"
         "                     [--help]\n"
         "\n"
         "DATASET is a raw CARMEN log (with --corrected: its corrected keyframe log), a corrected or\n"
         "pre-registered CARMEN log alone, a world file (config/worlds/*.yaml, simulated in-process) or a\n"
         "rosbag (.bag: scan + tf, optional optimized_trajectory).\n"
         "\n"
         "  --corrected LOG   corrected keyframes of the raw log: online mergers merge on the raw odometry\n"
         "                    and receive the corrected trajectory every N keyframes and at the end\n"
         "  --slam            (a raw CARMEN log) the trajectory of our laser SLAM (config/slam.yaml) in\n"
         "                    place of --corrected: its keyframes are the merger's keyframes\n"
         "  --relations FILE  with --slam: print the relations error of its trajectory against FILE\n"
         "                    (--slam writes DIR/slam.svg and .png: trajectory, scans, closures and the\n"
         "                    relations above 0.3 m)\n"
         "  --save-session F  with --slam: write the session file F (the SLAM's keyframes, graph and scans,\n"
         "                    and the cae map with its provenance: line_map_merging/README.md)\n"
         "  RUN...            with --slam: several raw CARMEN logs or rosbags (scan + odom tf, or scans\n"
         "                    alone) mapped into one graph and one map, in order: each later run is\n"
         "                    placed by global localization in the map of those before it\n"
         "  --session F       with --slam: the runs continue the saved session F (placed in its map by\n"
         "                    global localization; the graph and, with --merger cae, its map go on)\n"
         "  --extractor NAME  extraction algorithm (default: parameter 'algorithm')\n"
         "  --merger NAME     merger to run; repeatable (default: all of ";
  for (std::size_t i = 0; i < line_map_merging::mergerNames().size(); ++i)
    out << (i ? ", " : "") << line_map_merging::mergerNames()[i];
  out << ")\n"
         "  --param key=value override a parameter by its config/*.yaml name (nested keys as a/b)\n"
         "  --config FILE     an extra YAML parameter file, read after the defaults\n"
         "  --config-dir DIR  where line_extraction.yaml, line_map_merging.yaml, line_map_eval.yaml are\n"
         "                    (default: $LINEMAP_CONFIG_DIR, $LINEMAP_ROOT/config, or found from the\n"
         "                    executable or the working directory)\n"
         "  --out DIR         write DIR/report.json, DIR/report.md and DIR/<merger>/ figures and map\n"
         "                    files (default: linemap_batch_out)\n"
         "  --every N         keyframes between the trajectories of the loop closure (default 50; 0: only "
         "at\n"
         "                    the end); a .bag's own trajectories are used as they are\n"
         "  --sensor FILE     (a world file) simulate with this sensor profile (config/sensors/*.yaml):\n"
         "                    its laser block replaces the world's key by key\n"
         "  --pose-noise P,H[,L]  (a world file) the keyframes' registered poses err: std P [m] of x\n"
         "                    and y, H [deg] of the heading, correlated over L m of path (default 10)\n"
         "  --no-progress     no progress bars\n"
         "  --no-figures      write the reports and map files only\n"
         "  --time-steps      time each step of the mergers that name theirs (CAE-RLSM: OTM-ILSM, map\n"
         "                    merge, crossings, per keyframe and per adjustment) into the reports\n"
         "  --replay          (a .bag) feed the bag's messages in bag order to the online mapper and\n"
         "                    evaluator the nodelets run (one --merger, default cae); writes "
         "DIR/replay.json\n";
}

/// The command line.
struct Arguments
{
  std::string dataset, corrected, config_dir, out_dir = "linemap_batch_out";
  std::vector<std::string> configs, overrides;
  bool replay = false, slam = false;
  std::string relations, sensor, save_session, session;
  std::vector<std::string> more_runs;  ///< with --slam: the runs after the first
  std::optional<line_map_eval::RegistrationModel> pose_noise;
  BatchOptions options;
};

/// Parses the command line; false after --help. Throws std::invalid_argument on a bad one.
bool parseArguments(int argc, char** argv, Arguments& a)
{
  for (CommandLine cl(argc, argv); cl.next();)
  {
    const std::string& arg = cl.arg();
    if (arg == "--help" || arg == "-h") return false;
    std::string* text = arg == "--corrected"      ? &a.corrected
                        : arg == "--extractor"    ? &a.options.extractor
                        : arg == "--config-dir"   ? &a.config_dir
                        : arg == "--out"          ? &a.out_dir
                        : arg == "--sensor"       ? &a.sensor
                        : arg == "--relations"    ? &a.relations
                        : arg == "--save-session" ? &a.save_session
                        : arg == "--session"      ? &a.session
                                                  : nullptr;
    std::vector<std::string>* list = arg == "--merger"   ? &a.options.mergers
                                     : arg == "--param"  ? &a.overrides
                                     : arg == "--config" ? &a.configs
                                                         : nullptr;
    if (text)
      *text = cl.value();
    else if (list)
      list->push_back(cl.value());
    else if (arg == "--every")
      a.options.adjust_every = parseCount(arg, cl.value());
    else if (arg == "--no-progress")
      a.options.progress = false;
    else if (arg == "--no-figures")
      a.options.figure_formats = 0;
    else if (arg == "--time-steps")
      a.options.time_steps = true;
    else if (arg == "--slam")
      a.slam = true;
    else if (arg == "--pose-noise")
      a.pose_noise = line_map_eval::parseRegistrationOption(arg, cl.value());
    else if (arg == "--replay")
      a.replay = true;
    else if (!arg.empty() && arg[0] == '-')
      throw std::invalid_argument("unknown option " + arg);
    else if (a.dataset.empty())
      a.dataset = arg;
    else
      a.more_runs.push_back(arg);
  }
  if (a.dataset.empty()) throw std::invalid_argument("no dataset given");
  if (!a.more_runs.empty() && !a.slam)
    throw std::invalid_argument("more than one dataset (" + a.dataset + ", " + a.more_runs.front() +
                                "): several runs go with --slam, which maps them into one graph");
  if (!a.session.empty() && !a.slam)
    throw std::invalid_argument("--session goes with --slam (the runs continue the session's graph)");
  if (!a.relations.empty() && (!a.more_runs.empty() || !a.session.empty()))
    throw std::invalid_argument("--relations goes with one run and no --session");
  if (!a.save_session.empty() && !a.slam)
    throw std::invalid_argument(
        "--save-session goes with --slam (a session is the SLAM's graph and its map)");
  return true;
}

/// The parameter files (config dir, then --config) and the --param overrides; the SLAM's apart (its
/// frame names are the nodelet's, not the merger's).
void loadParameters(Arguments& a, linemap::ParamSet& slam_params, linemap::ParamSet& localization_params)
{
  const fs::path dir = findConfigDir(a.config_dir);
  std::vector<std::string> files;
  if (dir.empty())
    std::cerr
        << "linemap_batch: no config directory found (use --config-dir); running on built-in defaults\n";
  else
    for (const char* name : kPipelineConfigFiles)
      if (fs::exists(dir / name))
        files.push_back((dir / name).string());
      else
        std::cerr << "linemap_batch: " << (dir / name).string() << " not found; its defaults are built in\n";
  files.insert(files.end(), a.configs.begin(), a.configs.end());
  a.options.params = loadParameterFiles(files);
  if (a.slam && !dir.empty() && fs::exists(dir / "slam.yaml"))
    slam_params = loadParameterFiles({(dir / "slam.yaml").string()});
  if (a.slam && !dir.empty() && fs::exists(dir / "localization.yaml"))
    localization_params = loadParameterFiles({(dir / "localization.yaml").string()});
  for (const auto& o : a.overrides)
  {
    const std::string key = o.substr(0, o.find('='));
    if (slam_params.has(key))
    {
      applyOverride(slam_params, o);
      continue;
    }
    if (localization_params.has(key) && !a.options.params.has(key))
    {
      applyOverride(localization_params, o);
      continue;
    }
    if (!a.options.params.has(key))
      std::cerr << "linemap_batch: warning: --param " << key << " is in none of the parameter files\n";
    applyOverride(a.options.params, o);
  }
}

int runReplay(const Arguments& a)
{
  if (fs::path(a.dataset).extension() != ".bag") throw std::invalid_argument("--replay needs a .bag");
  ReplayOptions ro;
  ro.params = a.options.params;
  if (!a.options.mergers.empty()) ro.method = a.options.mergers.front();
  const ReplayResult r = replayBag(readBag(a.dataset), ro);
  fs::create_directories(a.out_dir);
  const std::string json = (fs::path(a.out_dir) / "replay.json").string();
  writeReplayJson(r, json);
  std::cout << std::fixed << std::setprecision(2) << "replay of " << r.scans << " scans, " << r.trajectories
            << " trajectories: " << r.keyframe_stamps.size() << " keyframes, " << r.map.size()
            << " map segments, quality " << (r.metrics ? r.metrics->quality.quality : 0.0) << " %, "
            << r.evaluator_scans << " evaluator scans, " << r.wall_ms << " ms; wrote " << json << "\n";
  return 0;
}

/// A run for the SLAM: a raw CARMEN log, or a rosbag's scans with their odometry (`odometry` false: the bag
/// has none).
Recording readRun(const std::string& path, bool& odometry)
{
  odometry = true;
  if (isWorldFile(path))
    throw std::invalid_argument("--slam takes raw CARMEN logs and rosbags, not the world file " + path);
  if (fs::path(path).extension() != ".bag") return fromCarmen(readCarmenLog(path), nullptr);
  BagContents bag = readBag(path);
  bag.recording.keyframes.clear();  // the SLAM makes the trajectory
  odometry = bag.odometry;
  if (!odometry) std::cout << path << ": scans without odometry (no odom -> base_link on /tf): laser only\n";
  return std::move(bag.recording);
}

/// A raw CARMEN log or a rosbag with the trajectory of our laser SLAM as the loop closure; the SLAM's part
/// of the session into `session`.
BatchDataset slamDataset(const Arguments& a, const linemap::ParamSet& slam_params,
                         line_map_merging::SlamSession& session)
{
  if (!a.corrected.empty())
    throw std::invalid_argument("--slam makes the trajectory: it does not go with --corrected");
  bool odometry = true;
  Recording recording = readRun(a.dataset, odometry);
  const bool use_odometry = odometry && slam_params.getBool("use_odometry", true);
  const SlamRecordingResult run =
      runSlam(recording, line_map_merging::LaserSlamParams::fromParams(slam_params), use_odometry);
  const auto& c = run.counters;
  std::cout << std::fixed << std::setprecision(1) << "laser SLAM: " << recording.scans.size() << " scans in "
            << run.cpu_seconds << " s CPU, " << c.keyframes << " keyframes, "
            << line_map_merging::closureSummary(c) << ", " << c.poor_matches << " poor matches\n";
  std::optional<std::vector<RelationResidual>> residuals;
  if (!a.relations.empty())
  {
    std::vector<std::pair<double, Pose2>> poses;
    for (std::size_t i = 0; i < run.scan_poses.size(); ++i)
      poses.push_back({recording.scans[i].stamp, run.scan_poses[i]});
    const auto relations = readRelations(a.relations);
    const RelationsError e = relationsError(relations, poses);
    residuals = relationResiduals(relations, poses);
    std::cout << std::setprecision(4) << "relations error (" << e.used << " of " << e.relations
              << "): translation " << e.translation_mean << " +- " << e.translation_std << " m, rotation "
              << std::setprecision(2) << e.rotation_mean * 180.0 / linemap::kPi << " +- "
              << e.rotation_std * 180.0 / linemap::kPi << " deg\n";
  }
  if (a.options.figure_formats != 0)
  {
    fs::create_directories(a.out_dir);
    const std::string caption =
        linemap::fileStem(a.dataset) + " - laser SLAM" + (use_odometry ? "" : ", no odometry");
    const auto files = drawSlamRun(recording, run, residuals ? &*residuals : nullptr, caption,
                                   (fs::path(a.out_dir) / "slam").string());
    std::cout << "wrote the SLAM figure " << files.back() << "\n";
  }
  session = run.session;
  return datasetFromRecording(withSlamKeyframes(std::move(recording), run), linemap::fileStem(a.dataset),
                              "carmen+slam");
}

/// One line per run of `joined`: where it was placed and what it closed; returns how many were placed.
std::size_t printRuns(const std::vector<std::string>& paths, const std::vector<Recording>& runs,
                      const SessionsRun& joined, bool after_a_session)
{
  std::size_t placed = 0;
  for (std::size_t r = 0; r < runs.size(); ++r)
  {
    std::cout << "  run " << r + 1 << " " << paths[r] << ": " << runs[r].scans.size() << " scans, ";
    if (!joined.localized_at[r] && !joined.joined_at[r])
    {
      std::cout << "NOT placed: global localization found no pose in the map so far, neither within its "
                   "first 400 scans nor later; left out\n";
      continue;
    }
    ++placed;
    std::cout << joined.keyframes[r].size() << " keyframes, "
              << line_map_merging::closureSummary(joined.counters[r]);
    if (joined.joined_at[r])
      std::cout << "; not found within its first 400 scans: mapped apart, and joined at scan "
                << *joined.joined_at[r] << " (the map frame is now this run's), "
                << joined.closures_to_earlier[r] << " closures to earlier runs";
    else if (after_a_session || r > 0)
      std::cout << "; placed at scan " << *joined.localized_at[r] << ", " << joined.closures_to_earlier[r]
                << " closures to earlier runs";
    std::cout << "\n";
  }
  return placed;
}

/// Several runs (or runs after a saved session) mapped into one graph by the SLAM, then merged as one
/// recording; the joined graph into `session`.
BatchDataset sessionsDataset(const Arguments& a, const linemap::ParamSet& slam_params,
                             const linemap::ParamSet& localization_params,
                             line_map_merging::SlamSession& session)
{
  if (!a.corrected.empty())
    throw std::invalid_argument("--slam makes the trajectory: it does not go with --corrected");
  std::vector<std::string> paths{a.dataset};
  paths.insert(paths.end(), a.more_runs.begin(), a.more_runs.end());
  std::vector<Recording> runs;
  bool use_odometry = slam_params.getBool("use_odometry", true);
  for (const auto& path : paths)
  {
    bool odometry = true;
    runs.push_back(readRun(path, odometry));
    use_odometry = use_odometry && odometry;
  }
  std::optional<line_map_merging::Session> loaded;
  std::optional<line_map_merging::SlamSession> saved;
  if (!a.session.empty())
  {
    loaded = line_map_merging::readSessionFile(a.session);
    saved = loaded->slam;
  }
  const std::vector<double> shifts =
      followInTime(runs, saved && !saved->scans.empty() ? saved->scans.back().stamp
                                                        : -std::numeric_limits<double>::infinity());
  const SessionsRun joined =
      runSessions(runs, saved, line_map_merging::LaserSlamParams::fromParams(slam_params),
                  line_map_merging::LocalizerParams::fromParams(localization_params), use_odometry);
  std::cout << std::fixed << std::setprecision(1) << "laser SLAM, " << runs.size()
            << (runs.size() == 1 ? " run" : " runs")
            << (saved ? " after the session " + a.session : std::string())
            << (use_odometry ? "" : ", no odometry") << ": " << joined.session.keyframes.size()
            << " keyframes in one graph, " << joined.cpu_seconds << " s CPU\n";
  const std::size_t placed = printRuns(paths, runs, joined, saved.has_value());
  if (placed == 0) throw std::runtime_error("no run could be placed in the session " + a.session);
  for (std::size_t r = 0; r < shifts.size(); ++r)
    if (shifts[r] != 0.0)
      std::cout << "  run " << r + 1 << ": stamps shifted by " << shifts[r]
                << " s to follow the run before it in time\n";
  Recording recording = joinedRecording(runs, joined, use_odometry);
  session = joined.session;
  std::string name = linemap::fileStem(a.dataset);
  for (const auto& path : a.more_runs) name += "+" + linemap::fileStem(path);
  BatchDataset dataset = datasetFromRecording(std::move(recording), name, "runs+slam");
  if (loaded) dataset.saved_map = continuedMap(*loaded, joined.session, a.session + " (record LMAP)");
  return dataset;
}

/// A rosbag: its scans and, when it has them, its trajectories; the ground truth beside a simulated one.
BatchDataset bagDataset(const std::string& path)
{
  BagContents bag = readBag(path);
  const bool trajectory = !bag.recording.keyframes.empty();
  BatchDataset dataset = datasetFromRecording(std::move(bag.recording), linemap::fileStem(path),
                                              trajectory ? "bag+trajectory" : "bag");
  // The online mergers get the bag's messages as --replay and the nodelets do.
  dataset.schedule = BackEndSchedule{std::move(bag.trajectory), std::move(bag.map_to_odom)};
  // A simulated bag carries its ground truth next to it (simulate_world writes OUT.truth.yaml).
  const std::string truth = truthPathForBag(path);
  if (fs::exists(truth)) dataset.truth = readGroundTruth(truth);
  return dataset;
}

BatchDataset loadDataset(const Arguments& a, const linemap::ParamSet& slam_params,
                         const linemap::ParamSet& localization_params, line_map_merging::SlamSession& session)
{
  if (a.slam && (!a.more_runs.empty() || !a.session.empty()))
    return sessionsDataset(a, slam_params, localization_params, session);
  if (a.slam) return slamDataset(a, slam_params, session);
  const bool bag = fs::path(a.dataset).extension() == ".bag";
  if (!a.corrected.empty())
  {
    if (isWorldFile(a.dataset) || bag)
      throw std::invalid_argument("--corrected goes with a raw CARMEN log, not " + a.dataset);
    return loadCarmenWithCorrection(a.dataset, a.corrected);
  }
  if (isWorldFile(a.dataset))
  {
    ProgressBar bar("simulate", 0, a.options.progress);
    SimulationOptions sim;
    sim.on_scan = [&bar](std::size_t done, std::size_t) { bar.update(done); };
    World world = loadWorld(a.dataset);
    if (!a.sensor.empty()) world = withSensorProfile(world, a.sensor);
    sim.registration = a.pose_noise;
    BatchDataset dataset = simulatedDataset(world, sim);
    bar.finish();
    return dataset;
  }
  return bag ? bagDataset(a.dataset) : loadCarmenRegistered(a.dataset);
}

void printResult(const BatchResult& result)
{
  std::cout << result.dataset << " (" << result.kind << "), extractor " << result.extractor << ", "
            << result.keyframes << " keyframes of " << result.candidate_scans << " candidates\n"
            << formatTable(result);
  double slowest_evaluation = 0.0;
  for (const auto& r : result.mergers) slowest_evaluation = std::max(slowest_evaluation, r.evaluation_ms);
  std::cout << std::fixed << std::setprecision(1) << "extraction " << result.extraction_ms
            << " ms; lookup table of " << result.scan_points << " scan points " << result.table_ms
            << " ms; evaluation of one map <= " << result.table_ms + slowest_evaluation
            << " ms (table included)\n"
            << std::setprecision(2) << "originals fit their own points to " << result.original_fit_rms * 1e3
            << " mm RMS (line position +-" << result.original_line_sigma * 1e3
            << " mm): the error column's excess comes from the poses and the merging\n";
}

/// The SLAM's graph with CAE-RLSM's map (its map file, when cae ran) as a session file.
void saveSession(const BatchResult& result, const std::string& path, line_map_merging::Session& session)
{
  for (const auto& run : result.mergers)
    if (run.name == "cae")
      for (const auto& file : run.files)
        if (fs::path(file).filename() == "map.yaml")
          session.line_map = linemap::readWholeFile(file, "map file");
  if (session.line_map.empty())
    std::cout << "note: the session holds no line map (--merger cae did not run): the SLAM's graph alone\n";
  line_map_merging::writeSessionFile(path, session);
  std::cout << "wrote the session " << path << ": " << session.slam.keyframes.size() << " keyframes, "
            << session.slam.edges.size() << " edges" << (session.line_map.empty() ? "" : ", the cae map")
            << "\n";
}

/// Everything after the command line: the dataset, the mergers, the reports.
int run(Arguments& a)
{
  linemap::ParamSet slam_params, localization_params;
  loadParameters(a, slam_params, localization_params);
  a.options.out_dir = a.out_dir;
  if (!a.sensor.empty() && !isWorldFile(a.dataset))
    throw std::invalid_argument("--sensor goes with a world file (config/worlds/*.yaml), not " + a.dataset);
  if (a.pose_noise && !isWorldFile(a.dataset))
    throw std::invalid_argument("--pose-noise goes with a world file (config/worlds/*.yaml), not " +
                                a.dataset);
  if (a.replay) return runReplay(a);
  line_map_merging::Session session;
  const BatchResult result =
      runBatch(loadDataset(a, slam_params, localization_params, session.slam), a.options);
  printResult(result);
  writeReports(result, a.out_dir);
  if (!a.save_session.empty()) saveSession(result, a.save_session, session);
  const std::string& out_dir = a.out_dir;
  std::cout << "wrote " << (fs::path(out_dir) / "report.json").string() << ", "
            << (fs::path(out_dir) / "report.md").string() << " and the per-merger files under " << out_dir
            << "/<merger>/\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  Arguments a;
  a.options.progress = isatty(STDERR_FILENO) != 0;
  return line_map_eval::toolMain(
      "linemap_batch", [&] { return parseArguments(argc, argv, a); }, usage, [&] { return run(a); }, "\n\n");
}
