// simulate_world: drives the robot of a world file once around its loop and writes the
// scans as a rosbag (drifting odometry, the true trajectory as the loop closure) plus the
// ground truth next to it (OUT.truth.yaml).
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "line_map_eval/batch/progress.hpp"
#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "linemap/small_helpers.hpp"
#include "tool_main.hpp"

namespace
{
const char* kUsage = R"(usage: rosrun line_map_eval simulate_world WORLD.yaml OUT.bag [options]

Simulates one lap of the world's closed path and writes
  OUT.bag         scan (sensor_msgs/LaserScan), tf odom->base_link (drifting odometry),
                  tf_static base_link->laser, tf map->odom, optimized_trajectory (nav_msgs/Path:
                  the true base poses of every scan (with --pose-noise
                  or the world's `registration`: registered poses that err), emitted once at the end = the loop closure)
  OUT.truth.yaml  ground truth (format linemap_truth/2): the walls (solids with thickness), the
                  true lines (their faces, free side on the left), and per scan the true laser
                  pose and the visible face pieces

options (override the world file):
  --sensor FILE      a sensor profile (config/sensors/*.yaml): its laser block replaces the
                     world's key by key
  --seed N           random seed (noise, spurious readings, odometry drift)
  --scans N          N scans spread evenly over one lap (default: one every path/scan_period)
  --beams N          beams over the same field of view
  --noise SIGMA      Gaussian range noise [m]
  --spurious F       fraction of readings replaced by uniform [0, range_max) (e.g. 0.2)
  --no-drift         odometry equals the true motion
  --start-time T     stamp of the first scan [s] (default 1; a later session: after the first's last)
  --pose-noise P,H[,L]  registration error of the trajectory: std P [m] of x and y, H [deg] of the
                     heading, correlated over L m of path (default 10; the world's `registration`)
  --every N          publish the trajectory every N keyframes as well (default: only at the end)
  --no-progress      no progress bar
  --help             this text

Readings without a return are +inf (above range_max, as REP 117 says).
)";

[[noreturn]] void usageError(const std::string& message)
{
  std::cerr << "simulate_world: " << message << "\n(run with --help for the usage)\n";
  std::exit(2);
}

unsigned long long parseCount(const std::string& option, const char* text, unsigned long long min,
                              unsigned long long max)
{
  try
  {
    return line_map_eval::parseCount(option, text, min, max);
  }
  catch (const std::invalid_argument& e)
  {
    usageError(e.what());
  }
}

double parseNumber(const std::string& option, const char* text, double min, double max)
{
  const std::optional<double> parsed = linemap::toNumber(text);
  const double v = parsed.value_or(NAN);
  if (!std::isfinite(v) || v < min || v > max)
  {
    std::ostringstream range;
    range << "[" << min << ", " << max << "]";
    usageError(option + " expects a number in " + range.str() + ", got '" + text + "'");
  }
  return v;
}

struct Arguments
{
  std::string world_path, bag_path, sensor_path;
  line_map_eval::SimulationOptions options;
  std::size_t every = 0;
  bool progress = true;
};

/// Reads one option (with its value, when it takes one); false for an unknown option.
bool parseOption(const std::string& arg, const std::function<const char*()>& value, Arguments& a)
{
  if (arg == "--sensor")
    a.sensor_path = value();
  else if (arg == "--seed")
    a.options.seed = static_cast<std::uint32_t>(parseCount(arg, value(), 0, 4294967295ull));
  else if (arg == "--scans")
    a.options.scans = parseCount(arg, value(), 1, 10000000);
  else if (arg == "--beams")
    a.options.beams = parseCount(arg, value(), 2, 100000);
  else if (arg == "--noise")
    a.options.sigma = parseNumber(arg, value(), 0.0, 1e3);
  else if (arg == "--spurious")
    a.options.spurious = parseNumber(arg, value(), 0.0, 1.0);
  else if (arg == "--no-drift")
    a.options.drift = false;
  else if (arg == "--start-time")
    a.options.start_time = parseNumber(arg, value(), 1e-3, 4e9);
  else if (arg == "--pose-noise")
    a.options.registration = line_map_eval::parseRegistrationOption(arg, value());
  else if (arg == "--every")
    a.every = parseCount(arg, value(), 1, 10000000);
  else if (arg == "--no-progress")
    a.progress = false;
  else
    return false;
  return true;
}

/// The command line; false after --help. Exits with usageError on a bad one.
bool parseArguments(int argc, char** argv, Arguments& a)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const auto value = [&]() -> const char*
    {
      if (i + 1 >= argc) usageError(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") return false;
    if (parseOption(arg, value, a)) continue;
    if (!arg.empty() && arg[0] == '-')
      usageError("unknown option '" + arg + "'");
    else if (a.world_path.empty())
      a.world_path = arg;
    else if (a.bag_path.empty())
      a.bag_path = arg;
    else
      usageError("unexpected argument '" + arg + "'");
  }
  if (a.world_path.empty() || a.bag_path.empty()) usageError("WORLD.yaml and OUT.bag are required");
  return true;
}

/// Simulates with a progress bar, created at the first scan, when the total is known.
line_map_eval::SimulationResult simulateWithProgress(const line_map_eval::World& world, Arguments& a)
{
  std::unique_ptr<line_map_eval::ProgressBar> bar;
  a.options.on_scan = [&](std::size_t done, std::size_t total)
  {
    if (!bar) bar = std::make_unique<line_map_eval::ProgressBar>("simulating", total, a.progress);
    bar->update(done);
  };
  line_map_eval::SimulationResult sim = line_map_eval::simulate(world, a.options);
  if (bar) bar->finish();
  return sim;
}

/// The world, the sensor and the odometry error at the last scan (leaves std::cout in fixed notation).
void printSimulation(const line_map_eval::SimulationResult& sim, const std::string& world_path,
                     double sim_seconds)
{
  const line_map_eval::World& w = sim.world;
  const line_map_eval::Recording& rec = sim.recording;
  std::cout << std::fixed << std::setprecision(2);
  std::cout << "simulate_world: " << w.name << " (" << world_path << "): " << w.walls.size()
            << " walls, path " << sim.path_length << " m, " << rec.scans.size() << " scans of "
            << w.laser.beams << " beams over " << w.laser.fov * 180.0 / linemap::kPi << " deg\n";
  std::cout << "simulate_world: range noise " << std::setprecision(3) << w.laser.sigma << " m"
            << (w.laser.sigma_slope > 0.0 ? " + " + std::to_string(w.laser.sigma_slope) + " x range" : "")
            << ", range_max " << std::setprecision(1) << w.laser.range_max << " m, " << std::setprecision(1)
            << 100.0 * w.laser.spurious << " % spurious, seed " << w.seed << ", odometry drift "
            << (w.odometry.isZero() ? "off" : "on") << "\n";
  const linemap::Pose2 err = rec.keyframes.back().pose.inverse() * rec.scans.back().odom;
  std::cout << "simulate_world: odometry error at the last scan " << std::setprecision(3)
            << std::hypot(err.x, err.y) << " m, " << std::abs(err.theta) * 180.0 / linemap::kPi
            << " deg; simulated in " << sim_seconds << " s\n";
}

/// OUT.bag and OUT.truth.yaml.
void writeOutputs(const line_map_eval::SimulationResult& sim, const Arguments& a)
{
  using namespace line_map_eval;
  const Recording& rec = sim.recording;
  BagWriterOptions bag_options;
  bag_options.trajectory_every = a.every > 0 ? a.every : rec.keyframes.size();
  bag_options.progress = a.progress;
  BagWriteSummary summary;
  writeBag(rec, a.bag_path, bag_options, &summary);
  const std::string truth_path = truthPathForBag(a.bag_path);
  writeGroundTruth(sim.truth, truth_path);
  std::cout << "simulate_world: wrote " << a.bag_path << " (" << summary.scans << " scans, "
            << summary.trajectory_emissions << " trajectory message"
            << (summary.trajectory_emissions == 1 ? "" : "s") << ", " << summary.duration << " s)\n";
  std::cout << "simulate_world: wrote " << truth_path << "\n";
}
}  // namespace

int main(int argc, char** argv)
{
  using namespace line_map_eval;
  Arguments args;
  if (!parseArguments(argc, argv, args))
  {
    std::cout << kUsage;
    return 0;
  }
  try
  {
    World world = loadWorld(args.world_path);
    if (!args.sensor_path.empty()) world = withSensorProfile(world, args.sensor_path);
    const auto t0 = std::chrono::steady_clock::now();
    const SimulationResult sim = simulateWithProgress(world, args);
    const double sim_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    printSimulation(sim, args.world_path, sim_seconds);
    writeOutputs(sim, args);
  }
  catch (const std::exception& e)
  {
    std::cerr << "simulate_world: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
