// rosrun line_map_eval carmen_to_bag IN.clf[.bz2|.gz] OUT.bag [options]
// Converts a CARMEN log (and optionally its corrected keyframe log) into a rosbag.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "linemap/small_helpers.hpp"
#include "tool_main.hpp"

namespace
{
const char* const kUsage = R"(usage: carmen_to_bag IN.clf[.bz2|.gz] OUT.bag [options]

Converts a CARMEN log (FLASER/ROBOTLASER1/RAWLASER1..4 scans; plain, gzip or bzip2)
into a rosbag: sensor_msgs/LaserScan on /scan (frame laser), tf odom->base_link per
scan on /tf, base_link->laser on /tf_static and, with --corrected, nav_msgs/Path on
/optimized_trajectory plus tf map->odom at every scan.

options:
  --corrected LOG   corrected keyframe log of the same run (e.g. intel-corrected.log.gz);
                    keyframes are paired with raw scans by their range values
  --every N         emit the trajectory every N keyframes and at the end (default 50)
  --max-scans N     convert only the first N scans (default: all)
  --lenient         skip malformed lines (counted and reported) instead of failing
  --no-progress     no progress bar on stderr
  --frames M,O,B,L  frame names map,odom,base_link,laser (default map,odom,base_link,laser)
  --compression C   bag chunk compression: none, lz4 or bz2 (default none)
  --min-step S      minimum time between consecutive scans [s]: stamps that do not increase
                    by at least S are moved to the previous stamp + S (default 0.001)
  --max-range R     readings beyond R metres are invalid too (range_max at most R)
  --help            this text

Beams: ROBOTLASER1 and RAWLASER lines state their geometry (start angle, angular resolution, beam
count, maximum range), which may change from line to line: every LaserScan carries its own
angle_min, angle_increment and range_max (5 mm below the line's maximum range). FLASER: n readings
span 180 degrees centred on the heading (increment pi/n for even n, pi/(n-1) for odd n). No return:
sensors write their maximum, printed with a jitter of a few centimetres (81.87, 81.89, 81.91 m): the
largest reading and the distinct readings below it in steps of at most 5 cm, within 1 % of it, are
no-return codes; range_max is 5 mm below the lowest of them.
Odometry: FLASER odom fields, ROBOTLASER1 robot pose; RAWLASER (no pose) and logs whose scan poses
never change: ODOM lines interpolated at the scan stamps. base_link->laser: PARAM
robot_frontlaser_offset, else the laser pose relative to the robot pose on the first line.
Exit code 1 on bad input.)";

std::size_t parseCount(const std::string& option, const std::string& value, std::size_t min)
{
  std::size_t used = 0;
  unsigned long long v = 0;
  try
  {
    v = std::stoull(value, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used != value.size() || value.empty() || value[0] == '-' || v < min)
    throw std::invalid_argument(option + " needs an integer >= " + std::to_string(min) + ", got '" + value +
                                "'");
  return static_cast<std::size_t>(v);
}

double parsePositive(const std::string& option, const std::string& value)
{
  const std::optional<double> v = linemap::toNumber(value);
  if (!v || !(*v > 0.0))
    throw std::invalid_argument(option + " needs a positive number, got '" + value + "'");
  return *v;
}

std::vector<std::string> split(const std::string& s, char sep)
{
  std::vector<std::string> parts;
  std::stringstream in(s);
  std::string part;
  while (std::getline(in, part, sep)) parts.push_back(part);
  if (!s.empty() && s.back() == sep) parts.emplace_back();
  return parts;
}

using line_map_eval::CommandLine;

struct Options
{
  std::vector<std::string> positional;
  std::string corrected_path;
  line_map_eval::CarmenReadOptions read;
  line_map_eval::CarmenRecordingOptions recording;
  line_map_eval::BagWriterOptions bag;
};

/// Reads one option (with its value, when it takes one); false for an unknown option.
bool parseOption(const std::string& arg, CommandLine& cl, Options& o)
{
  if (arg == "--corrected")
    o.corrected_path = cl.value();
  else if (arg == "--every")
    o.bag.trajectory_every = parseCount(arg, cl.value(), 1);
  else if (arg == "--max-scans")
    o.recording.max_scans = parseCount(arg, cl.value(), 1);
  else if (arg == "--lenient")
    o.read.lenient = true;
  else if (arg == "--no-progress")
    o.bag.progress = false;
  else if (arg == "--compression")
    o.bag.compression = cl.value();
  else if (arg == "--min-step")
    o.recording.min_stamp_step = parsePositive(arg, cl.value());
  else if (arg == "--max-range")
    o.recording.max_usable_range = parsePositive(arg, cl.value());
  else if (arg == "--frames")
  {
    const std::vector<std::string> f = split(cl.value(), ',');
    if (f.size() != 4 || f[0].empty() || f[1].empty() || f[2].empty() || f[3].empty())
      throw std::invalid_argument("--frames needs four non-empty names map,odom,base_link,laser");
    o.bag.map_frame = f[0];
    o.bag.odom_frame = f[1];
    o.bag.base_frame = f[2];
    o.bag.laser_frame = f[3];
  }
  else
    return false;
  return true;
}

/// The command line; false after --help. Throws std::invalid_argument on a bad one.
bool parseArguments(int argc, char** argv, Options& o)
{
  for (CommandLine cl(argc, argv); cl.next();)
  {
    const std::string& arg = cl.arg();
    if (arg == "--help" || arg == "-h") return false;
    if (parseOption(arg, cl, o)) continue;
    if (!arg.empty() && arg[0] == '-') throw std::invalid_argument("unknown option " + arg + " (see --help)");
    o.positional.push_back(arg);
  }
  if (o.positional.size() != 2)
    throw std::invalid_argument("expected IN and OUT, got " + std::to_string(o.positional.size()) +
                                " positional argument(s) (see --help)");
  if (o.bag.compression != "none" && o.bag.compression != "lz4" && o.bag.compression != "bz2")
    throw std::invalid_argument("--compression must be none, lz4 or bz2");
  return true;
}

void reportSkippedLines(const line_map_eval::CarmenLog& log)
{
  if (log.skipped_bad == 0) return;
  std::cerr << "carmen_to_bag: skipped " << log.skipped_bad << " malformed line(s) of " << log.path << ":\n";
  for (const std::string& p : log.problems) std::cerr << "  " << p << "\n";
}

/// The spread of the scans' own geometries, for logs whose geometry changes.
void printGeometries(const line_map_eval::Recording& rec, const line_map_eval::CarmenRecordingReport& report)
{
  std::size_t own = 0, min_beams = rec.geometry.beam_count, max_beams = rec.geometry.beam_count;
  double min_angle = rec.geometry.angle_min, max_angle = rec.geometry.angle_min;
  for (const line_map_eval::RecordedScan& s : rec.scans)
  {
    const line_map_eval::ScanGeometry& g = rec.geometryOf(s);
    own += s.geometry ? 1 : 0;
    min_beams = std::min(min_beams, g.beam_count);
    max_beams = std::max(max_beams, g.beam_count);
    min_angle = std::min(min_angle, g.angle_min);
    max_angle = std::max(max_angle, g.angle_min);
  }
  std::printf(
      "  geometry     %zu distinct, %zu scans differ from the first: %zu..%zu beams, "
      "angle_min %.4f..%.4f rad\n",
      report.geometries, own, min_beams, max_beams, min_angle, max_angle);
}

void printSummary(const Options& o, const line_map_eval::Recording& rec,
                  const line_map_eval::CarmenRecordingReport& report,
                  const line_map_eval::BagWriteSummary& summary)
{
  std::printf("carmen_to_bag: wrote %s\n", o.positional[1].c_str());
  std::printf("  scans        %zu (%zu beams, angle_min %.4f rad, increment %.6f rad, range_max %.3f m)\n",
              summary.scans, rec.geometry.beam_count, rec.geometry.angle_min, rec.geometry.angle_increment,
              rec.geometry.range_max);
  if (report.geometries > 1) printGeometries(rec, report);
  std::printf("  duration     %.1f s (median scan period %.4f s)\n", summary.duration, summary.scan_time);
  std::printf("  stamps       %zu moved to keep time increasing (largest move %.3f s)\n",
              report.stamps_adjusted, report.max_stamp_shift);
  std::printf("  odometry     %s\n", report.odometry_source.c_str());
  std::printf("  base->laser  (%.3f, %.3f, %.3f) from %s\n", rec.base_to_laser.x, rec.base_to_laser.y,
              rec.base_to_laser.theta, report.mounting_source.c_str());
  if (report.max_mounting_shift > 0.0 || report.max_mounting_turn > 0.0)
    std::printf("               other lines differ by up to %.2g m, %.2g rad\n", report.max_mounting_shift,
                report.max_mounting_turn);
  if (!o.corrected_path.empty())
    std::printf("  keyframes    %zu, trajectory emitted %zu times (every %zu)\n", summary.keyframes,
                summary.trajectory_emissions, o.bag.trajectory_every);
  else
    std::printf("  keyframes    none (no --corrected log)\n");
}

void convert(const Options& o)
{
  using namespace line_map_eval;
  const auto start = std::chrono::steady_clock::now();
  const CarmenLog raw = readCarmenLog(o.positional[0], o.read);
  CarmenLog corrected;
  if (!o.corrected_path.empty()) corrected = readCarmenLog(o.corrected_path, o.read);
  reportSkippedLines(raw);
  reportSkippedLines(corrected);
  CarmenRecordingReport report;
  const Recording rec =
      fromCarmen(raw, o.corrected_path.empty() ? nullptr : &corrected, o.recording, &report);
  const double parse_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  BagWriteSummary summary;
  writeBag(rec, o.positional[1], o.bag, &summary);
  const double total_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  printSummary(o, rec, report, summary);
  std::printf("  time         %.2f s reading and converting, %.2f s in total\n", parse_seconds,
              total_seconds);
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    if (!parseArguments(argc, argv, options))
    {
      std::cout << kUsage << std::endl;
      return 0;
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << "carmen_to_bag: " << e.what() << "\n" << std::endl;
    std::cerr << kUsage << std::endl;
    return 1;
  }
  try
  {
    convert(options);
  }
  catch (const std::exception& e)
  {
    std::cerr << "carmen_to_bag: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
