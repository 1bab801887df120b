// linemap_batch: extraction -> keyframe gating -> merging -> evaluation without a ROS master, for
// one or several mergers sharing one extraction; prints the comparison table and writes the
// reports, figures and map files.
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "line_map_eval/bag_reader.hpp"
#include "line_map_eval/bag_replay.hpp"
#include "line_map_eval/batch.hpp"
#include "line_map_eval/carmen_log.hpp"
#include "line_map_eval/carmen_recording.hpp"
#include "line_map_eval/ground_truth.hpp"
#include "line_map_eval/progress.hpp"
#include "line_map_eval/relations.hpp"
#include "line_map_eval/report.hpp"
#include "line_map_eval/slam_recording.hpp"
#include "line_map_eval/world.hpp"
#include "line_map_merging/mergers/merger.hpp"

namespace fs = std::filesystem;
using namespace line_map_eval;

namespace
{
const char* const kConfigFiles[] = {"line_extraction.yaml", "line_map_merging.yaml", "line_map_eval.yaml"};

void usage(std::ostream& out)
{
  out << "usage: linemap_batch DATASET [--corrected LOG | --slam [--relations FILE]] [--extractor NAME]\n"
         "                     [--merger NAME]...\n"
         "                     [--param key=value]... [--config FILE]... [--config-dir DIR] [--out DIR]\n"
         "                     [--every N] [--sensor FILE] [--no-progress] [--no-figures] [--help]\n"
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
         "  --every N         keyframes between trajectory corrections (default 50; 0: only at the end)\n"
         "  --sensor FILE     (a world file) simulate with this sensor profile (config/sensors/*.yaml):\n"
         "                    its laser block replaces the world's key by key\n"
         "  --no-progress     no progress bars\n"
         "  --no-figures      write the reports and map files only\n"
         "  --replay          (a .bag) feed the bag's messages in bag order to the online mapper and\n"
         "                    evaluator the nodelets run (one --merger, default cae); writes "
         "DIR/replay.json\n";
}

bool hasConfig(const fs::path& dir)
{
  return fs::exists(dir / kConfigFiles[0]);
}

/// The repository's config directory: explicit, from the environment, or searched upwards from
/// the executable (devel/lib/line_map_eval/ inside a build directory of the repository) and the
/// working directory.
fs::path findConfigDir(const std::string& explicit_dir)
{
  if (!explicit_dir.empty()) return explicit_dir;
  if (const char* env = std::getenv("LINEMAP_CONFIG_DIR")) return env;
  if (const char* root = std::getenv("LINEMAP_ROOT"))
    if (hasConfig(fs::path(root) / "config")) return fs::path(root) / "config";
  std::vector<fs::path> starts;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) starts.push_back(exe.parent_path());
  starts.push_back(fs::current_path(ec));
  for (fs::path dir : starts)
    for (; !dir.empty(); dir = dir.parent_path())
    {
      if (hasConfig(dir / "config")) return dir / "config";
      if (dir == dir.parent_path()) break;
    }
  return {};
}

