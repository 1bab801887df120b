// Extraction benchmark: speed (scans/s, one thread) of every extractor with and
// without breakpoint clustering, and, on simulated bags with ground truth, the
// detection statistics against the true visible walls (TruePos, FalsePos, error spread).
//
//   rosrun line_extraction extraction_benchmark --world a=office_clean.bag --world b=office_noisy.bag
//       --speed intel=intel.bag [--algorithms srg,split_merge] [--json out.json]
//
// True lines: each `visible` piece of the truth file (OUT.truth.yaml beside OUT.bag)
// transformed into the laser frame with the scan's true laser pose. A piece is
// required (counts for TruePos) when at least --truth-min-beams beams hit it and it is
// at least --truth-min-length long; a shorter piece may still absorb an extracted line,
// which is then no false positive. Lines are matched on (radius, angle); among the pairs
// within the gate, a true piece that the extracted segment overlaps is preferred
// (matchSegments), so that collinear pieces of one wall are told apart.
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/segment_matching.hpp"
#include "linemap/small_helpers.hpp"

namespace
{
using line_extraction::ExtractionResult;
using line_extraction::LineExtractor;
using line_extraction::ScanInput;

struct TrueLine
{
  line_extraction::LinePiece piece;  ///< laser frame
  bool counted = true;
};

struct Dataset
{
  std::string name, path;
  bool with_truth = false;
  // Scans of one bag (geometry of the first; a different one is an error).
  double angle_min = 0.0, angle_increment = 0.0, range_min = 0.0, range_max = 0.0;
  std::vector<std::vector<float>> ranges;
  std::vector<double> stamps;
  std::vector<std::vector<TrueLine>> truth;  ///< per scan, laser frame

  ScanInput input(std::size_t i) const
  {
    ScanInput s;
    s.ranges = ranges[i].data();
    s.count = ranges[i].size();
    s.angle_min = angle_min;
    s.angle_increment = angle_increment;
    s.range_min = range_min;
    s.range_max = range_max;
    return s;
  }
};

struct Options
{
  std::vector<Dataset> datasets;
  std::vector<std::string> algorithms;
  std::string json, topic = "/scan";
  double min_seconds = 0.5;
  std::size_t min_scans = 1000;
  int repetitions = 3;
  line_extraction::TruthRule truth_rule;
  linemap::ParamSet params;
};

void loadBag(Dataset& d, const std::string& topic)
{
  rosbag::Bag bag;
  try
  {
    bag.open(d.path, rosbag::bagmode::Read);
  }
  catch (const rosbag::BagException& e)
  {
    throw std::runtime_error(d.path + ": cannot open bag: " + e.what());
  }
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topic}));
  for (const rosbag::MessageInstance& m : view)
  {
    sensor_msgs::LaserScan::ConstPtr scan = m.instantiate<sensor_msgs::LaserScan>();
    if (!scan) continue;
    if (d.ranges.empty())
    {
      d.angle_min = scan->angle_min;
      d.angle_increment = scan->angle_increment;
      d.range_min = scan->range_min;
      d.range_max = scan->range_max;
    }
    else if (scan->ranges.size() != d.ranges.front().size() || scan->angle_increment != d.angle_increment)
    {
      throw std::runtime_error(d.path + ": scan " + std::to_string(d.ranges.size()) +
                               " has another beam geometry than the first");
    }
    d.ranges.push_back(scan->ranges);
    d.stamps.push_back(scan->header.stamp.toSec());
  }
  if (d.ranges.empty()) throw std::runtime_error(d.path + ": no sensor_msgs/LaserScan on " + topic);
}

std::string truthPath(const std::string& bag)
{
  const std::string ext = ".bag";
  if (bag.size() > ext.size() && bag.compare(bag.size() - ext.size(), ext.size(), ext) == 0)
    return bag.substr(0, bag.size() - ext.size()) + ".truth.yaml";
  return bag + ".truth.yaml";
}

template <typename T>
T field(const YAML::Node& node, const std::string& key, const std::string& file)
{
  const YAML::Node v = node[key];
  if (!v)
    throw std::runtime_error(file + ":" + std::to_string(node.Mark().line + 1) + ": missing '" + key + "'");
  try
  {
    return v.as<T>();
  }
  catch (const YAML::Exception&)
  {
    throw std::runtime_error(file + ":" + std::to_string(v.Mark().line + 1) + ": malformed '" + key + "'");
  }
}

