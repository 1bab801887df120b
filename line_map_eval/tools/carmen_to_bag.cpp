// rosrun line_map_eval carmen_to_bag IN.clf[.bz2|.gz] OUT.bag [options]
// Converts a CARMEN log (and optionally its corrected keyframe log) into a rosbag.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_map_eval/datasets/bag_writer.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"

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
  std::size_t used = 0;
  double v = 0.0;
  try
  {
    v = std::stod(value, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used != value.size() || !(v > 0.0))
    throw std::invalid_argument(option + " needs a positive number, got '" + value + "'");
  return v;
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
}  // namespace

int main(int argc, char** argv)
{
  using namespace line_map_eval;
  std::vector<std::string> positional;
  std::string corrected_path;
  CarmenReadOptions read_options;
  CarmenRecordingOptions rec_options;
  BagWriterOptions bag_options;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      const auto value = [&]() -> std::string
      {
        if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
        return argv[++i];
      };
      if (arg == "--help" || arg == "-h")
      {
        std::cout << kUsage << std::endl;
        return 0;
      }
      else if (arg == "--corrected")
        corrected_path = value();
      else if (arg == "--every")
        bag_options.trajectory_every = parseCount(arg, value(), 1);
      else if (arg == "--max-scans")
        rec_options.max_scans = parseCount(arg, value(), 1);
      else if (arg == "--lenient")
        read_options.lenient = true;
      else if (arg == "--no-progress")
        bag_options.progress = false;
      else if (arg == "--compression")
        bag_options.compression = value();
      else if (arg == "--min-step")
        rec_options.min_stamp_step = parsePositive(arg, value());
      else if (arg == "--max-range")
        rec_options.max_usable_range = parsePositive(arg, value());
      else if (arg == "--frames")
      {
        const std::vector<std::string> f = split(value(), ',');
        if (f.size() != 4 || f[0].empty() || f[1].empty() || f[2].empty() || f[3].empty())
          throw std::invalid_argument("--frames needs four non-empty names map,odom,base_link,laser");
        bag_options.map_frame = f[0];
        bag_options.odom_frame = f[1];
        bag_options.base_frame = f[2];
        bag_options.laser_frame = f[3];
      }
      else if (!arg.empty() && arg[0] == '-')
        throw std::invalid_argument("unknown option " + arg + " (see --help)");
      else
        positional.push_back(arg);
    }
    if (positional.size() != 2)
      throw std::invalid_argument("expected IN and OUT, got " + std::to_string(positional.size()) +
                                  " positional argument(s) (see --help)");
    if (bag_options.compression != "none" && bag_options.compression != "lz4" &&
        bag_options.compression != "bz2")
      throw std::invalid_argument("--compression must be none, lz4 or bz2");
  }
  catch (const std::exception& e)
  {
    std::cerr << "carmen_to_bag: " << e.what() << "\n" << std::endl;
    std::cerr << kUsage << std::endl;
    return 1;
  }

  try
  {
    const auto start = std::chrono::steady_clock::now();
    const CarmenLog raw = readCarmenLog(positional[0], read_options);
    CarmenLog corrected;
    if (!corrected_path.empty()) corrected = readCarmenLog(corrected_path, read_options);
    for (const CarmenLog* log : std::initializer_list<const CarmenLog*>{&raw, &corrected})
    {
      if (log->skipped_bad == 0) continue;
      std::cerr << "carmen_to_bag: skipped " << log->skipped_bad << " malformed line(s) of " << log->path
                << ":\n";
      for (const std::string& p : log->problems) std::cerr << "  " << p << "\n";
    }
    CarmenRecordingReport report;
    const Recording rec =
        fromCarmen(raw, corrected_path.empty() ? nullptr : &corrected, rec_options, &report);
    const double parse_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    BagWriteSummary summary;
    writeBag(rec, positional[1], bag_options, &summary);
    const double total_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::printf("carmen_to_bag: wrote %s\n", positional[1].c_str());
    std::printf("  scans        %zu (%zu beams, angle_min %.4f rad, increment %.6f rad, range_max %.3f m)\n",
                summary.scans, rec.geometry.beam_count, rec.geometry.angle_min, rec.geometry.angle_increment,
                rec.geometry.range_max);
    if (report.geometries > 1)
    {
      std::size_t own = 0, min_beams = rec.geometry.beam_count, max_beams = rec.geometry.beam_count;
      double min_angle = rec.geometry.angle_min, max_angle = rec.geometry.angle_min;
      for (const RecordedScan& s : rec.scans)
      {
        const ScanGeometry& g = rec.geometryOf(s);
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
    std::printf("  duration     %.1f s (median scan period %.4f s)\n", summary.duration, summary.scan_time);
    std::printf("  stamps       %zu moved to keep time increasing (largest move %.3f s)\n",
                report.stamps_adjusted, report.max_stamp_shift);
    std::printf("  odometry     %s\n", report.odometry_source.c_str());
    std::printf("  base->laser  (%.3f, %.3f, %.3f) from %s\n", rec.base_to_laser.x, rec.base_to_laser.y,
                rec.base_to_laser.theta, report.mounting_source.c_str());
    if (report.max_mounting_shift > 0.0 || report.max_mounting_turn > 0.0)
      std::printf("               other lines differ by up to %.2g m, %.2g rad\n", report.max_mounting_shift,
                  report.max_mounting_turn);
    if (!corrected_path.empty())
      std::printf("  keyframes    %zu, trajectory emitted %zu times (every %zu)\n", summary.keyframes,
                  summary.trajectory_emissions, bag_options.trajectory_every);
    else
      std::printf("  keyframes    none (no --corrected log)\n");
    std::printf("  time         %.2f s reading and converting, %.2f s in total\n", parse_seconds,
                total_seconds);
  }
  catch (const std::exception& e)
  {
    std::cerr << "carmen_to_bag: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
