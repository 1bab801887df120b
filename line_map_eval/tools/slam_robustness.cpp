// slam_robustness: the laser SLAM's robustness benchmark (batch/slam_robustness.hpp). Runs the SLAM on
// a raw CARMEN log (scored by its relations file) or a simulated world (scored by relations taken from
// its ground truth) under the defaults, each numeric parameter x0.7 and x1.4, and seeded input faults;
// prints every run, the median, 90th percentile and worst error, and each failure with its cause and the
// command that runs it again alone.
#include "line_map_eval/batch/slam_robustness.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "config_files.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "tool_main.hpp"

namespace fs = std::filesystem;
using namespace line_map_eval;

namespace
{
void usage(std::ostream& out)
{
  out << "usage: slam_robustness DATASET [RELATIONS] [--no-odometry] [--runs N] [--seed S] [--jobs J]\n"
         "                       [--only defaults|parameters|faults]... [--keys K1,K2,...] [--fault "
         "NAME]...\n"
         "                       [--config FILE] [--param key=value]... [--sensor FILE] [--csv FILE]\n"
         "                       [--figures DIR]\n"
         "The laser SLAM's robustness: runs it under the defaults, each numeric parameter of "
         "config/slam.yaml\n"
         "(front_end/, graph/, loop/, isotropic_ratio, min_weight) scaled x0.7 and x1.4 one at a time, and "
         "N\n"
         "seeded runs of each input fault (odometry 3 % long or short, heading drifting 3 mrad/m, 10 % of "
         "the\n"
         "scans dropped, the log started later, stamps jittered, the front end slipping by 0.3 m and 5 "
         "degrees\n"
         "at a random scan of the first half; the odometry faults only with odometry).\n"
         "Prints each run's relations error, then the median, 90th percentile and worst, and every failure\n"
         "(worse than 2x the defaults or above 0.1 m) with the change behind it. Exit 0 whatever the "
         "figures.\n"
         "  DATASET          a raw CARMEN log with its RELATIONS file; a corrected CARMEN log with ODOM\n"
         "                   lines (the SLAM on its scans and odometry, relations from its corrected\n"
         "                   poses); or a world file (config/worlds/*.yaml, simulated; relations from\n"
         "                   its ground truth)\n"
         "  --no-odometry    the SLAM on the scans alone\n"
         "  --runs N         seeded runs per fault (default 3)\n"
         "  --seed S         the first seed (default 1)\n"
         "  --jobs J         runs in parallel (default 1; CPU times are per run either way)\n"
         "  --only WHAT      only these groups (repeatable); the defaults always run\n"
         "  --keys K1,K2     only these parameters\n"
         "  --fault NAME     only this input fault (repeatable): odometry-scale, heading-drift,\n"
         "                   dropped-scans, late-start, stamp-jitter, front-end-slip\n"
         "  --config FILE    the SLAM parameter file (default: slam.yaml in the config directory\n"
         "                   linemap_batch finds: $LINEMAP_CONFIG_DIR, $LINEMAP_ROOT/config, or\n"
         "                   upwards from the executable or the working directory)\n"
         "  --param key=value  a changed default for every run\n"
         "  --sensor FILE    (a world) its laser replaced by this sensor profile\n"
         "  --csv FILE       every run as a CSV row\n"
         "  --figures DIR    each run's SLAM figure (trajectory, closures, relations above 0.3 m) and\n"
         "                   trajectory ('stamp x y theta') in DIR, and a world's true one (truth.txt)\n";
}

struct Arguments
{
  std::vector<std::string> positional, overrides, only;
  std::vector<InputFault> faults;  ///< --fault: only these (empty: all)
  std::string config, sensor, csv, keys, figures;
  bool odometry = true;
  std::size_t runs = 3, jobs = 1;
  std::uint32_t seed = 1;
};

bool parseArguments(int argc, char** argv, Arguments& a)
{
  for (CommandLine cl(argc, argv); cl.next();)
  {
    const std::string& arg = cl.arg();
    if (arg == "--help" || arg == "-h") return false;
    if (arg == "--no-odometry")
      a.odometry = false;
    else if (arg == "--runs")
      a.runs = parseCount(arg, cl.value());
    else if (arg == "--seed")
      a.seed = static_cast<std::uint32_t>(parseCount(arg, cl.value()));
    else if (arg == "--jobs")
      a.jobs = std::max<std::size_t>(1, parseCount(arg, cl.value()));
    else if (arg == "--only")
    {
      a.only.push_back(cl.value());
      if (a.only.back() != "defaults" && a.only.back() != "parameters" && a.only.back() != "faults")
        throw std::invalid_argument("--only expects defaults, parameters or faults, got '" + a.only.back() +
                                    "'");
    }
    else if (arg == "--fault")
    {
      const std::string name = cl.value();
      const auto fault = faultFromName(name);
      if (!fault)
      {
        std::string names;
        for (InputFault f : allInputFaults()) names += (names.empty() ? "" : ", ") + faultOption(f);
        throw std::invalid_argument("--fault expects one of " + names + ", got '" + name + "'");
      }
      a.faults.push_back(*fault);
    }
    else if (arg == "--keys")
      a.keys = cl.value();
    else if (arg == "--config")
      a.config = cl.value();
    else if (arg == "--param")
      a.overrides.push_back(cl.value());
    else if (arg == "--sensor")
      a.sensor = cl.value();
    else if (arg == "--csv")
      a.csv = cl.value();
    else if (arg == "--figures")
      a.figures = cl.value();
    else if (!arg.empty() && arg[0] == '-')
      throw std::invalid_argument("unknown option " + arg);
    else
      a.positional.push_back(arg);
  }
  if (a.positional.empty() || a.positional.size() > 2)
    throw std::invalid_argument("expected DATASET [RELATIONS]");
  return true;
}

/// The recording, the stamp each scan is known by in the relations, and the relations.
struct Input
{
  Recording recording;
  std::vector<double> stamps;
  std::vector<Relation> relations;
};

Input loadInput(const Arguments& a)
{
  Input in;
  if (isWorldFile(a.positional[0]))
  {
    World world = loadWorld(a.positional[0]);
    if (!a.sensor.empty()) world = withSensorProfile(world, a.sensor);
    in.recording = simulate(world).recording;
    for (const auto& s : in.recording.scans) in.stamps.push_back(s.stamp);
    in.relations = truthRelations(in.recording);
    if (!a.figures.empty())
    {
      fs::create_directories(a.figures);
      std::ofstream truth(fs::path(a.figures) / "truth.txt");
      truth << std::setprecision(17);
      for (const auto& kf : in.recording.keyframes)
        truth << in.recording.scans[kf.scan_index].stamp << " " << kf.pose.x << " " << kf.pose.y << " "
              << kf.pose.theta << "\n";
    }
    return in;
  }
  const CarmenLog raw = readCarmenLog(a.positional[0]);
  if (a.positional.size() == 2)
  {
    in.recording = fromCarmen(raw, nullptr);
    for (const auto& s : raw.scans) in.stamps.push_back(s.timestamp);
    in.relations = readRelations(a.positional[1]);
    return in;
  }
  // A corrected log of keyframes with the robot's ODOM lines: the SLAM on its scans and odometry, judged
  // against its corrected poses.
  if (raw.odometry.size() < 2)
    throw std::invalid_argument(a.positional[0] +
                                ": a raw CARMEN log needs its RELATIONS file, a corrected one ODOM lines");
  std::size_t later = 0;  // scans stamped after the one before
  for (std::size_t i = 1; i < raw.scans.size(); ++i)
    later += raw.scans[i].timestamp > raw.scans[i - 1].timestamp;
  if (2 * later < raw.scans.size())
    throw std::invalid_argument(
        a.positional[0] + ": only " + std::to_string(later) + " of its " + std::to_string(raw.scans.size()) +
        " scans are stamped after the one before: the ODOM lines cannot be placed at them");
  CarmenRecordingOptions options;
  options.odometry_from_odom_lines = true;
  options.odometry_delay = fitOdometryDelay(raw);
  in.recording = fromCarmen(raw, &raw, options);
  for (const auto& s : in.recording.scans) in.stamps.push_back(s.stamp);
  in.relations = truthRelations(in.recording);
  std::cout << a.positional[0] << ": a corrected log; the SLAM on its ODOM lines (delayed by "
            << options.odometry_delay << " s, fitted to its poses), judged against its corrected poses ("
            << in.relations.size() << " relations)\n";
  return in;
}

std::vector<RobustnessVariant> variants(const Arguments& a, const linemap::ParamSet& defaults)
{
  auto wanted = [&](const std::string& group)
  { return a.only.empty() || std::find(a.only.begin(), a.only.end(), group) != a.only.end(); };
  std::vector<RobustnessVariant> out{{"defaults", {}, std::nullopt, 0}};
  if (wanted("parameters"))
    for (auto& v : parameterVariants(defaults))
    {
      const std::string key = v.overrides.front().substr(0, v.overrides.front().find('='));
      if (a.keys.empty() || ("," + a.keys + ",").find("," + key + ",") != std::string::npos)
        out.push_back(std::move(v));
    }
  if (wanted("faults"))
  {
    std::vector<InputFault> faults;
    for (InputFault f : allInputFaults())
    {
      const bool needs_odometry = f == InputFault::kOdometryScale || f == InputFault::kHeadingDrift;
      const bool chosen =
          a.faults.empty() || std::find(a.faults.begin(), a.faults.end(), f) != a.faults.end();
      if (chosen && (a.odometry || !needs_odometry)) faults.push_back(f);
    }
    for (auto& v : faultVariants(faults, a.runs, a.seed)) out.push_back(std::move(v));
  }
  return out;
}

/// Every run's line, the summary and the failures, on stdout.
void printRuns(const Arguments& a, const std::vector<RobustnessRun>& runs, const RobustnessSummary& s)
{
  const bool world = isWorldFile(a.positional[0]);
  const double deg = 180.0 / linemap::kPi;
  std::cout << fs::path(a.positional[0]).filename().string() << (a.odometry ? "" : ", no odometry") << ": "
            << runs.size() << " runs\n"
            << std::left << std::setw(48) << "run" << std::right
            << "  trans [m] mean ± std   rot [deg]  x defaults\n";
  for (const auto& r : runs)
    std::cout << std::left << std::setw(48) << r.variant.label << std::right << std::fixed
              << std::setprecision(4) << std::setw(9) << r.error.translation_mean << " ± " << std::setw(6)
              << r.error.translation_std << std::setprecision(2) << std::setw(9)
              << r.error.rotation_mean * deg << std::setw(10)
              << (s.defaults > 0.0 ? r.error.translation_mean / s.defaults : 0.0) << "  "
              << line_map_merging::closureSummary(r.counters)
              << (world ? ", " + std::to_string(r.false_closures) + " false" : std::string()) << ", "
              << std::setprecision(1) << r.cpu_seconds << " s CPU\n";
  std::cout << std::setprecision(4) << "defaults " << s.defaults << " m; median " << s.median
            << " m, 90th percentile " << s.p90 << " m, worst " << s.worst << " m (" << s.worst_label << ", "
            << std::setprecision(2) << (s.defaults > 0.0 ? s.worst / s.defaults : 0.0) << "x the defaults)\n";
  if (!s.by_fault.empty())
  {
    std::cout << "by fault:";
    for (const auto& t : s.by_fault)
      std::cout << (&t == &s.by_fault.front() ? " " : "; ") << faultName(t.fault) << " " << t.failures
                << " of " << t.runs << " failing (worst " << std::setprecision(4) << t.worst << " m)";
    std::cout << "\n";
  }
  std::cout << s.failures << " failures (worse than 2x the defaults or above 0.1 m)"
            << (s.failures ? ":" : "") << "\n";
  // Each failure with the command that runs it again alone.
  std::string again = "slam_robustness";
  for (const auto& p : a.positional) again += " " + p;
  if (!a.odometry) again += " --no-odometry";
  if (!a.config.empty()) again += " --config " + a.config;
  if (!a.sensor.empty()) again += " --sensor " + a.sensor;
  for (const auto& o : a.overrides) again += " --param " + o;
  for (const auto& r : runs)
    if (!r.failure.empty())
      std::cout << "  " << r.variant.label << ": " << r.failure << "\n    again: " << again << " "
                << rerunOptions(r.variant) << "\n";
}

/// Every run as a CSV row in `path`.
void writeCsv(const std::string& path, const std::vector<RobustnessRun>& runs)
{
  const double deg = 180.0 / linemap::kPi;
  std::ofstream csv(path);
  csv << "run,translation_mean,translation_std,rotation_mean_deg,relations_used,closures,inconsistent,cpu_"
         "s,"
         "failure\n";
  for (const auto& r : runs)
    csv << '"' << r.variant.label << "\"," << r.error.translation_mean << "," << r.error.translation_std
        << "," << r.error.rotation_mean * deg << "," << r.error.used << "," << r.counters.loops_accepted
        << "," << r.counters.loops_inconsistent << "," << r.cpu_seconds << ",\"" << r.failure << "\"\n";
  if (!csv) throw std::runtime_error(path + ": cannot write");
}

int run(const Arguments& a)
{
  linemap::ParamSet defaults = loadParameterFiles(configFiles(a.config, "slam.yaml", "slam_robustness"));
  for (const auto& o : a.overrides) applyOverride(defaults, o);
  const Input input = loadInput(a);
  if (!a.figures.empty()) fs::create_directories(a.figures);
  std::vector<RobustnessVariant> todo = variants(a, defaults);
  std::vector<RobustnessRun> runs(todo.size());
  std::atomic<std::size_t> next{0};
  std::mutex print;
  auto worker = [&]
  {
    for (std::size_t i; (i = next++) < todo.size();)
    {
      std::string figure;
      if (!a.figures.empty()) figure = (fs::path(a.figures) / ("run" + std::to_string(i))).string();
      runs[i] =
          runVariant(input.recording, input.stamps, input.relations, defaults, todo[i], a.odometry, figure);
      const std::lock_guard<std::mutex> lock(print);
      std::cerr << "[" << i + 1 << "/" << todo.size() << "] " << todo[i].label << ": " << std::fixed
                << std::setprecision(4) << runs[i].error.translation_mean << " m\n";
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t j = 0; j < std::min(a.jobs, todo.size()); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  const RobustnessSummary summary = summarize(runs);  // marks each run's failure
  printRuns(a, runs, summary);
  if (!a.csv.empty()) writeCsv(a.csv, runs);
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  Arguments a;
  return toolMain(
      "slam_robustness", [&] { return parseArguments(argc, argv, a); }, usage, [&] { return run(a); });
}
