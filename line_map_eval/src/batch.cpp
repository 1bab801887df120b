// The batch comparison pipeline: datasets -> gating -> one extraction -> every merger -> metrics.
#include "line_map_eval/batch.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "line_map_eval/carmen_log.hpp"
#include "line_map_eval/carmen_recording.hpp"
#include "line_map_eval/figures.hpp"
#include "line_map_eval/lookup_table.hpp"
#include "line_map_eval/progress.hpp"
#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/online/keyframe_gate.hpp"
#include "line_map_merging/online/trajectory_correction.hpp"

namespace line_map_eval
{
namespace fs = std::filesystem;
using linemap::Pose2;
using linemap::Segment2;
using Clock = std::chrono::steady_clock;

namespace
{
double msSince(Clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string baseName(const std::string& path)
{
  std::string name = fs::path(path).filename().string();
  // intel.clf.bz2 -> intel, office.yaml -> office, intel-corrected.log.gz -> intel-corrected
  const auto dot = name.find('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

void flatten(const YAML::Node& node, const std::string& prefix, linemap::ParamSet& out)
{
  if (node.IsMap())
  {
    for (const auto& item : node)
    {
      const std::string key = item.first.as<std::string>();
      flatten(item.second, prefix.empty() ? key : prefix + "/" + key, out);
    }
  }
  else if (node.IsSequence())
  {
    std::string text = "[";
    for (std::size_t i = 0; i < node.size(); ++i)
    {
      if (!node[i].IsScalar())
        throw std::runtime_error("parameter '" + prefix + "': only sequences of scalars are supported");
      text += (i ? ", " : "") + node[i].Scalar();
    }
    out.set(prefix, text + "]");
  }
  else if (node.IsScalar() && !prefix.empty())
  {
    out.set(prefix, node.Scalar());
  }
}

/// Online mergers merge keyframe by keyframe on the trajectory known so far and receive its
/// corrections as loop closures; the others (cae_offline, o2to, ms, li2023) get the final poses.
bool isOnline(const std::string& name)
{
  return name == "cae" || name == "oto";
}

double median(std::vector<double> values)
{
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  double m = values[mid];
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), values.begin() + mid));
  return m;
}

std::vector<Segment2> segmentsOf(const std::vector<line_map_merging::MapSegment>& map)
{
  std::vector<Segment2> out;
  out.reserve(map.size());
  for (const auto& m : map) out.push_back(m.segment);
  return out;
}

/// One gated keyframe with its extracted segments.
struct Frame
{
  std::size_t scan = 0;            ///< index into Recording::scans
  Pose2 final_pose;                ///< base_link in map (corrected / true / only pose)
  std::vector<Segment2> segments;  ///< laser frame
};

}  // namespace

bool isWorldFile(const std::string& path)
{
  const std::string ext = fs::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml";
}

linemap::ParamSet loadParameterFiles(const std::vector<std::string>& files)
{
  linemap::ParamSet params;
  for (const auto& file : files)
  {
    YAML::Node root;
    try
    {
      root = YAML::LoadFile(file);
    }
    catch (const YAML::Exception& e)
    {
      throw std::runtime_error(file + ": " + e.what());
    }
    if (root.IsNull()) continue;
    if (!root.IsMap()) throw std::runtime_error(file + ": expected a map of parameters at the top level");
    flatten(root, "", params);
  }
  return params;
}

void applyOverride(linemap::ParamSet& params, const std::string& assignment)
{
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw linemap::ParameterError("--param '" + assignment + "': expected key=value");
  params.set(assignment.substr(0, eq), assignment.substr(eq + 1));
}

BatchDataset loadCarmenWithCorrection(const std::string& raw_log, const std::string& corrected_log)
{
  const CarmenLog raw = readCarmenLog(raw_log);
  const CarmenLog corrected = readCarmenLog(corrected_log);
  BatchDataset d;
  d.name = baseName(raw_log);
  d.kind = "carmen+corrected";
  d.recording = fromCarmen(raw, &corrected);
  d.loop_closure = true;
  if (d.recording.keyframes.empty())
    throw std::runtime_error(corrected_log + ": no keyframe matched a raw scan");
  return d;
}

BatchDataset loadCarmenRegistered(const std::string& log)
{
  const CarmenLog carmen = readCarmenLog(log);
  BatchDataset d;
  d.name = baseName(log);
  d.kind = "carmen";
  d.recording = fromCarmen(carmen, nullptr);
  if (d.recording.scans.size() != carmen.scans.size())
    throw std::runtime_error(log + ": the recording does not hold every scan of the log");
  const Pose2 laser_to_base = d.recording.base_to_laser.inverse();
  d.recording.keyframes.clear();
  for (std::size_t i = 0; i < carmen.scans.size(); ++i)
    d.recording.keyframes.push_back({i, carmen.scans[i].laser_pose * laser_to_base});
  if (d.recording.keyframes.empty()) throw std::runtime_error(log + ": no laser scans");
  return d;
}

BatchDataset loadSimulatedWorld(const std::string& world_yaml, const SimulationOptions& options)
{
  return simulatedDataset(loadWorld(world_yaml), options);
}

BatchDataset simulatedDataset(const World& world, const SimulationOptions& options)
{
  SimulationResult sim = simulate(world, options);
  BatchDataset d;
  d.name = sim.world.name.empty() ? baseName(world.source) : sim.world.name;
  d.kind = "world";
  d.recording = std::move(sim.recording);
  d.truth = std::move(sim.truth);
  d.loop_closure = true;
  return d;
}

BatchDataset datasetFromRecording(Recording recording, const std::string& name, const std::string& kind)
{
  BatchDataset d;
  d.name = name;
  d.kind = kind;
  d.loop_closure = !recording.keyframes.empty();
  if (!d.loop_closure)
    for (std::size_t i = 0; i < recording.scans.size(); ++i)
      recording.keyframes.push_back({i, recording.scans[i].odom});
  d.recording = std::move(recording);
  return d;
}

LengthStatistics lengthStatistics(const std::vector<Segment2>& segments)
{
  const MapStatistics s = computeMapStatistics(segments, segments.size());
  LengthStatistics out;
  out.count = s.segment_count;
  out.shortest = s.shortest_length;
  out.longest = s.longest_length;
  out.mean = s.mean_length;
  return out;
}

BatchResult runBatch(const BatchDataset& dataset, const BatchOptions& options)
{
  const Recording& rec = dataset.recording;
  BatchResult result;
  result.dataset = dataset.name;
  result.kind = dataset.kind;
  result.loop_closure = dataset.loop_closure;
  result.adjust_every = options.adjust_every;
  result.parameters = options.params;
  if (!options.extractor.empty()) result.parameters.set("algorithm", options.extractor);
  const linemap::ParamSet& params = result.parameters;

  // Everything that can reject a parameter is built before any work is done.
  line_extraction::LineExtractor extractor(params);
  result.extractor = extractor.params().algorithm;
  line_extraction::SubmapExtractor submap(line_extraction::SubmapParams::fromParams(params),
                                          extractor.params().sensor);
  const auto gate_params = line_map_merging::KeyframeGateParams::fromParams(params);
  const auto table_params = LookupTableParams::fromParams(params);
  const auto quality_params = QualityParams::fromParams(params);
  const auto fusion_params = line_map_merging::FusionParams::fromParams(params);
  const MapMetricParams metric_params{quality_params, fusion_params, CoverageParams::fromParams(params)};
  std::optional<GroundTruthParams> truth_params;
  if (dataset.truth) truth_params = GroundTruthParams::fromParams(params);
  const std::vector<std::string> names =
      options.mergers.empty() ? line_map_merging::mergerNames() : options.mergers;
  for (const auto& name : names) line_map_merging::makeMerger(name, params);  // rejects unknown names early

  // Gating on the final poses, so every merger sees the same keyframes.
  result.candidate_scans = rec.keyframes.size();
  line_map_merging::KeyframeGate gate(gate_params);
  std::vector<Frame> frames;
  for (const auto& kf : rec.keyframes)
  {
    if (kf.scan_index >= rec.scans.size())
      throw std::runtime_error(rec.source + ": keyframe names scan " + std::to_string(kf.scan_index) +
                               " of " + std::to_string(rec.scans.size()));
    if (gate.accept(kf.pose)) frames.push_back({kf.scan_index, kf.pose, {}});
  }
  result.keyframes = frames.size();
  if (frames.empty()) throw std::runtime_error(dataset.name + ": no keyframes");

  // One extraction shared by every merger.
  const Pose2& mount = rec.base_to_laser;
  std::vector<Segment2> originals_world;
  double fit_rms_sum = 0.0, line_sigma_sum = 0.0;
  std::size_t fitted = 0;
  {
    ProgressBar bar("extract " + result.extractor, frames.size(), options.progress);
    const auto start = Clock::now();
    for (std::size_t k = 0; k < frames.size(); ++k)
    {
      const RecordedScan& scan = rec.scans[frames[k].scan];
      try
      {
        const auto& extracted = extractor.extract(scanInput(rec.geometryOf(scan), scan.ranges));
        const auto& points = extractor.preparedScan().points;
        for (const auto& s : extracted.segments)
        {
          frames[k].segments.emplace_back(s.start, s.end);
          double squares = 0.0;
          const Vec2 normal(std::cos(s.angle), std::sin(s.angle));
          for (int i = s.index_begin; i < s.index_end; ++i)
          {
            const double d = normal.dot(points[extracted.point_indices[i]]) - s.radius;
            squares += d * d;
          }
          const int n = s.index_end - s.index_begin;
          if (n <= 0) continue;
          const double rms = std::sqrt(squares / n);
          fit_rms_sum += rms;
          line_sigma_sum += rms / std::sqrt(static_cast<double>(n));
          ++fitted;
        }
      }
      catch (const line_extraction::ScanError& e)
      {
        throw std::runtime_error(rec.source + ": scan " + std::to_string(frames[k].scan) + ": " + e.what());
      }
      // Registered by odometry, as online.
      for (const auto& s : submap.update(extractor.preparedScan(), extractor.lastResult(), scan.odom * mount))
        frames[k].segments.emplace_back(s.start, s.end);
      const Pose2 laser = frames[k].final_pose * mount;
      for (const auto& s : frames[k].segments) originals_world.push_back(s.transformed(laser));
      bar.update(k + 1);
    }
    result.extraction_ms = msSince(start);
    bar.finish();
  }
  if (fitted > 0)
  {
    result.original_fit_rms = fit_rms_sum / static_cast<double>(fitted);
    result.original_line_sigma = line_sigma_sum / static_cast<double>(fitted);
  }
  result.originals = lengthStatistics(originals_world);

  // The lookup table of the registered keyframe scans under the final poses (shared).
  Recording registered;
  registered.geometry = rec.geometry;
  registered.base_to_laser = mount;
  registered.source = rec.source;
  registered.scans.reserve(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    registered.scans.push_back(rec.scans[frames[k].scan]);
    registered.keyframes.push_back({k, frames[k].final_pose});
  }
  auto table_start = Clock::now();
  const std::vector<Vec2> scan_points = registeredScanPoints(registered);
  const LookupTable table = LookupTable::build(scan_points, table_params);
  result.table_ms = msSince(table_start);
  result.scan_points = scan_points.size();
  const auto structure_start = Clock::now();
  const StructurePoints structure =
      classifyStructure(scan_points, table_params.sigma, metric_params.coverage.structure);
  result.structure_ms = msSince(structure_start);
  registered.scans.clear();

  for (const auto& name : names)
  {
    auto merger = line_map_merging::makeMerger(name, params);
    MergerRun run;
    run.name = name;
    run.online = isOnline(name);
    run.provenance = merger->hasProvenance();
    const bool on_odometry = dataset.loop_closure && run.online;

    std::vector<double> frame_ms;
    frame_ms.reserve(frames.size());
    Pose2 map_to_odom;  // the latest correction, identity until the first loop closure
    std::size_t since_adjust = 0;
    auto adjust_to = [&](std::size_t last)
    {
      // Corrected laser poses of keyframes 0..last, as a SLAM back end would publish them.
      std::map<std::uint64_t, Pose2> matched;
      for (std::size_t k = 0; k <= last; ++k) matched[frames[k].scan] = frames[k].final_pose * mount;
      auto infos = merger->keyframes();
      std::sort(infos.begin(), infos.end(), [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
      const auto poses = line_map_merging::correctKeyframes(infos, matched);
      const auto start = Clock::now();
      merger->adjust(poses);
      run.adjust_ms += msSince(start);
      ++run.adjustments;
      const Frame& f = frames[last];
      map_to_odom = f.final_pose * rec.scans[f.scan].odom.inverse();
      since_adjust = 0;
    };

    ProgressBar bar("merge " + name, frames.size(), options.progress);
    double total_ms = 0.0;
    for (std::size_t k = 0; k < frames.size(); ++k)
    {
      const Frame& f = frames[k];
      line_map_merging::Keyframe kf;
      kf.index = f.scan;
      kf.stamp = rec.scans[f.scan].stamp;
      kf.pose = (on_odometry ? map_to_odom * rec.scans[f.scan].odom : f.final_pose) * mount;
      kf.mount = mount;
      kf.segments = f.segments;
      const auto start = Clock::now();
      merger->addKeyframe(kf);
      const double ms = msSince(start);
      frame_ms.push_back(ms);
      total_ms += ms;
      if (on_odometry && ++since_adjust == options.adjust_every && k + 1 < frames.size())
      {
        const double before = run.adjust_ms;
        adjust_to(k);
        total_ms += run.adjust_ms - before;
      }
      bar.update(k + 1);
    }
    if (on_odometry)
    {
      run.map_before_adjust = segmentsOf(merger->map());
      run.quality_before_adjust = computeMapQuality(table, run.map_before_adjust, quality_params).quality;
      const double before = run.adjust_ms;
      adjust_to(frames.size() - 1);
      total_ms += run.adjust_ms - before;
    }
    const auto map_start = Clock::now();
    const auto map = merger->map();
    total_ms += msSince(map_start);
    bar.finish();
    run.total_ms = total_ms;
    if (run.online) run.per_frame_ms = median(frame_ms);
    run.scans = frames.size();
    run.final_map = segmentsOf(map);

    // Evaluation of this map against the shared table and the originals.
    const auto eval_start = Clock::now();
    run.original_segments = originals_world.size();
    run.originals = result.originals;
    run.map_segments = map.size();
    run.map = lengthStatistics(run.final_map);
    ErrorAssignment provenance;
    if (run.provenance)
    {
      std::map<std::uint64_t, Pose2> pose_of;
      for (const auto& info : merger->keyframes()) pose_of[info.index] = info.pose;
      for (std::size_t i = 0; i < map.size(); ++i)
        for (const auto& leaf : merger->leaves(map[i].id))
        {
          const auto it = pose_of.find(leaf.keyframe);
          if (it == pose_of.end()) continue;
          provenance.originals.push_back(leaf.segment.transformed(it->second));
          provenance.map_index.push_back(static_cast<int>(i));
        }
    }
    MapMetrics metrics = computeMapMetrics(table, scan_points, originals_world, run.final_map, metric_params,
                                           run.provenance ? &provenance : nullptr, &structure);
    run.quality = metrics.quality;
    run.error = metrics.error;
    run.error_assignment = run.provenance ? "provenance" : "nearest segment meeting the fusion conditions";
    run.point_coverage = std::move(metrics.point_coverage);
    run.structure_coverage = std::move(metrics.structure_coverage);
    run.length_coverage = metrics.length_coverage;
    run.redundancy = std::move(metrics.redundancy);
    run.crossing_pairs = std::move(metrics.crossing_pairs);
    run.evaluation_ms = msSince(eval_start);
    if (dataset.truth)
      run.ground_truth = evaluateAgainstGroundTruth(*dataset.truth, run.final_map, *truth_params);

    if (!options.out_dir.empty())
    {
      const fs::path dir = fs::path(options.out_dir) / name;
      std::error_code ec;
      fs::create_directories(dir, ec);
      if (ec) throw std::runtime_error(dir.string() + ": cannot create the directory: " + ec.message());
      const std::string caption =
          dataset.name + " - " + name + " (" + std::to_string(map.size()) + " segments)";
      const bool figures = (options.figure_formats & kFigureAllFormats) != 0;
      MapFigure figure;
      figure.segments = run.final_map;
      figure.scan_points = scan_points;
      figure.caption = caption;
      figure.show_coverage = true;
      // Uncovered straight structure in its own colour; the rest of the uncovered points is clutter.
      std::size_t next = 0;
      for (const std::size_t i : run.point_coverage.uncovered)
      {
        const auto& on_structure = run.structure_coverage.uncovered;
        while (next < on_structure.size() && on_structure[next] < i) ++next;
        if (next < on_structure.size() && on_structure[next] == i)
          figure.uncovered_structure_points.push_back(scan_points[i]);
        else
          figure.uncovered_points.push_back(scan_points[i]);
      }
      for (const auto& [i, j] : run.redundancy.pair_indices)
        figure.redundant_pairs.emplace_back(run.final_map[i], run.final_map[j]);
      if (figures)
        for (auto& f : drawMap(figure, (dir / "map").string(), options.figure_formats))
          run.files.push_back(f);
      if (figures)
        for (auto& f : drawLookupTable(table, run.final_map, caption + " over the lookup table",
                                       (dir / "lookup_table").string(), options.figure_formats))
          run.files.push_back(f);
      if (figures && on_odometry)
      {
        MapFigure before;
        before.segments = run.map_before_adjust;
        before.scan_points = scan_points;
        before.caption = dataset.name + " - " + name + " before the final adjustment";
        MapFigure after = figure;
        after.caption = dataset.name + " - " + name + " after the final adjustment";
        for (auto& f : drawComparison(before, after, (dir / "adjustment").string(), options.figure_formats))
          run.files.push_back(f);
      }
      try
      {
        const std::string path = (dir / "map.yaml").string();
        merger->save(path);
        run.files.push_back(path);
      }
      catch (const line_map_merging::MapFileError& e)
      {
        // Saving is optional for a merger (the report lists the files written); real failures are not.
        if (std::string(e.what()).find("not supported") == std::string::npos) throw;
      }
    }
    result.mergers.push_back(std::move(run));
  }
  return result;
}

}  // namespace line_map_eval
