// linemap_relations: the relations error (Kümmerle et al. 2009) of trajectories of a raw CARMEN log
// against its relations file: our laser SLAM (with or without the log's odometry), the raw odometry,
// the corrected log's keyframes (every other scan anchored to its nearest keyframe by relative
// odometry), a trajectory file ("timestamp x y theta" per line, raw log timestamps), or the log
// localized in a saved line map (--localize).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "config_files.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_figure.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/datasets/localization_recording.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_eval/datasets/slam_sessions.hpp"
#include "linemap/small_helpers.hpp"
#include "tool_main.hpp"

namespace fs = std::filesystem;
using namespace line_map_eval;
using Trajectory = std::vector<std::pair<double, Pose2>>;

namespace
{
void usage(std::ostream& out)
{
  out << "usage: linemap_relations RAW_LOG RELATIONS [--slam] [--slam-no-odometry] [--odometry]\n"
         "                         [--corrected LOG] [--trajectory FILE]... [--param key=value]...\n"
         "                         [--config FILE] [--write FILE] [--out DIR] [--no-figures]\n"
         "                         [--localize MAP_FILE [--initial-pose X,Y,THETA] [--localize-config FILE]\n"
         "                          [--localize-param key=value]...] [--two-sessions [--search-scans N]]\n"
         "Prints the mean and standard deviation of the translational and rotational relation error of\n"
         "each trajectory (default: --slam).\n"
         "  --slam              laser SLAM on the log's scans and odometry\n"
         "  --slam-no-odometry  laser SLAM on the scans alone\n"
         "  --odometry          the raw odometry\n"
         "  --corrected LOG     the corrected keyframes, other scans by relative odometry to the nearest\n"
         "  --trajectory FILE   'timestamp x y theta' per line\n"
         "  --param key=value   a SLAM parameter by its config/slam.yaml name (e.g. loop/min_score=0.6)\n"
         "  --config FILE       the SLAM parameter file (default: slam.yaml in $LINEMAP_CONFIG_DIR,\n"
         "                      $LINEMAP_ROOT/config, or the config/ found upwards from the executable\n"
         "                      or the working directory, as linemap_batch finds it)\n"
         "  --write FILE        write the (last) SLAM or localized trajectory of every scan as\n"
         "                      'timestamp x y theta'\n"
         "  --out DIR           where each SLAM run's figure goes: DIR/slam.svg, .png (without odometry\n"
         "                      slam_no_odometry): trajectory, scans, closures, relations above 0.3 m\n"
         "                      (default: linemap_relations_out)\n"
         "  --no-figures        no SLAM figure\n"
         "  --localize MAP_FILE the log's scans and odometry localized in a saved line map, from the\n"
         "                      first scan's base pose in the map given by --initial-pose, or by global\n"
         "                      localization without it\n"
         "  --localize-config FILE  localization parameters (default: config/localization.yaml as above)\n"
         "  --localize-param key=value  a localization parameter by its config/localization.yaml name\n"
         "  --two-sessions      the SLAM in two sessions: the log cut at its middle scan, the first half\n"
         "                      mapped and saved, the second half (odometry from zero, as after a\n"
         "                      restart) globally localized in the first's keyframes and continuing its\n"
         "                      session; the joined trajectory against the single run\n"
         "  --search-scans N    with --two-sessions: scans to search before the second half maps apart\n"
         "                      (joined to the first when found later; default 400)\n";
}

Trajectory readTrajectory(const std::string& path)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the trajectory file");
  Trajectory t;
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line))
  {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    double s, x, y, th;
    if (!(f >> s >> x >> y >> th))
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 'timestamp x y theta'");
    t.push_back({s, {x, y, th}});
  }
  return t;
}

void writeTrajectory(const std::string& path, const Trajectory& t)
{
  std::ofstream out(path);
  out << std::setprecision(17);
  for (const auto& [stamp, p] : t) out << stamp << " " << p.x << " " << p.y << " " << p.theta << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write the trajectory");
}