void loadTruth(Dataset& d, const Options& o)
{
  const std::string file = truthPath(d.path);
  YAML::Node root;
  try
  {
    root = YAML::LoadFile(file);
  }
  catch (const YAML::Exception& e)
  {
    throw std::runtime_error(file + ": cannot read ground truth: " + e.what());
  }
  // Only the scans' poses and visible pieces are read: the same in /1 and /2 (whose `walls` are faces).
  const std::string format = field<std::string>(root, "format", file);
  if (format != "linemap_truth/2" && format != "linemap_truth/1")
    throw std::runtime_error(file + ": 'format' is not linemap_truth/2");
  const YAML::Node scans = root["scans"];
  if (!scans || !scans.IsSequence()) throw std::runtime_error(file + ": missing 'scans'");
  if (scans.size() != d.ranges.size())
    throw std::runtime_error(file + ": " + std::to_string(scans.size()) + " scans, the bag has " +
                             std::to_string(d.ranges.size()));
  d.truth.resize(scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i)
  {
    const YAML::Node s = scans[i];
    const double stamp = field<double>(s, "stamp", file);
    if (std::abs(stamp - d.stamps[i]) > 1e-3)
      throw std::runtime_error(file + ":" + std::to_string(s.Mark().line + 1) + ": scan " +
                               std::to_string(i) + " stamp " + std::to_string(stamp) +
                               " differs from the bag's " + std::to_string(d.stamps[i]));
    const std::vector<double> pose = field<std::vector<double>>(s, "pose", file);
    if (pose.size() != 3)
      throw std::runtime_error(file + ": 'pose' of scan " + std::to_string(i) + " needs 3 values");
    const linemap::Pose2 laser_pose(pose[0], pose[1], pose[2]);
    const YAML::Node visible = s["visible"];
    if (!visible) continue;
    for (const YAML::Node& v : visible)
    {
      const std::vector<double> seg = field<std::vector<double>>(v, "segment", file);
      if (seg.size() != 4)
        throw std::runtime_error(file + ":" + std::to_string(v.Mark().line + 1) +
                                 ": 'segment' needs 4 values");
      const linemap::Segment2 piece({seg[0], seg[1]}, {seg[2], seg[3]});
      TrueLine t;
      t.piece.line = line_extraction::lineInLaserFrame(laser_pose, piece);
      t.piece.extent = line_extraction::pieceInLaserFrame(laser_pose, piece);
      t.counted = o.truth_rule.counts(field<std::size_t>(v, "beams", file), piece.length());
      d.truth[i].push_back(t);
    }
  }
}

struct Accuracy
{
  line_extraction::MatchStatistics stats;
  double lines_per_scan = 0.0;
};

Accuracy measureAccuracy(LineExtractor& extractor, const Dataset& d)
{
  Accuracy a;
  std::vector<line_extraction::LinePiece> extracted, truth;
  std::vector<bool> counted;
  std::size_t lines = 0;
  for (std::size_t i = 0; i < d.ranges.size(); ++i)
  {
    const ExtractionResult& r = extractor.extract(d.input(i));
    extracted.clear();
    for (const line_extraction::Segment& s : r.segments)
      extracted.push_back({{s.angle, s.radius}, {s.start, s.end}});
    lines += r.segments.size();
    if (!d.with_truth) continue;
    truth.clear();
    counted.clear();
    for (const TrueLine& t : d.truth[i])
    {
      truth.push_back(t.piece);
      counted.push_back(t.counted);
    }
    a.stats.add(extracted.size(), truth.size(), line_extraction::matchSegments(extracted, truth), counted);
  }
  a.lines_per_scan = static_cast<double>(lines) / d.ranges.size();
  return a;
}

double threadSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Speed
{
  double wall = 0.0;  ///< scans per steady-clock second
  double cpu = 0.0;   ///< scans per second of this thread's CPU time (robust on a shared machine)
};

/// Medians over repetitions of scans/s; each repetition cycles through the scans until
/// both min_seconds (steady clock) and min_scans are reached.
Speed measureSpeed(LineExtractor& extractor, const Dataset& d, const Options& o)
{
  std::vector<ScanInput> inputs;
  for (std::size_t i = 0; i < d.ranges.size(); ++i) inputs.push_back(d.input(i));
  for (const ScanInput& s : inputs) extractor.extract(s);  // warm-up: buffers reach their size
  std::vector<double> wall, cpu;
  std::size_t sink = 0;
  for (int rep = 0; rep < o.repetitions; ++rep)
  {
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = Clock::now();
    const double cpu_start = threadSeconds();
    std::size_t done = 0, next = 0;
    double elapsed = 0.0;
    while (true)
    {
      for (int k = 0; k < 32; ++k)  // read the clock every 32 scans only
      {
        sink += extractor.extract(inputs[next]).segments.size();
        if (++next == inputs.size()) next = 0;
      }
      done += 32;
      elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      if (elapsed >= o.min_seconds && done >= o.min_scans) break;
    }
    wall.push_back(done / elapsed);
    cpu.push_back(done / std::max(1e-9, threadSeconds() - cpu_start));
  }
  if (sink == 1) std::fprintf(stderr, " ");  // keeps the loop's work observable
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  return {wall[wall.size() / 2], cpu[cpu.size() / 2]};
}

