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

#include "line_map_eval/batch.hpp"
#include "line_map_eval/carmen_log.hpp"
#include "line_map_eval/carmen_recording.hpp"
#include "line_map_eval/localization_recording.hpp"
#include "line_map_eval/relations.hpp"
#include "line_map_eval/slam_recording.hpp"

namespace fs = std::filesystem;
using namespace line_map_eval;
using Trajectory = std::vector<std::pair<double, Pose2>>;

namespace
{
void usage(std::ostream& out)
{
  out << "usage: linemap_relations RAW_LOG RELATIONS [--slam] [--slam-no-odometry] [--odometry]\n"
         "                         [--corrected LOG] [--trajectory FILE]... [--param key=value]...\n"
         "                         [--config FILE] [--write FILE]\n"
         "                         [--localize MAP_FILE [--initial-pose X,Y,THETA] [--localize-config FILE]\n"
         "                          [--localize-param key=value]...]\n"
         "Prints the mean and standard deviation of the translational and rotational relation error of\n"
         "each trajectory (default: --slam).\n"
         "  --slam              laser SLAM on the log's scans and odometry\n"
         "  --slam-no-odometry  laser SLAM on the scans alone\n"
         "  --odometry          the raw odometry\n"
         "  --corrected LOG     the corrected keyframes, other scans by relative odometry to the nearest\n"
         "  --trajectory FILE   'timestamp x y theta' per line\n"
         "  --param key=value   a SLAM parameter by its config/slam.yaml name (e.g. loop/min_score=0.6)\n"
         "  --config FILE       the SLAM parameter file (default: $LINEMAP_ROOT/config/slam.yaml or\n"
         "                      ./config/slam.yaml when present)\n"
         "  --write FILE        write the (last) SLAM or localized trajectory of every scan as\n"
         "                      'timestamp x y theta'\n"
         "  --localize MAP_FILE the log's scans and odometry localized in a saved line map, from the\n"
         "                      first scan's base pose in the map given by --initial-pose, or by global\n"
         "                      localization without it\n"
         "  --localize-config FILE  localization parameters (default: config/localization.yaml as above)\n"
         "  --localize-param key=value  a localization parameter by its config/localization.yaml name\n";
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

// The given file, else `name` under $LINEMAP_ROOT or the working directory when present.
std::vector<std::string> configFiles(const std::string& given, const std::string& name)
{
  if (!given.empty()) return {given};
  const char* root = std::getenv("LINEMAP_ROOT");
  for (const fs::path& p : {root ? fs::path(root) / name : fs::path(), fs::path(name)})
    if (!p.empty() && fs::exists(p)) return {p.string()};
  return {};
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
}  // namespace

int main(int argc, char** argv)
{
  std::vector<std::string> positional, overrides, trajectories, localize_overrides;
  std::string corrected, config, write, localize, localize_config;
  std::optional<Pose2> initial_pose;
  bool slam = false, slam_no_odom = false, odometry = false;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string
    {
      if (i + 1 >= argc)
      {
        std::cerr << "linemap_relations: " << arg << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h")
    {
      usage(std::cout);
      return 0;
    }
    else if (arg == "--slam")
      slam = true;
    else if (arg == "--slam-no-odometry")
      slam_no_odom = true;
    else if (arg == "--odometry")
      odometry = true;
    else if (arg == "--corrected")
      corrected = value();
    else if (arg == "--trajectory")
      trajectories.push_back(value());
    else if (arg == "--param")
      overrides.push_back(value());
    else if (arg == "--config")
      config = value();
    else if (arg == "--write")
      write = value();
    else if (arg == "--localize")
      localize = value();
    else if (arg == "--localize-param")
      localize_overrides.push_back(value());
    else if (arg == "--localize-config")
      localize_config = value();
    else if (arg == "--initial-pose")
    {
      const std::string v = value();
      Pose2 p;
      char c1 = 0, c2 = 0;
      std::istringstream f(v);
      if (!(f >> p.x >> c1 >> p.y >> c2 >> p.theta) || c1 != ',' || c2 != ',' || !f.eof())
      {
        std::cerr << "linemap_relations: --initial-pose expects X,Y,THETA, got '" << v << "'\n";
        return 2;
      }
      initial_pose = p;
    }
    else if (!arg.empty() && arg[0] == '-')
    {
      std::cerr << "linemap_relations: unknown option " << arg << "\n";
      usage(std::cerr);
      return 2;
    }
    else
      positional.push_back(arg);
  }
  if (positional.size() != 2)
  {
    usage(std::cerr);
    return 2;
  }
  if (!slam && !slam_no_odom && !odometry && corrected.empty() && trajectories.empty() && localize.empty())
    slam = true;
  try
  {
    // The map first: a bad map file is reported before the log is read.
    const auto map_segments =
        localize.empty() ? std::vector<linemap::Segment2>() : line_map_merging::loadLineMapSegments(localize);
    const CarmenLog raw = readCarmenLog(positional[0]);
    const auto relations = readRelations(positional[1]);
    CarmenLog corrected_log;
    if (!corrected.empty()) corrected_log = readCarmenLog(corrected);
    const Recording recording = fromCarmen(raw, corrected.empty() ? nullptr : &corrected_log);
    // Relation timestamps are the raw FLASER timestamps; the recording's stamps are made monotonic.
    auto byRawStamp = [&](const std::vector<Pose2>& poses)
    {
      Trajectory t;
      for (std::size_t i = 0; i < poses.size() && i < raw.scans.size(); ++i)
        t.push_back({raw.scans[i].timestamp, poses[i]});
      return t;
    };
    std::cout << "trajectory                 used/total   trans [m] mean ± std   rot [deg] mean ± std\n";
    if (odometry)
    {
      std::vector<Pose2> poses;
      for (const auto& s : recording.scans) poses.push_back(s.odom);
      print("raw odometry", relationsError(relations, byRawStamp(poses)), "");
    }
    if (!corrected.empty())
    {
      // Every scan takes its nearest keyframe (in scan order) and the relative odometry from it.
      std::vector<Pose2> poses(recording.scans.size());
      const auto& kfs = recording.keyframes;
      std::size_t k = 0;
      for (std::size_t i = 0; i < poses.size() && !kfs.empty(); ++i)
      {
        while (k + 1 < kfs.size() && kfs[k + 1].scan_index <= i) ++k;
        std::size_t best = k;
        if (k + 1 < kfs.size() &&
            kfs[k + 1].scan_index - i < (i > kfs[k].scan_index ? i - kfs[k].scan_index : 0))
          best = k + 1;
        const auto& kf = kfs[best];
        poses[i] = kf.pose * (recording.scans[kf.scan_index].odom.inverse() * recording.scans[i].odom);
      }
      print("corrected log", relationsError(relations, byRawStamp(poses)), "(keyframes + relative odometry)");
    }
    for (const auto& path : trajectories)
      print(fs::path(path).filename().string(), relationsError(relations, readTrajectory(path)), "");
    if (slam || slam_no_odom)
    {
      linemap::ParamSet params = loadParameterFiles(configFiles(config, "config/slam.yaml"));
      for (const auto& o : overrides) applyOverride(params, o);
      const auto slam_params = line_map_merging::LaserSlamParams::fromParams(params);
      for (int pass = 0; pass < 2; ++pass)
      {
        const bool with_odom = pass == 0;
        if ((with_odom && !slam) || (!with_odom && !slam_no_odom)) continue;
        const SlamRecordingResult r = runSlam(recording, slam_params, with_odom);
        std::ostringstream extra;
        const auto& c = r.counters;
        extra << std::setprecision(1) << std::fixed << r.cpu_seconds << " s CPU (" << r.seconds
              << " s wall, optimisation " << c.total_optimization_ms / 1000.0 << " s, loops "
              << c.total_loop_ms / 1000.0 << " s), " << c.keyframes << " keyframes, " << c.loops_accepted
              << " closures (" << c.loops_rejected_score << " + " << c.loops_rejected_graph << " rejected), "
              << c.poor_matches << " poor matches";
        print(with_odom ? "laser SLAM" : "laser SLAM, no odometry",
              relationsError(relations, byRawStamp(r.scan_poses)), extra.str());
        if (!write.empty()) writeTrajectory(write, byRawStamp(r.scan_poses));
      }
    }
    if (!localize.empty())
    {
      linemap::ParamSet loc_params =
          loadParameterFiles(configFiles(localize_config, "config/localization.yaml"));
      for (const auto& o : localize_overrides) applyOverride(loc_params, o);
      const auto params = line_map_merging::LocalizerParams::fromParams(loc_params);
      const auto& segments = map_segments;
      const LocalizationRunResult r = runLocalization(recording, segments, params, initial_pose);
      std::vector<double> ms = r.scan_ms;
      std::sort(ms.begin(), ms.end());
      const auto& c = r.counters;
      std::ostringstream extra;
      extra << std::setprecision(1) << std::fixed << r.cpu_seconds << " s CPU, " << segments.size()
            << " map segments, " << std::setprecision(3) << (ms.empty() ? 0.0 : ms[ms.size() / 2])
            << " ms/scan median, " << c.tracked << " tracked, " << c.predicted << " predicted, " << c.lost
            << " lost, " << c.replaced << " replaced by a rival";
      if (!initial_pose)
        extra << (r.recovered_at ? ", global localization at scan " + std::to_string(*r.recovered_at)
                                 : std::string(", global localization failed"));
      print("localized in the map", relationsError(relations, byRawStamp(r.scan_poses)), extra.str());
      if (!write.empty()) writeTrajectory(write, byRawStamp(r.scan_poses));
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << "linemap_relations: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