void print(const std::string& name, const RelationsError& e, const std::string& extra)
{
  const double deg = 180.0 / linemap::kPi;
  std::cout << std::left << std::setw(25) << name << std::right << std::fixed << std::setw(6) << e.used << "/"
            << std::left << std::setw(6) << e.relations << std::right << std::setprecision(4) << std::setw(8)
            << e.translation_mean << " ± " << std::setw(6) << e.translation_std << std::setprecision(2)
            << std::setw(8) << e.rotation_mean * deg << " ± " << std::setw(5) << e.rotation_std * deg << "  "
            << extra << std::endl;
}
/// The command line.
struct Arguments
{
  std::vector<std::string> positional, overrides, trajectories, localize_overrides;
  std::string corrected, config, write, localize, localize_config, out_dir = "linemap_relations_out";
  std::optional<Pose2> initial_pose;
  bool slam = false, slam_no_odom = false, odometry = false, figures = true, two_sessions = false;
  std::size_t search_scans = 400;
};

Pose2 parsePose(const std::string& v)
{
  Pose2 p;
  char c1 = 0, c2 = 0;
  std::istringstream f(v);
  if (!(f >> p.x >> c1 >> p.y >> c2 >> p.theta) || c1 != ',' || c2 != ',' || !f.eof())
    throw std::invalid_argument("--initial-pose expects X,Y,THETA, got '" + v + "'");
  return p;
}

/// Parses the command line; false after --help. Throws std::invalid_argument on a bad one.
bool parseArguments(int argc, char** argv, Arguments& a)
{
  for (CommandLine cl(argc, argv); cl.next();)
  {
    const std::string& arg = cl.arg();
    std::string* text = arg == "--corrected"         ? &a.corrected
                        : arg == "--config"          ? &a.config
                        : arg == "--write"           ? &a.write
                        : arg == "--localize"        ? &a.localize
                        : arg == "--localize-config" ? &a.localize_config
                        : arg == "--out"             ? &a.out_dir
                                                     : nullptr;
    std::vector<std::string>* list = arg == "--trajectory"       ? &a.trajectories
                                     : arg == "--param"          ? &a.overrides
                                     : arg == "--localize-param" ? &a.localize_overrides
                                                                 : nullptr;
    if (arg == "--help" || arg == "-h") return false;
    if (text)
      *text = cl.value();
    else if (list)
      list->push_back(cl.value());
    else if (arg == "--slam")
      a.slam = true;
    else if (arg == "--slam-no-odometry")
      a.slam_no_odom = true;
    else if (arg == "--odometry")
      a.odometry = true;
    else if (arg == "--two-sessions")
      a.two_sessions = true;
    else if (arg == "--search-scans")
      a.search_scans = parseCount(arg, cl.value(), 1);
    else if (arg == "--no-figures")
      a.figures = false;
    else if (arg == "--initial-pose")
      a.initial_pose = parsePose(cl.value());
    else if (!arg.empty() && arg[0] == '-')
      throw std::invalid_argument("unknown option " + arg);
    else
      a.positional.push_back(arg);
  }
  if (a.positional.size() != 2) throw std::invalid_argument("expected RAW_LOG and RELATIONS");
  if (!a.slam && !a.slam_no_odom && !a.odometry && a.corrected.empty() && a.trajectories.empty() &&
      a.localize.empty() && !a.two_sessions)
    a.slam = true;
  return true;
}

/// Every scan at its nearest keyframe (in scan order) and the relative odometry from it.
std::vector<Pose2> correctedPoses(const Recording& recording)
{
  std::vector<Pose2> poses(recording.scans.size());
  const auto& kfs = recording.keyframes;
  std::size_t k = 0;
  for (std::size_t i = 0; i < poses.size() && !kfs.empty(); ++i)
  {
    while (k + 1 < kfs.size() && kfs[k + 1].scan_index <= i) ++k;
    std::size_t best = k;
    if (k + 1 < kfs.size() && kfs[k + 1].scan_index - i < (i > kfs[k].scan_index ? i - kfs[k].scan_index : 0))
      best = k + 1;
    const auto& kf = kfs[best];
    poses[i] = kf.pose * (recording.scans[kf.scan_index].odom.inverse() * recording.scans[i].odom);
  }
  return poses;
}