struct Row
{
  std::string algorithm, dataset;
  bool clustering = false, with_truth = false;
  std::size_t scans = 0;
  Speed speed;
  Accuracy accuracy;
};

std::string jsonString(const std::string& s)
{
  std::string out = "\"";
  for (char c : s)
  {
    if (c == '"' || c == '\\')
      out += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20)
      out += ' ';
    else
      out += c;
  }
  return out + "\"";
}

void writeJson(const std::vector<Row>& rows, const Options& o)
{
  std::ofstream f(o.json);
  if (!f) throw std::runtime_error(o.json + ": cannot write");
  f.precision(9);
  f << "{\n  \"format\": \"linemap_extraction_benchmark/1\",\n  \"settings\": {\"min_seconds\": "
    << o.min_seconds << ", \"min_scans\": " << o.min_scans << ", \"repetitions\": " << o.repetitions
    << ", \"truth_min_beams\": " << o.truth_rule.min_beams
    << ", \"truth_min_length\": " << o.truth_rule.min_length
    << ", \"matching\": {\"sigma_radius\": 0.03, \"sigma_angle\": 0.03, \"gate\": 2.77}},\n  \"datasets\": [";
  for (std::size_t i = 0; i < o.datasets.size(); ++i)
  {
    const Dataset& d = o.datasets[i];
    f << (i ? ", " : "") << "{\"name\": " << jsonString(d.name) << ", \"bag\": " << jsonString(d.path)
      << ", \"scans\": " << d.ranges.size() << ", \"beams\": " << d.ranges.front().size()
      << ", \"ground_truth\": " << (d.with_truth ? "true" : "false") << "}";
  }
  f << "],\n  \"results\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i)
  {
    const Row& r = rows[i];
    f << "    {\"algorithm\": " << jsonString(r.algorithm)
      << ", \"clustering\": " << (r.clustering ? "true" : "false")
      << ", \"dataset\": " << jsonString(r.dataset) << ", \"scans\": " << r.scans
      << ", \"scans_per_second\": " << r.speed.wall << ", \"cpu_scans_per_second\": " << r.speed.cpu
      << ", \"lines_per_scan\": " << r.accuracy.lines_per_scan;
    if (r.with_truth)
    {
      const line_extraction::MatchStatistics& s = r.accuracy.stats;
      f << ", \"true_pos\": " << s.truePositiveRate() << ", \"false_pos\": " << s.falsePositiveRate()
        << ", \"std_radius\": " << s.radiusErrorStd() << ", \"std_angle\": " << s.angleErrorStd()
        << ", \"true_lines\": " << s.counted() << ", \"extracted\": " << s.extracted()
        << ", \"matched\": " << s.matched();
    }
    f << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  f << "  ]\n}\n";
}

void printTable(const std::vector<Row>& rows, const Dataset& d)
{
  std::printf("\n%s: %s (%zu scans, %zu beams%s)\n", d.name.c_str(), d.path.c_str(), d.ranges.size(),
              d.ranges.front().size(), d.with_truth ? ", ground truth" : "");
  if (d.with_truth)
    std::printf("%-16s %-5s %10s %10s %7s %8s %8s %10s %11s\n", "algorithm", "clust", "scans/s",
                "cpu scans/s", "lines", "TruePos", "FalsePos", "std r [m]", "std a [deg]");
  else
    std::printf("%-16s %-5s %10s %10s %7s\n", "algorithm", "clust", "scans/s", "cpu scans/s", "lines");
  for (const Row& r : rows)
  {
    if (r.dataset != d.name) continue;
    if (!d.with_truth)
    {
      std::printf("%-16s %-5s %10.0f %10.0f %7.2f\n", r.algorithm.c_str(), r.clustering ? "yes" : "no",
                  r.speed.wall, r.speed.cpu, r.accuracy.lines_per_scan);
      continue;
    }
    const line_extraction::MatchStatistics& s = r.accuracy.stats;
    std::printf("%-16s %-5s %10.0f %10.0f %7.2f %7.1f%% %7.1f%% %10.4f %11.3f\n", r.algorithm.c_str(),
                r.clustering ? "yes" : "no", r.speed.wall, r.speed.cpu, r.accuracy.lines_per_scan,
                100.0 * s.truePositiveRate(), 100.0 * s.falsePositiveRate(), s.radiusErrorStd(),
                s.angleErrorStd() * 180.0 / linemap::kPi);
  }
}

const char* kUsage =
    "usage: extraction_benchmark [--world NAME=BAG]... [--speed NAME=BAG]... [--json FILE]\n"
    "         [--algorithms a,b,...] [--min-seconds S] [--min-scans N] [--repetitions N]\n"
    "         [--truth-min-beams N] [--truth-min-length M] [--topic /scan] [--param key=value]...\n"
    "  --world: a simulated bag with OUT.truth.yaml beside it (speed and detection statistics)\n"
    "  --speed: any bag of LaserScans (speed and lines per scan only)\n";

std::pair<std::string, std::string> splitPair(const std::string& arg, const std::string& option)
{
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == arg.size())
    throw std::invalid_argument(option + " expects NAME=VALUE, got '" + arg + "'");
  return {arg.substr(0, eq), arg.substr(eq + 1)};
}

