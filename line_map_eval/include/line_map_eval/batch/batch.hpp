// The batch comparison pipeline (ROS-free): one extraction of a dataset's scans, the keyframes the
// online path chooses (online_drive.hpp: the OnlineMapper the nodelets run), every online merger
// driven through its own OnlineMapper and every offline merger on the same keyframes at their final
// poses, and the evaluation of each map
// (Tables I and III of the CAE-RLSM paper, correlation quality, error metric, runtimes and, for
// simulated worlds, the ground-truth metrics). The linemap_batch tool is a thin front end.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/metrics/error_metric.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/metrics/map_metrics.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/metrics/map_statistics.hpp"
#include "line_map_eval/online/online_drive.hpp"
#include "line_map_eval/simulation/ground_truth.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// A dataset ready for the batch run. `recording.keyframes` are the keyframe candidates with
/// their final (corrected, optimised or true) base_link poses in the map frame.
struct BatchDataset
{
  std::string name;  ///< for captions and the report, e.g. "intel"
  std::string kind;  ///< "carmen+corrected", "carmen", "world", "bag" or "bag+trajectory"
  Recording recording;
  /// True when the scans' odometry is the uncorrected trajectory and the keyframe poses are its
  /// correction: online mergers then merge on odometry and receive the corrections as loop
  /// closures. False when the keyframe poses are the only poses (every merger uses them).
  bool loop_closure = false;
  std::optional<GroundTruth> truth;  ///< simulated worlds
  /// What the back end published along the recording (a bag's trajectories and map -> odom); empty:
  /// made from the keyframe poses (loopClosureSchedule every BatchOptions::adjust_every keyframes, or
  /// fixedPoseSchedule without loop closure).
  std::optional<BackEndSchedule> schedule;
  /// A saved map the recording continues (linemap_batch --session): the online mergers that can load a map
  /// start from it, the saved keyframes' poses in the joined graph join every trajectory (so MP-GMA re-fuses
  /// the whole map), and their scan points join the evaluation's.
  struct SavedMap
  {
    std::string text;                                      ///< the map file's text (CAE-RLSM's)
    std::string origin;                                    ///< names it in errors
    std::vector<std::pair<double, Pose2>> keyframe_poses;  ///< (stamp, base pose in the joined map frame)
    std::vector<linemap::Vec2> points;                     ///< the saved keyframes' scan points, map frame
  };
  std::optional<SavedMap> saved_map;
};

/// A raw CARMEN log with its corrected keyframe log (Recording::keyframes pair them).
/// Throws std::runtime_error naming the file and line on bad input.
BatchDataset loadCarmenWithCorrection(const std::string& raw_log, const std::string& corrected_log);

/// A corrected or pre-registered CARMEN log alone: every scan is a keyframe candidate whose pose
/// is its laser pose field (composed with the inverse mounting).
BatchDataset loadCarmenRegistered(const std::string& log);

/// A world file (config/worlds/*.yaml), simulated in-process: drifting odometry, the true
/// trajectory as the loop closure, the ground truth for the extra metrics.
BatchDataset loadSimulatedWorld(const std::string& world_yaml, const SimulationOptions& options = {});
/// Same for a world already loaded (e.g. with a changed odometry model).
BatchDataset simulatedDataset(const World& world, const SimulationOptions& options = {});

/// A recording from elsewhere (a bag). With keyframes (an optimised trajectory) it is a loop
/// closure run; without, every scan is a keyframe candidate at its odometry pose.
BatchDataset datasetFromRecording(Recording recording, const std::string& name, const std::string& kind);

/// True for .yaml / .yml paths (world files).
bool isWorldFile(const std::string& path);

/// Reads YAML parameter files into one flat set: nested maps become "a/b" keys, sequences are
/// written as "[x, y]". Later files override earlier ones. Throws std::runtime_error naming the
/// file on a parse error.
linemap::ParamSet loadParameterFiles(const std::vector<std::string>& files);

/// Applies "key=value"; throws linemap::ParameterError naming the argument when malformed.
void applyOverride(linemap::ParamSet& params, const std::string& assignment);

struct BatchOptions
{
  /// Extraction algorithm; empty: the parameter "algorithm" (config/line_extraction.yaml).
  std::string extractor;
  /// Merger names; empty: every name of line_map_merging::mergerNames().
  std::vector<std::string> mergers;
  /// Every extractor, merger, gate and evaluation parameter ("block/name" keys).
  linemap::ParamSet params;
  /// Loop closure runs without a schedule of their own: the back end publishes the trajectory of the
  /// keyframe candidates every this many of them and at the end; 0 = only at the end (the map before
  /// it is then the odometry map).
  std::size_t adjust_every = 50;
  bool progress = true;
  /// Where figures and map files go (DIR/<merger>/...); empty: nothing is written.
  std::string out_dir;
  unsigned figure_formats = 7u;  ///< FigureFormat bits; 0: no figures (map files and reports only)
  /// Time the mergers' own steps (Merger::stepTimes) into MergerRun::step_ms; adds a little to their
  /// time, so the speed figures come from runs without it.
  bool time_steps = false;
};