/// What every trajectory is measured against, and the recording they are made from.
struct Evaluation
{
  const Arguments& args;
  const CarmenLog& raw;
  const Recording& recording;
  const std::vector<Relation>& relations;

  /// Relation timestamps are the raw FLASER timestamps; the recording's stamps are made monotonic.
  Trajectory byRawStamp(const std::vector<Pose2>& poses) const
  {
    Trajectory t;
    for (std::size_t i = 0; i < poses.size() && i < raw.scans.size(); ++i)
      t.push_back({raw.scans[i].timestamp, poses[i]});
    return t;
  }
  void report(const std::string& name, const std::vector<Pose2>& poses, const std::string& extra) const
  {
    print(name, relationsError(relations, byRawStamp(poses)), extra);
  }
};

void reportSlam(const Evaluation& ev)
{
  const Arguments& a = ev.args;
  linemap::ParamSet params = loadParameterFiles(configFiles(a.config, "slam.yaml", "linemap_relations"));
  for (const auto& o : a.overrides) applyOverride(params, o);
  const auto slam_params = line_map_merging::LaserSlamParams::fromParams(params);
  for (const bool with_odom : {true, false})
  {
    if ((with_odom && !a.slam) || (!with_odom && !a.slam_no_odom)) continue;
    const SlamRecordingResult r = runSlam(ev.recording, slam_params, with_odom);
    std::ostringstream extra;
    const auto& c = r.counters;
    extra << std::setprecision(1) << std::fixed << r.cpu_seconds << " s CPU (" << r.seconds
          << " s wall, optimisation " << c.total_optimization_ms / 1000.0 << " s, loops "
          << c.total_loop_ms / 1000.0 << " s), " << c.keyframes << " keyframes, "
          << line_map_merging::closureSummary(c) << ", " << c.poor_matches << " poor matches";
    ev.report(with_odom ? "laser SLAM" : "laser SLAM, no odometry", r.scan_poses, extra.str());
    if (!a.write.empty()) writeTrajectory(a.write, ev.byRawStamp(r.scan_poses));
    if (!a.figures) continue;
    fs::create_directories(a.out_dir);
    const auto residuals = relationResiduals(ev.relations, ev.byRawStamp(r.scan_poses));
    const auto files = drawSlamRun(
        ev.recording, r, &residuals,
        linemap::fileStem(a.positional[0]) + (with_odom ? " - laser SLAM" : " - laser SLAM, no odometry"),
        (fs::path(a.out_dir) / (with_odom ? "slam" : "slam_no_odometry")).string());
    std::cout << "  wrote " << files.back() << "\n";
  }
}

void reportTwoSessions(const Evaluation& ev)
{
  const Arguments& a = ev.args;
  linemap::ParamSet params = loadParameterFiles(configFiles(a.config, "slam.yaml", "linemap_relations"));
  for (const auto& o : a.overrides) applyOverride(params, o);
  linemap::ParamSet loc_params =
      loadParameterFiles(configFiles(a.localize_config, "localization.yaml", "linemap_relations"));
  for (const auto& o : a.localize_overrides) applyOverride(loc_params, o);
  const std::size_t cut = ev.recording.scans.size() / 2;
  const TwoSessionRun r = runTwoSessions(
      ev.recording, cut, line_map_merging::LaserSlamParams::fromParams(params),
      line_map_merging::LocalizerParams::fromParams(loc_params), true, std::nullopt, a.search_scans);
  Trajectory joined;
  for (std::size_t i = 0; i < r.scan_poses.size() && i < ev.raw.scans.size(); ++i)
    if (r.scan_poses[i]) joined.push_back({ev.raw.scans[i].timestamp, *r.scan_poses[i]});
  std::ostringstream extra;
  extra << std::setprecision(1) << std::fixed << r.cpu_seconds << " s CPU; cut at scan " << cut << "; ";
  if (r.localized_at)
    extra << "the second half localized at its scan " << *r.localized_at << ", " << r.closures_between
          << " closures between the sessions, " << line_map_merging::closureSummary(r.second_counters);
  else if (r.joined_at)
    extra << "the second half not found within " << a.search_scans
          << " scans: mapped apart and joined at its scan " << *r.joined_at << ", " << r.closures_between
          << " closures between the sessions, " << line_map_merging::closureSummary(r.second_counters);
  else
    extra << "the second half never found: not mapped";
  print("two sessions, joined", relationsError(ev.relations, joined), extra.str());
  if (!a.write.empty()) writeTrajectory(a.write, joined);
}