std::string stem(const std::string& path)
{
  std::string name = fs::path(path).filename().string();
  const auto dot = name.find('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace

int main(int argc, char** argv)
{
  std::string dataset_path, corrected, config_dir, out_dir = "linemap_batch_out";
  std::vector<std::string> configs, overrides;
  bool replay = false, slam = false;
  std::string relations, sensor;
  BatchOptions options;
  options.progress = isatty(STDERR_FILENO) != 0;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string
      {
        if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
        return argv[++i];
      };
      if (arg == "--help" || arg == "-h")
      {
        usage(std::cout);
        return 0;
      }
      else if (arg == "--corrected")
        corrected = value();
      else if (arg == "--extractor")
        options.extractor = value();
      else if (arg == "--merger")
        options.mergers.push_back(value());
      else if (arg == "--param")
        overrides.push_back(value());
      else if (arg == "--config")
        configs.push_back(value());
      else if (arg == "--config-dir")
        config_dir = value();
      else if (arg == "--out")
        out_dir = value();
      else if (arg == "--every")
      {
        const std::string v = value();
        std::size_t used = 0;
        long n = -1;
        try
        {
          n = std::stol(v, &used);
        }
        catch (const std::exception&)
        {
        }
        if (n < 0 || used != v.size())
          throw std::invalid_argument("--every: expected a count >= 0, got '" + v + "'");
        options.adjust_every = static_cast<std::size_t>(n);
      }
      else if (arg == "--no-progress")
        options.progress = false;
      else if (arg == "--no-figures")
        options.figure_formats = 0;
      else if (arg == "--slam")
        slam = true;
      else if (arg == "--sensor")
        sensor = value();
      else if (arg == "--relations")
        relations = value();
      else if (arg == "--replay")
        replay = true;
      else if (!arg.empty() && arg[0] == '-')
        throw std::invalid_argument("unknown option " + arg);
      else if (dataset_path.empty())
        dataset_path = arg;
      else
        throw std::invalid_argument("more than one dataset: " + dataset_path + ", " + arg);
    }
    if (dataset_path.empty()) throw std::invalid_argument("no dataset given");
  }
  catch (const std::exception& e)
  {
    std::cerr << "linemap_batch: " << e.what() << "\n\n";
    usage(std::cerr);
    return 2;
  }

  try
  {
    const fs::path dir = findConfigDir(config_dir);
    std::vector<std::string> files;
    if (dir.empty())
      std::cerr
          << "linemap_batch: no config directory found (use --config-dir); running on built-in defaults\n";
    else
      for (const char* name : kConfigFiles)
        if (fs::exists(dir / name))
          files.push_back((dir / name).string());
        else
          std::cerr << "linemap_batch: " << (dir / name).string()
                    << " not found; its defaults are built in\n";
    files.insert(files.end(), configs.begin(), configs.end());
    options.params = loadParameterFiles(files);
    // The SLAM's parameters apart: its frame names are the nodelet's, not the merger's.
    linemap::ParamSet slam_params;
    if (slam && !dir.empty() && fs::exists(dir / "slam.yaml"))
      slam_params = loadParameterFiles({(dir / "slam.yaml").string()});
    for (const auto& o : overrides)
    {
      const std::string key = o.substr(0, o.find('='));
      if (slam_params.has(key))
      {
        applyOverride(slam_params, o);
        continue;
      }
      if (!options.params.has(key))
        std::cerr << "linemap_batch: warning: --param " << key << " is in none of the parameter files\n";
      applyOverride(options.params, o);
    }
    options.out_dir = out_dir;
    if (!sensor.empty() && !isWorldFile(dataset_path))
      throw std::invalid_argument("--sensor goes with a world file (config/worlds/*.yaml), not " +
                                  dataset_path);

    if (replay)
    {
      if (fs::path(dataset_path).extension() != ".bag") throw std::invalid_argument("--replay needs a .bag");
      ReplayOptions ro;
      ro.params = options.params;
      if (!options.mergers.empty()) ro.method = options.mergers.front();
      const ReplayResult r = replayBag(readBag(dataset_path), ro);
      fs::create_directories(out_dir);
      writeReplayJson(r, (fs::path(out_dir) / "replay.json").string());
      std::cout << std::fixed << std::setprecision(2) << "replay of " << r.scans << " scans, "
                << r.trajectories << " trajectories: " << r.keyframe_stamps.size() << " keyframes, "
                << r.map.size() << " map segments, quality " << (r.metrics ? r.metrics->quality.quality : 0.0)
                << " %, " << r.evaluator_scans << " evaluator scans, " << r.wall_ms << " ms; wrote "
                << (fs::path(out_dir) / "replay.json").string() << "\n";
      return 0;
    }
    BatchDataset dataset;
    if (slam)
    {
      if (!corrected.empty() || isWorldFile(dataset_path) || fs::path(dataset_path).extension() == ".bag")
        throw std::invalid_argument("--slam goes with a raw CARMEN log alone, not with --corrected or " +
                                    dataset_path);
      const CarmenLog raw = readCarmenLog(dataset_path);
      Recording recording = fromCarmen(raw, nullptr);
      const SlamRecordingResult run =
          runSlam(recording, line_map_merging::LaserSlamParams::fromParams(slam_params),
                  slam_params.getBool("use_odometry", true));
      const auto& c = run.counters;
      std::cout << std::fixed << std::setprecision(1) << "laser SLAM: " << recording.scans.size()
                << " scans in " << run.cpu_seconds << " s CPU, " << c.keyframes << " keyframes, "
                << c.loops_accepted << " loop closures (" << c.loops_rejected_score + c.loops_rejected_graph
                << " rejected), " << c.poor_matches << " poor matches\n";
      if (!relations.empty())
      {
        std::vector<std::pair<double, Pose2>> poses;
        for (std::size_t i = 0; i < run.scan_poses.size() && i < raw.scans.size(); ++i)
          poses.push_back({raw.scans[i].timestamp, run.scan_poses[i]});
        const RelationsError e = relationsError(readRelations(relations), poses);
        std::cout << std::setprecision(4) << "relations error (" << e.used << " of " << e.relations
                  << "): translation " << e.translation_mean << " +- " << e.translation_std << " m, rotation "
                  << std::setprecision(2) << e.rotation_mean * 180.0 / linemap::kPi << " +- "
                  << e.rotation_std * 180.0 / linemap::kPi << " deg\n";
      }
      dataset = datasetFromRecording(withSlamKeyframes(std::move(recording), run), stem(dataset_path),
                                     "carmen+slam");
    }
    else if (!corrected.empty())
    {
      if (isWorldFile(dataset_path) || fs::path(dataset_path).extension() == ".bag")
        throw std::invalid_argument("--corrected goes with a raw CARMEN log, not " + dataset_path);
      dataset = loadCarmenWithCorrection(dataset_path, corrected);
    }
    else if (isWorldFile(dataset_path))
    {
      ProgressBar bar("simulate", 0, options.progress);
      SimulationOptions sim;
      sim.on_scan = [&bar](std::size_t done, std::size_t) { bar.update(done); };
      World world = loadWorld(dataset_path);
      if (!sensor.empty()) world = withSensorProfile(world, sensor);
      dataset = simulatedDataset(world, sim);
      bar.finish();
    }
    else if (fs::path(dataset_path).extension() == ".bag")
    {
      BagContents bag = readBag(dataset_path);
      const bool trajectory = !bag.recording.keyframes.empty();
      dataset = datasetFromRecording(std::move(bag.recording), stem(dataset_path),
                                     trajectory ? "bag+trajectory" : "bag");
      // A simulated bag carries its ground truth next to it (simulate_world writes OUT.truth.yaml).
      const std::string truth = truthPathForBag(dataset_path);
      if (fs::exists(truth)) dataset.truth = readGroundTruth(truth);
    }
    else
      dataset = loadCarmenRegistered(dataset_path);

    const BatchResult result = runBatch(dataset, options);
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
    writeReports(result, out_dir);
    std::cout << "wrote " << (fs::path(out_dir) / "report.json").string() << ", "
              << (fs::path(out_dir) / "report.md").string() << " and the per-merger files under " << out_dir
              << "/<merger>/\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "linemap_batch: " << e.what() << "\n";
    return 1;
  }
}