/// `v` as a number >= 0; the error names `option`.
double number(const std::string& option, const std::string& v)
{
  const std::optional<double> x = linemap::toNumber(v);
  if (!x || !(*x >= 0.0)) throw std::invalid_argument(option + ": '" + v + "' is not a number >= 0");
  return *x;
}

Options parseArgs(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help")
    {
      std::cout << kUsage;
      std::exit(0);
    }
    if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
    const std::string v = argv[++i];
    if (a == "--world" || a == "--speed")
    {
      Dataset d;
      std::tie(d.name, d.path) = splitPair(v, a);
      d.with_truth = a == "--world";
      o.datasets.push_back(std::move(d));
    }
    else if (a == "--json")
      o.json = v;
    else if (a == "--topic")
      o.topic = v;
    else if (a == "--algorithms")
    {
      std::stringstream ss(v);
      std::string name;
      while (std::getline(ss, name, ','))
        if (!name.empty()) o.algorithms.push_back(name);
    }
    else if (a == "--min-seconds")
      o.min_seconds = number(a, v);
    else if (a == "--min-scans")
      o.min_scans = static_cast<std::size_t>(number(a, v));
    else if (a == "--repetitions")
      o.repetitions = std::max(1, static_cast<int>(number(a, v)));
    else if (a == "--truth-min-beams")
      o.truth_rule.min_beams = static_cast<std::size_t>(number(a, v));
    else if (a == "--truth-min-length")
      o.truth_rule.min_length = number(a, v);
    else if (a == "--param")
    {
      const auto kv = splitPair(v, a);
      o.params.set(kv.first, kv.second);
    }
    else
      throw std::invalid_argument("unknown option " + a);
  }
  if (o.datasets.empty()) throw std::invalid_argument("give at least one --world or --speed bag");
  if (o.algorithms.empty()) o.algorithms = line_extraction::extractorNames();
  return o;
}

}  // namespace

int main(int argc, char** argv)
{
  Options o;
  try
  {
    o = parseArgs(argc, argv);
  }
  catch (const std::exception& e)
  {
    std::cerr << "extraction_benchmark: " << e.what() << "\n" << kUsage;
    return 2;
  }
  try
  {
    for (Dataset& d : o.datasets)
    {
      loadBag(d, o.topic);
      if (d.with_truth) loadTruth(d, o);
      std::fprintf(stderr, "loaded %s: %zu scans of %zu beams\n", d.path.c_str(), d.ranges.size(),
                   d.ranges.front().size());
    }
    std::vector<Row> rows;
    for (const std::string& name : o.algorithms)
    {
      for (bool clustering : {false, true})
      {
        linemap::ParamSet p = o.params;
        p.set("algorithm", name);
        p.set("clustering", clustering ? "true" : "false");
        LineExtractor extractor(p);
        for (const Dataset& d : o.datasets)
        {
          Row r;
          r.algorithm = name;
          r.dataset = d.name;
          r.clustering = clustering;
          r.with_truth = d.with_truth;
          r.scans = d.ranges.size();
          r.accuracy = measureAccuracy(extractor, d);
          r.speed = measureSpeed(extractor, d, o);
          std::fprintf(stderr, "%-16s clustering %-3s %-8s %10.0f scans/s %10.0f cpu scans/s\n", name.c_str(),
                       clustering ? "yes" : "no", d.name.c_str(), r.speed.wall, r.speed.cpu);
          rows.push_back(r);
        }
      }
    }
    for (const Dataset& d : o.datasets) printTable(rows, d);
    if (!o.json.empty()) writeJson(rows, o);
  }
  catch (const std::exception& e)
  {
    std::cerr << "extraction_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