void reportLocalization(const Evaluation& ev, const std::vector<linemap::Segment2>& segments)
{
  const Arguments& a = ev.args;
  linemap::ParamSet loc_params =
      loadParameterFiles(configFiles(a.localize_config, "localization.yaml", "linemap_relations"));
  for (const auto& o : a.localize_overrides) applyOverride(loc_params, o);
  const auto params = line_map_merging::LocalizerParams::fromParams(loc_params);
  const LocalizationRunResult r = runLocalization(ev.recording, segments, params, a.initial_pose);
  std::vector<double> ms = r.scan_ms;
  std::sort(ms.begin(), ms.end());
  const auto& c = r.counters;
  std::ostringstream extra;
  extra << std::setprecision(1) << std::fixed << r.cpu_seconds << " s CPU, " << segments.size()
        << " map segments, " << std::setprecision(3) << (ms.empty() ? 0.0 : ms[ms.size() / 2])
        << " ms/scan median, " << c.tracked << " tracked, " << c.predicted << " predicted, " << c.lost
        << " lost, " << c.replaced << " replaced by a rival";
  if (!a.initial_pose)
    extra << (r.recovered_at ? ", global localization at scan " + std::to_string(*r.recovered_at)
                             : std::string(", global localization failed"));
  ev.report("localized in the map", r.scan_poses, extra.str());
  if (!a.write.empty()) writeTrajectory(a.write, ev.byRawStamp(r.scan_poses));
}

int run(const Arguments& a)
{
  // The map first: a bad map file is reported before the log is read.
  const auto map_segments = a.localize.empty() ? std::vector<linemap::Segment2>()
                                               : line_map_merging::loadLineMapSegments(a.localize);
  const CarmenLog raw = readCarmenLog(a.positional[0]);
  const auto relations = readRelations(a.positional[1]);
  CarmenLog corrected_log;
  if (!a.corrected.empty()) corrected_log = readCarmenLog(a.corrected);
  const Recording recording = fromCarmen(raw, a.corrected.empty() ? nullptr : &corrected_log);
  const Evaluation ev{a, raw, recording, relations};
  std::cout << "trajectory                 used/total   trans [m] mean ± std   rot [deg] mean ± std\n";
  if (a.odometry)
  {
    std::vector<Pose2> poses;
    for (const auto& s : recording.scans) poses.push_back(s.odom);
    ev.report("raw odometry", poses, "");
  }
  if (!a.corrected.empty())
    ev.report("corrected log", correctedPoses(recording), "(keyframes + relative odometry)");
  for (const auto& path : a.trajectories)
    print(fs::path(path).filename().string(), relationsError(relations, readTrajectory(path)), "");
  if (a.slam || a.slam_no_odom) reportSlam(ev);
  if (a.two_sessions) reportTwoSessions(ev);
  if (!a.localize.empty()) reportLocalization(ev, map_segments);
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  Arguments a;
  return line_map_eval::toolMain(
      "linemap_relations", [&] { return parseArguments(argc, argv, a); }, usage, [&] { return run(a); });
}
