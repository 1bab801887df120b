// The batch comparison pipeline: datasets -> gating -> one extraction -> every merger -> metrics.
#include "line_map_eval/batch/batch.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "line_extraction/line_extractor.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "line_map_eval/batch/figures.hpp"
#include "line_map_eval/batch/progress.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"
#include "line_map_eval/datasets/carmen_recording.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/online/online_drive.hpp"
#include "line_map_eval/online/timed_merger.hpp"
#include "line_map_merging/mergers/fusion.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/mergers/offline_merger.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
namespace fs = std::filesystem;
using linemap::Pose2;
using linemap::Segment2;
using Clock = std::chrono::steady_clock;

namespace
{
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

std::vector<Segment2> segmentsOf(const std::vector<line_map_merging::MapSegment>& map)
{
  std::vector<Segment2> out;
  out.reserve(map.size());
  for (const auto& m : map) out.push_back(m.segment);
  return out;
}

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
  d.name = linemap::fileStem(raw_log);
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
  d.name = linemap::fileStem(log);
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
  d.name = sim.world.name.empty() ? linemap::fileStem(world.source) : sim.world.name;
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

namespace
{
/// Keyframes without a map: an OnlineMapper over it makes the online path's choice of keyframes,
/// which every merger then gets (the online ones through their own OnlineMapper, the others at the
/// final poses).
class KeyframeRecorder : public line_map_merging::OfflineMerger
{
 public:
  const char* name() const override { return "keyframes"; }

 private:
  std::vector<line_map_merging::MapSegment> compute() const override { return {}; }
};

/// The lines of one scan and how well they fit their own points.
struct ScanLines
{
  std::vector<Segment2> segments;  ///< laser frame: the scan's own, then the submap's
  double fit_rms_sum = 0.0, line_sigma_sum = 0.0;
  std::size_t fitted = 0;
};

/// A keyframe the online path chose, at its final pose.
struct Frame
{
  std::size_t scan = 0;  ///< index into Recording::scans
  Pose2 final_pose;      ///< base_link in map, after the last trajectory
};

/// What every merger's map is measured against: the keyframes' originals and registered scans.
struct SharedEvaluation
{
  std::vector<Segment2> originals;  ///< map frame
  std::vector<Vec2> scan_points;
  LookupTable table;
  StructurePoints structure;
};

/// Everything a run needs, built (and every parameter checked) before any work is done.
struct BatchSetup
{
  const BatchDataset& dataset;
  const BatchOptions& options;
  const linemap::ParamSet& params;
  line_extraction::LineExtractor extractor;
  line_extraction::SubmapExtractor submap;
  line_map_merging::OnlineMapperParams mapper;
  LookupTableParams table;
  MapMetricParams metrics;
  std::optional<GroundTruthParams> truth;
  BackEndSchedule schedule;
  std::vector<ScanLines> lines;
  std::vector<Frame> frames;