struct LengthStatistics
{
  std::size_t count = 0;
  double shortest = 0.0;  ///< [m]
  double longest = 0.0;   ///< [m]
  double mean = 0.0;      ///< [m]
};

struct MergerRun
{
  std::string name;
  bool online = false;      ///< Merger::isOnline(): driven through the OnlineMapper, as the nodelets drive it
  bool provenance = false;  ///< error metric from the merger's own provenance
  std::size_t scans = 0;    ///< keyframes merged
  std::size_t original_segments = 0;
  LengthStatistics originals;
  std::size_t map_segments = 0;
  LengthStatistics map;
  QualityResult quality;
  ErrorMetricResult error;
  PointCoverage point_coverage;          ///< of the registered scan points (lookup table)
  StructureCoverage structure_coverage;  ///< of those on straight structure
  LengthCoverage length_coverage;        ///< of the originals extracted from the keyframes
  RedundancyResult redundancy;           ///< pairs of map segments meeting the fusion conditions
  std::vector<line_map_merging::CrossingPair> crossing_pairs;  ///< map segments crossing in an X
  std::string error_assignment;     ///< "provenance" or "nearest segment meeting the fusion conditions"
  std::size_t trajectories = 0;     ///< trajectories fed to the OnlineMapper (online mergers)
  std::size_t adjustments = 0;      ///< adjust() calls the OnlineMapper made
  std::size_t rebuilds = 0;         ///< maps made again from the nodes of the first trajectory
  std::size_t retired = 0;          ///< originals of a saved map retired as seen through (see_through)
  std::size_t map_level_lines = 0;  ///< lines the map-level passes found (their parts are originals)
  double map_level_ms = 0.0;        ///< [ms] the map-level passes, part of total_ms
  std::optional<double> quality_before_adjust;  ///< [%] map just before the last trajectory
  std::optional<GroundTruthResult> ground_truth;
  double per_frame_ms = std::numeric_limits<double>::quiet_NaN();      ///< median addKeyframe, online only
  double per_frame_p99_ms = std::numeric_limits<double>::quiet_NaN();  ///< its 99th percentile
  double total_ms = 0.0;       ///< every addKeyframe and adjust, and the final map() call
  double adjust_ms = 0.0;      ///< of which adjust()
  double keyframe_ms = 0.0;    ///< of which addKeyframe() (the rest: the online mapper's own work)
  double evaluation_ms = 0.0;  ///< every metric of this map (computeMapMetrics; table excluded)
  std::vector<line_map_merging::StepTime> step_ms;  ///< with BatchOptions::time_steps: the merger's steps
  std::vector<linemap::Segment2> final_map;
  std::vector<linemap::Segment2> map_before_adjust;  ///< the same map (loop closure runs, online mergers)
  std::vector<std::string> files;                    ///< figures and map file written
};

struct BatchResult
{
  std::string dataset;
  std::string kind;
  std::string extractor;
  bool loop_closure = false;
  std::size_t adjust_every = 0;
  std::size_t trajectories = 0;     ///< published along the recording (the schedule's)
  linemap::ParamSet parameters;     ///< everything the run used
  std::size_t candidate_scans = 0;  ///< keyframes of the recording (trajectory nodes, or every scan)
  std::size_t keyframes = 0;        ///< chosen by the online path (gate and trajectory nodes)
  LengthStatistics originals;
  /// Accuracy at the source: the mean over originals of the RMS distance of their member points to their
  /// own fitted line, and of that line's position standard error (RMS / sqrt(points)) [m]. Against the
  /// error metric (originals against their map segment) they tell extraction noise from registration.
  double original_fit_rms = 0.0;
  double original_line_sigma = 0.0;
  std::size_t scan_points = 0;                   ///< registered points in the lookup table
  std::vector<linemap::Vec2> registered_points;  ///< those points
  double extraction_ms = 0.0;                    ///< all keyframes
  double table_ms = 0.0;                         ///< lookup table of the registered scans
  double structure_ms = 0.0;  ///< classifying them as straight structure or not (once, for every map)
  std::vector<MergerRun> mergers;
};

/// Runs the pipeline. Throws linemap::ParameterError naming a bad parameter or an unknown
/// extractor/merger, std::runtime_error for an unusable dataset or unwritable output.
BatchResult runBatch(const BatchDataset& dataset, const BatchOptions& options);

/// Lengths of a set of segments.
LengthStatistics lengthStatistics(const std::vector<linemap::Segment2>& segments);

}  // namespace line_map_eval
