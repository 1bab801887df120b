// The SLAM's robustness benchmark (ROS-free), the core of `slam_robustness`: the laser SLAM run on one
// recording many times, under the defaults, under each numeric parameter scaled up and down, and under
// seeded faults of the input, each run scored by the relations metric. A SLAM whose error moves far
// under a small change fails on some building it was not tuned on; the benchmark reports the worst run
// and names the change behind each failure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_merging/slam/laser_slam.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// A fault injected into the input, drawn from `seed`.
enum class InputFault
{
  kOdometryScale,  ///< every odometry step's translation 3 % long or short
  kHeadingDrift,   ///< the odometry's heading drifting 3 mrad per metre, either way
  kDroppedScans,   ///< 10 % of the scans removed at random
  kLateStart,      ///< the log started 2–10 % of its scans later
  kStampJitter,    ///< every stamp moved by up to a fifth of the scan period (order kept)
  /// The front end slips by 0.3 m (in a random direction) and 5 degrees (either way) at a random scan of
  /// the recording's first half (LaserSlam::injectFrontEndSlip): later closures must repair it.
  kFrontEndSlip,
};

/// Every input fault, in the order the benchmark runs them.
const std::vector<InputFault>& allInputFaults();
std::string faultName(InputFault fault);
/// The name on the command line: faultName's with dashes for spaces ("late-start").
std::string faultOption(InputFault fault);
/// The fault a name stands for: faultName's or faultOption's; none when unknown.
std::optional<InputFault> faultFromName(const std::string& name);

/// One run of the benchmark: parameter overrides ("key=value") and/or a fault.
struct RobustnessVariant
{
  std::string label;  ///< "defaults", "loop/min_score x0.7", "dropped scans (seed 2)"
  std::vector<std::string> overrides;
  std::optional<InputFault> fault;
  std::uint32_t seed = 0;
};

/// The SLAM's keys (config/slam.yaml) the benchmark scales: those fromParams reads (front_end/,
/// graph/, loop/, isotropic_ratio, min_weight) whose value is a finite number below 1e8 (larger ones
/// switch a check off). Sorted.
std::vector<std::string> scalableSlamKeys(const linemap::ParamSet& defaults);

/// `value` of `key` scaled by `factor` as the key's kind allows: counts rounded (at least 1), ratios
/// capped at 1, a probability's tail (1 - p) scaled instead of p. Empty when the result equals the
/// value (nothing to try).
std::optional<std::string> scaledValue(const std::string& key, const std::string& value, double factor);

/// Each scalable key scaled by each factor, one at a time.
std::vector<RobustnessVariant> parameterVariants(const linemap::ParamSet& defaults,
                                                 const std::vector<double>& factors = {0.7, 1.4});

/// The slam_robustness options that run `variant` again alone (with the same DATASET, RELATIONS and
/// --param): "--only defaults", "--only parameters --keys KEY" (both of its factors), or "--only faults
/// --fault NAME --runs 1 --seed S".
std::string rerunOptions(const RobustnessVariant& variant);

/// Each fault in `faults` with seeds first_seed .. first_seed + runs - 1.
std::vector<RobustnessVariant> faultVariants(const std::vector<InputFault>& faults, std::size_t runs,
                                             std::uint32_t first_seed);

/// A recording with a fault, and where each of its scans came from.
struct FaultyRecording
{
  Recording recording;
  std::vector<std::size_t> original;  ///< index into the input's scans, per scan
  std::optional<FrontEndSlip> slip;   ///< kFrontEndSlip: where and how much
};

/// `recording` with `fault` drawn from `seed`; keyframes follow their scans (those of removed scans are
/// dropped).
FaultyRecording withFault(const Recording& recording, InputFault fault, std::uint32_t seed);

/// Relations of the kind Kümmerle et al. verified by hand, from a recording's true keyframe poses
/// (a simulated world): scans sampled every `spacing` metres of true path, each related to the next
/// two samples, and to the nearest sample within `loop_distance` metres that lies more than
/// `loop_path` metres of path away (a revisit). Stamps are the scans' stamps.
std::vector<Relation> truthRelations(const Recording& recording, double spacing = 0.5,
                                     double loop_distance = 2.0, double loop_path = 10.0);

struct RobustnessRun
{
  RobustnessVariant variant;
  RelationsError error;
  line_map_merging::SlamCounters counters;
  double cpu_seconds = 0.0;
  /// With true poses (a simulated world): closures in the final graph whose measurement misses the true
  /// relative pose by more than 0.1 m in the directions it determines or 0.02 rad.
  std::size_t false_closures = 0;
  std::string failure;  ///< empty when the run is no failure (RobustnessSummary)
};

/// One SLAM run of the variant on `recording` (`stamps`: the stamp each of its scans is known by in
/// the relations), scored against `relations`. With `figure` (a path without extension), the run's
/// SLAM figure (slam_figure.hpp) is written there, and its trajectory as "stamp x y theta" lines to
/// `figure`.txt.
RobustnessRun runVariant(const Recording& recording, const std::vector<double>& stamps,
                         const std::vector<Relation>& relations, const linemap::ParamSet& defaults,
                         const RobustnessVariant& variant, bool use_odometry, const std::string& figure = "");

struct RobustnessSummary
{
  double defaults = 0.0;  ///< translation error of the defaults' run [m]
  double median = 0.0, p90 = 0.0, worst = 0.0;
  std::string worst_label;
  std::size_t failures = 0;
  /// The runs of one input fault (all its seeds): how many, how many failed, the worst error [m].
  struct FaultTally
  {
    InputFault fault;
    std::size_t runs = 0, failures = 0;
    double worst = 0.0;
  };
  std::vector<FaultTally> by_fault;  ///< in the order the faults first appear among the runs
};

/// Median, 90th percentile and worst translation error over every run (the defaults' included), and
/// marks as failures the runs worse than `failure_ratio` x the defaults' or above `failure_error`.
/// The defaults' run is the one labelled "defaults".
RobustnessSummary summarize(std::vector<RobustnessRun>& runs, double failure_ratio = 2.0,
                            double failure_error = 0.1);

}  // namespace line_map_eval