  BatchSetup(const BatchDataset& d, const BatchOptions& o, const linemap::ParamSet& p)
      : dataset(d),
        options(o),
        params(p),
        extractor(p),
        submap(line_extraction::SubmapParams::fromParams(p), extractor.params().sensor),
        mapper(line_map_merging::OnlineMapperParams::fromParams(p)),
        table(LookupTableParams::fromParams(p)),
        metrics{QualityParams::fromParams(p), line_map_merging::FusionParams::fromParams(p),
                CoverageParams::fromParams(p)}
  {
    if (d.truth) truth = GroundTruthParams::fromParams(p);
    // The bag's own trajectories and transforms; else a back end's, from the keyframe poses.
    schedule = d.schedule       ? *d.schedule
               : d.loop_closure ? loopClosureSchedule(d.recording, o.adjust_every)
                                : fixedPoseSchedule(d.recording);
    // A continued map's keyframes are nodes of the same graph: every trajectory places them too. The new
    // keyframes are the graph's nodes from the start, as a fresh run's become at its first trajectory
    // (there the gate's keyframes before it are made again from the nodes; here they would stay).
    if (d.saved_map) mapper.keyframe_source = line_map_merging::KeyframeSource::kTrajectory;
    if (d.saved_map)
      for (auto& emission : schedule.trajectories)
        emission.poses.insert(emission.poses.begin(), d.saved_map->keyframe_poses.begin(),
                              d.saved_map->keyframe_poses.end());
  }
  const Recording& rec() const { return dataset.recording; }
  line_map_eval::SegmentSource segmentSource() const
  {
    return [this](std::size_t i, const Pose2&) { return lines[i].segments; };
  }
};

/// Appends the extraction's segments to `out` with the RMS distance of their points to their line.
void fitLines(const line_extraction::LineExtractor& extractor, ScanLines& out)
{
  const auto& extracted = extractor.lastResult();
  const auto& points = extractor.preparedScan().points;
  for (const auto& s : extracted.segments)
  {
    out.segments.emplace_back(s.start, s.end);
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
    out.fit_rms_sum += rms;
    out.line_sigma_sum += rms / std::sqrt(static_cast<double>(n));
    ++out.fitted;
  }
}

/// Every scan's lines, extracted once for every merger; the submap registered by odometry, as online.
void extractEveryScan(BatchSetup& setup, BatchResult& result)
{
  const Recording& rec = setup.rec();
  setup.lines.assign(rec.scans.size(), {});
  ProgressBar bar("extract " + result.extractor, rec.scans.size(), setup.options.progress);
  const auto start = Clock::now();
  for (std::size_t i = 0; i < rec.scans.size(); ++i)
  {
    const RecordedScan& scan = rec.scans[i];
    try
    {
      setup.extractor.extract(scanInput(rec.geometryOf(scan), scan.ranges));
    }
    catch (const line_extraction::ScanError& e)
    {
      throw std::runtime_error(rec.source + ": scan " + std::to_string(i) + ": " + e.what());
    }
    fitLines(setup.extractor, setup.lines[i]);
    const auto& extractor = setup.extractor;
    for (const auto& s :
         setup.submap.update(extractor.preparedScan(), extractor.lastResult(), scan.odom * rec.base_to_laser))
      setup.lines[i].segments.emplace_back(s.start, s.end);
    bar.update(i + 1);
  }
  result.extraction_ms = linemap::millisecondsSince(start);
  bar.finish();
}

/// The keyframes of the online path (the OnlineMapper's gate and trajectory nodes), at their final poses.
std::vector<Frame> chooseKeyframes(const BatchSetup& setup)
{
  line_map_merging::OnlineMapperParams params = setup.mapper;
  params.map_level.enabled = false;  // only the keyframes are wanted here
  line_map_merging::OnlineMapper mapper(std::make_unique<KeyframeRecorder>(), params);
  driveOnline(mapper, setup.rec(), setup.schedule, setup.segmentSource());
  std::unordered_map<double, std::size_t> scan_of;
  for (std::size_t i = 0; i < setup.rec().scans.size(); ++i) scan_of.emplace(setup.rec().scans[i].stamp, i);
  std::vector<Frame> frames;
  for (const auto& k : mapper.merger().keyframes())  // by index: in the order they were merged
    frames.push_back({scan_of.at(k.stamp), k.pose * k.mount.inverse()});
  return frames;
}

/// The originals and registered scans of the keyframes, and the lookup table of those (shared).
SharedEvaluation shareEvaluation(const BatchSetup& setup, BatchResult& result)
{
  const Recording& rec = setup.rec();
  const Pose2& mount = rec.base_to_laser;
  SharedEvaluation shared;
  ScanLines fit;
  Recording registered;
  registered.geometry = rec.geometry;
  registered.base_to_laser = mount;
  registered.source = rec.source;
  for (const Frame& f : setup.frames)
  {
    const ScanLines& lines = setup.lines[f.scan];
    for (const auto& s : lines.segments) shared.originals.push_back(s.transformed(f.final_pose * mount));
    fit.fit_rms_sum += lines.fit_rms_sum;
    fit.line_sigma_sum += lines.line_sigma_sum;
    fit.fitted += lines.fitted;
    registered.keyframes.push_back({registered.scans.size(), f.final_pose});
    registered.scans.push_back(rec.scans[f.scan]);
  }
  if (fit.fitted > 0)
  {
    result.original_fit_rms = fit.fit_rms_sum / static_cast<double>(fit.fitted);
    result.original_line_sigma = fit.line_sigma_sum / static_cast<double>(fit.fitted);
  }
  result.originals = lengthStatistics(shared.originals);
  const auto table_start = Clock::now();
  shared.scan_points = registeredScanPoints(registered);
  if (setup.dataset.saved_map)
    shared.scan_points.insert(shared.scan_points.end(), setup.dataset.saved_map->points.begin(),
                              setup.dataset.saved_map->points.end());
  shared.table = LookupTable::build(shared.scan_points, setup.table);
  result.table_ms = linemap::millisecondsSince(table_start);
  result.scan_points = shared.scan_points.size();
  result.registered_points = shared.scan_points;
  const auto structure_start = Clock::now();
  shared.structure =
      classifyStructure(shared.scan_points, setup.table.sigma, setup.metrics.coverage.structure);
  result.structure_ms = linemap::millisecondsSince(structure_start);
  return shared;
}

/// A merger after its run: an online one inside the OnlineMapper that drove it.
struct MergerHolder
{
  std::unique_ptr<line_map_merging::OnlineMapper> mapper;
  std::unique_ptr<line_map_merging::Merger> offline;
  const line_map_merging::Merger& get() const { return mapper ? mapper->merger() : *offline; }
};

/// An online merger through the one online path: every scan and trajectory into its OnlineMapper, as
/// the nodelets and --replay do. In loop closure runs the map before the last trajectory is kept.
MergerHolder runOnline(const BatchSetup& setup, const SharedEvaluation& shared, MergerRun& run)
{
  auto owned = std::make_unique<TimedMerger>(line_map_merging::makeMerger(run.name, setup.params));
  const TimedMerger& timed = *owned;
  MergerHolder holder;
  holder.mapper = std::make_unique<line_map_merging::OnlineMapper>(std::move(owned), setup.mapper);
  if (setup.dataset.saved_map)
    holder.mapper->loadText(setup.dataset.saved_map->text, setup.dataset.saved_map->origin);
  const std::size_t loaded = holder.mapper->keyframeStamps().size();
  const Recording& rec = setup.rec();
  ProgressBar bar("merge " + run.name, rec.scans.size(), setup.options.progress);
  OnlineDriveHooks hooks;
  hooks.scan = [&bar](std::size_t i, const line_map_merging::StampedScan&) { bar.update(i + 1); };
  double aside_ms = 0.0;  // taking the map before the last trajectory is no merging time
  hooks.before_trajectory = [&](std::size_t k)
  {
    if (!setup.dataset.loop_closure || k + 1 != setup.schedule.trajectories.size()) return;
    const auto start = Clock::now();
    run.map_before_adjust = segmentsOf(timed.map());
    run.quality_before_adjust =
        computeMapQuality(shared.table, run.map_before_adjust, setup.metrics.quality).quality;
    aside_ms += linemap::millisecondsSince(start);
  };
  holder.mapper->merger().timeSteps(setup.options.time_steps);
  const auto start = Clock::now();
  run.trajectories = driveOnline(*holder.mapper, rec, setup.schedule, setup.segmentSource(), hooks);
  run.total_ms = linemap::millisecondsSince(start) - aside_ms;
  bar.finish();
  const auto& counters = holder.mapper->counters();
  run.adjustments = counters.adjustments;
  run.rebuilds = counters.rebuilds;
  run.retired = counters.retired;
  run.map_level_lines = counters.map_level_lines;
  run.map_level_ms = counters.map_level_ms;
  run.adjust_ms = timed.adjustTime();
  run.per_frame_ms = linemap::median(timed.addTimes());
  run.per_frame_p99_ms = linemap::percentile(timed.addTimes(), 0.99);
  for (const double ms : timed.addTimes()) run.keyframe_ms += ms;
  run.step_ms = timed.stepTimes();
  const auto& stamps = holder.mapper->keyframeStamps();
  bool same = stamps.size() == loaded + setup.frames.size();
  for (std::size_t k = 0; same && k < setup.frames.size(); ++k)
    same = stamps[loaded + k] == rec.scans[setup.frames[k].scan].stamp;
  if (!same) throw std::logic_error(run.name + ": the online path chose other keyframes than for the others");
  return holder;
}

/// A merger that computes its map from every keyframe at once: the keyframes at their final poses.
MergerHolder runOffline(const BatchSetup& setup, MergerRun& run)
{
  MergerHolder holder;
  holder.offline = line_map_merging::makeMerger(run.name, setup.params);
  const Recording& rec = setup.rec();
  ProgressBar bar("merge " + run.name, setup.frames.size(), setup.options.progress);
  for (std::size_t k = 0; k < setup.frames.size(); ++k)
  {
    const Frame& f = setup.frames[k];
    line_map_merging::Keyframe kf;
    kf.index = f.scan;
    kf.stamp = rec.scans[f.scan].stamp;
    kf.pose = f.final_pose * rec.base_to_laser;
    kf.mount = rec.base_to_laser;
    kf.segments = setup.lines[f.scan].segments;
    const auto start = Clock::now();
    holder.offline->addKeyframe(kf);
    run.total_ms += linemap::millisecondsSince(start);
    bar.update(k + 1);
  }
  bar.finish();
  if (setup.mapper.map_level.enabled)
  {
    // The map-level lines over every keyframe at its final pose, in one pass.
    const auto start = Clock::now();
    line_map_merging::MapLevelLines map_level(setup.mapper.map_level);
    for (const Frame& f : setup.frames)
      map_level.addKeyframe(f.scan, *keyframeScan(rec, f.scan), setup.lines[f.scan].segments);
    std::vector<Segment2> lines;
    for (const auto& k : map_level.extract(holder.offline->keyframes(), holder.offline->map(), &lines))
      holder.offline->addOriginals(k.keyframe, k.segments);
    run.map_level_lines = lines.size();
    run.map_level_ms = linemap::millisecondsSince(start);
    run.total_ms += run.map_level_ms;
  }
  return holder;
}

/// Every metric of the run's map against the shared table and originals.
void evaluateRun(const BatchSetup& setup, const SharedEvaluation& shared,
                 const line_map_merging::Merger& merger, const std::vector<line_map_merging::MapSegment>& map,
                 MergerRun& run)
{
  const auto start = Clock::now();
  ErrorAssignment provenance;
  if (run.provenance)
  {
    // The extractor's originals only: a map-level line's parts lie on it by construction.
    std::unordered_map<double, std::size_t> scan_of;
    for (const Frame& f : setup.frames) scan_of.emplace(setup.rec().scans[f.scan].stamp, f.scan);
    std::map<std::uint64_t, std::pair<Pose2, const std::vector<Segment2>*>> keyframe_of;
    for (const auto& info : merger.keyframes())
    {
      const auto scan = scan_of.find(info.stamp);
      keyframe_of[info.index] = {info.pose,
                                 scan == scan_of.end() ? nullptr : &setup.lines[scan->second].segments};
    }
    const auto extracted = [](const Segment2& s, const std::vector<Segment2>* own)
    {
      return own == nullptr ||
             std::any_of(own->begin(), own->end(),
                         [&](const Segment2& o) { return o.start == s.start && o.end == s.end; });
    };
    for (std::size_t i = 0; i < map.size(); ++i)
      for (const auto& leaf : merger.leaves(map[i].id))
      {
        const auto it = keyframe_of.find(leaf.keyframe);
        if (it == keyframe_of.end() || !extracted(leaf.segment, it->second.second)) continue;
        provenance.originals.push_back(leaf.segment.transformed(it->second.first));
        provenance.map_index.push_back(static_cast<int>(i));
      }
  }
  MapMetrics metrics =
      computeMapMetrics(shared.table, shared.scan_points, shared.originals, run.final_map, setup.metrics,
                        run.provenance ? &provenance : nullptr, &shared.structure);
  run.quality = metrics.quality;
  run.error = metrics.error;
  run.error_assignment = run.provenance ? "provenance" : "nearest segment meeting the fusion conditions";
  run.point_coverage = std::move(metrics.point_coverage);
  run.structure_coverage = std::move(metrics.structure_coverage);
  run.length_coverage = metrics.length_coverage;
  run.redundancy = std::move(metrics.redundancy);
  run.crossing_pairs = std::move(metrics.crossing_pairs);
  run.evaluation_ms = linemap::millisecondsSince(start);
  if (setup.dataset.truth)
    run.ground_truth = evaluateAgainstGroundTruth(*setup.dataset.truth, run.final_map, *setup.truth);
}

/// The figure of a run's map: uncovered straight structure in its own colour, the rest of the
/// uncovered points as clutter, the redundant pairs.
MapFigure mapFigure(const SharedEvaluation& shared, const MergerRun& run, const std::string& caption)
{
  MapFigure figure;
  figure.segments = run.final_map;
  figure.scan_points = shared.scan_points;
  figure.caption = caption;
  figure.show_coverage = true;
  std::size_t next = 0;
  for (const std::size_t i : run.point_coverage.uncovered)
  {
    const auto& on_structure = run.structure_coverage.uncovered;
    while (next < on_structure.size() && on_structure[next] < i) ++next;
    if (next < on_structure.size() && on_structure[next] == i)
      figure.uncovered_structure_points.push_back(shared.scan_points[i]);
    else
      figure.uncovered_points.push_back(shared.scan_points[i]);
  }
  for (const auto& [i, j] : run.redundancy.pair_indices)
    figure.redundant_pairs.emplace_back(run.final_map[i], run.final_map[j]);
  return figure;
}

/// Figures and the map file of a run under DIR/<merger>/.
void writeRunFiles(const BatchSetup& setup, const SharedEvaluation& shared,
                   const line_map_merging::Merger& merger, MergerRun& run)
{
  const BatchOptions& options = setup.options;
  const fs::path dir = fs::path(options.out_dir) / run.name;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create the directory: " + ec.message());
  const std::string& dataset = setup.dataset.name;
  const std::string caption =
      dataset + " - " + run.name + " (" + std::to_string(run.map_segments) + " segments)";
  if ((options.figure_formats & kFigureAllFormats) != 0)
  {
    const unsigned formats = options.figure_formats;
    const MapFigure figure = mapFigure(shared, run, caption);
    for (auto& f : drawMap(figure, (dir / "map").string(), formats)) run.files.push_back(f);
    for (auto& f : drawLookupTable(shared.table, run.final_map, caption + " over the lookup table",
                                   (dir / "lookup_table").string(), formats))
      run.files.push_back(f);
    if (run.quality_before_adjust)
    {
      MapFigure before;
      before.segments = run.map_before_adjust;
      before.scan_points = shared.scan_points;
      before.caption = dataset + " - " + run.name + " before the final adjustment";
      MapFigure after = figure;
      after.caption = dataset + " - " + run.name + " after the final adjustment";
      for (auto& f : drawComparison(before, after, (dir / "adjustment").string(), formats))
        run.files.push_back(f);
    }
  }
  try
  {
    const std::string path = (dir / "map.yaml").string();
    merger.save(path);
    run.files.push_back(path);
  }
  catch (const line_map_merging::MapFileError& e)
  {
    // Saving is optional for a merger (the report lists the files written); real failures are not.
    if (std::string(e.what()).find("not supported") == std::string::npos) throw;
  }
}

/// One merger: its run (online or offline), the metrics of its map, its files.
MergerRun runMerger(const BatchSetup& setup, const SharedEvaluation& shared, const std::string& name,
                    const BatchResult& result)
{
  MergerRun run;
  run.name = name;
  {
    const auto probe = line_map_merging::makeMerger(name, setup.params);
    run.online = probe->isOnline();
    run.provenance = probe->hasProvenance();
  }
  const MergerHolder holder = run.online ? runOnline(setup, shared, run) : runOffline(setup, run);
  const auto map_start = Clock::now();
  const auto map = holder.get().map();
  run.total_ms += linemap::millisecondsSince(map_start);
  run.scans = setup.frames.size();
  run.final_map = segmentsOf(map);
  run.original_segments = shared.originals.size();
  run.originals = result.originals;
  run.map_segments = map.size();
  run.map = lengthStatistics(run.final_map);
  evaluateRun(setup, shared, holder.get(), map, run);
  if (!setup.options.out_dir.empty()) writeRunFiles(setup, shared, holder.get(), run);
  return run;
}

}  // namespace

BatchResult runBatch(const BatchDataset& dataset, const BatchOptions& options)
{
  BatchResult result;
  result.dataset = dataset.name;
  result.kind = dataset.kind;
  result.loop_closure = dataset.loop_closure;
  result.adjust_every = options.adjust_every;
  result.parameters = options.params;
  if (!options.extractor.empty()) result.parameters.set("algorithm", options.extractor);

  // Everything that can reject a parameter is built before any work is done.
  BatchSetup setup(dataset, options, result.parameters);
  result.extractor = setup.extractor.params().algorithm;
  const std::vector<std::string> names =
      options.mergers.empty() ? line_map_merging::mergerNames() : options.mergers;
  for (const auto& name : names)
  {
    const auto probe = line_map_merging::makeMerger(name, result.parameters);  // unknown names
    if (dataset.saved_map && !probe->isOnline())
      throw std::runtime_error("merger " + name + " cannot continue the saved map of " +
                               dataset.saved_map->origin + ": it merges every keyframe at once");
    if (dataset.saved_map) probe->loadText(dataset.saved_map->text, dataset.saved_map->origin);  // can it?
  }
  const Recording& rec = dataset.recording;
  for (const auto& kf : rec.keyframes)
    if (kf.scan_index >= rec.scans.size())
      throw std::runtime_error(rec.source + ": keyframe names scan " + std::to_string(kf.scan_index) +
                               " of " + std::to_string(rec.scans.size()));
  result.candidate_scans = rec.keyframes.size();
  result.trajectories = setup.schedule.trajectories.size();

  extractEveryScan(setup, result);
  setup.frames = chooseKeyframes(setup);
  result.keyframes = setup.frames.size();
  if (setup.frames.empty()) throw std::runtime_error(dataset.name + ": no keyframes");
  const SharedEvaluation shared = shareEvaluation(setup, result);
  for (const auto& name : names) result.mergers.push_back(runMerger(setup, shared, name, result));
  return result;
}

}  // namespace line_map_eval
