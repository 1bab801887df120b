#include "line_map_eval/batch/slam_robustness.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <sstream>

#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/batch/slam_figure.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
namespace
{
bool startsWith(const std::string& s, const std::string& prefix)
{
  return s.rfind(prefix, 0) == 0;
}

bool isCount(const std::string& value)
{
  return !value.empty() && std::all_of(value.begin(), value.end(), [](char c) { return std::isdigit(c); });
}

/// Keys whose value must stay within [0, 1].
bool isRatio(const std::string& key)
{
  return key == "isotropic_ratio" || key == "min_weight" || key == "front_end/widen_ratio" ||
         key == "loop/ambiguity_margin";
}

std::string formatNumber(double v)
{
  std::ostringstream out;
  out << std::setprecision(6) << v;
  return out.str();
}

/// Strictly increasing stamps after a change that may have reordered or tied them.
void keepIncreasing(std::vector<RecordedScan>& scans)
{
  for (std::size_t i = 1; i < scans.size(); ++i)
    scans[i].stamp = std::max(scans[i].stamp, scans[i - 1].stamp + 1e-6);
}

/// The odometry rebuilt step by step with each step's translation scaled and its heading turned by
/// drift per metre of the step.
void distortOdometry(std::vector<RecordedScan>& scans, double scale, double drift_per_metre)
{
  if (scans.empty()) return;
  Pose2 previous_raw = scans[0].odom, rebuilt = scans[0].odom;
  for (std::size_t i = 1; i < scans.size(); ++i)
  {
    const Pose2 step = previous_raw.inverse() * scans[i].odom;
    previous_raw = scans[i].odom;
    const double length = std::hypot(step.x, step.y);
    rebuilt = rebuilt * Pose2(step.x * scale, step.y * scale, step.theta + drift_per_metre * length);
    scans[i].odom = rebuilt;
  }
}

/// `recording` with only the scans `keep` marks, its keyframes following their scans.
FaultyRecording withScansKept(const Recording& recording, const std::vector<bool>& keep)
{
  FaultyRecording out;
  out.recording = recording;
  out.recording.scans.clear();
  out.recording.keyframes.clear();
  std::vector<std::size_t> new_index(keep.size(), static_cast<std::size_t>(-1));
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i])
    {
      new_index[i] = out.recording.scans.size();
      out.recording.scans.push_back(recording.scans[i]);
      out.original.push_back(i);
    }
  for (const auto& kf : recording.keyframes)
    if (kf.scan_index < keep.size() && keep[kf.scan_index])
      out.recording.keyframes.push_back({new_index[kf.scan_index], kf.pose});
  return out;
}
}  // namespace

const std::vector<InputFault>& allInputFaults()
{
  static const std::vector<InputFault> faults{InputFault::kOdometryScale, InputFault::kHeadingDrift,
                                              InputFault::kDroppedScans,  InputFault::kLateStart,
                                              InputFault::kStampJitter,   InputFault::kFrontEndSlip};
  return faults;
}

std::string faultName(InputFault fault)
{
  switch (fault)
  {
    case InputFault::kOdometryScale:
      return "odometry scale";
    case InputFault::kHeadingDrift:
      return "heading drift";
    case InputFault::kDroppedScans:
      return "dropped scans";
    case InputFault::kLateStart:
      return "late start";
    case InputFault::kStampJitter:
      return "stamp jitter";
    case InputFault::kFrontEndSlip:
      return "front-end slip";
  }
  return "?";
}

std::string faultOption(InputFault fault)
{
  std::string dashed = faultName(fault);
  std::replace(dashed.begin(), dashed.end(), ' ', '-');
  return dashed;
}

std::optional<InputFault> faultFromName(const std::string& name)
{
  for (InputFault f : allInputFaults())
    if (name == faultName(f) || name == faultOption(f)) return f;
  return std::nullopt;
}

std::string rerunOptions(const RobustnessVariant& variant)
{
  if (variant.fault)
  {
    return "--only faults --fault " + faultOption(*variant.fault) + " --runs 1 --seed " +
           std::to_string(variant.seed);
  }
  if (variant.overrides.empty()) return "--only defaults";
  const std::string& o = variant.overrides.front();
  return "--only parameters --keys " + o.substr(0, o.find('='));
}

std::vector<std::string> scalableSlamKeys(const linemap::ParamSet& defaults)
{
  std::vector<std::string> keys;
  for (const auto& [key, value] : defaults.values())
  {
    if (!(startsWith(key, "front_end/") || startsWith(key, "graph/") || startsWith(key, "loop/") ||
          key == "isotropic_ratio" || key == "min_weight"))
      continue;
    const auto number = linemap::toNumber(value);
    if (number && std::isfinite(*number) && std::fabs(*number) < 1e8) keys.push_back(key);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

std::optional<std::string> scaledValue(const std::string& key, const std::string& value, double factor)
{
  const auto number = linemap::toNumber(value);
  if (!number) return std::nullopt;
  const double v = *number;
  double scaled = v * factor;
  if (key == "loop/consistency_probability")
    scaled = 1.0 - (1.0 - v) * factor;
  else if (isRatio(key))
    scaled = std::min(scaled, 1.0);
  if (isCount(value))
  {
    const double rounded = std::max(1.0, std::round(scaled));
    if (rounded == v) return std::nullopt;
    return std::to_string(static_cast<long long>(rounded));
  }
  if (scaled == v) return std::nullopt;
  return formatNumber(scaled);
}

std::vector<RobustnessVariant> parameterVariants(const linemap::ParamSet& defaults,
                                                 const std::vector<double>& factors)
{
  std::vector<RobustnessVariant> out;
  for (const auto& key : scalableSlamKeys(defaults))
    for (double f : factors)
      if (const auto v = scaledValue(key, defaults.getString(key, ""), f))
        out.push_back({key + " x" + formatNumber(f) + " (" + *v + ")", {key + "=" + *v}, std::nullopt, 0});
  return out;
}

std::vector<RobustnessVariant> faultVariants(const std::vector<InputFault>& faults, std::size_t runs,
                                             std::uint32_t first_seed)
{
  std::vector<RobustnessVariant> out;
  for (InputFault f : faults)
    for (std::size_t r = 0; r < runs; ++r)
    {
      const std::uint32_t seed = first_seed + static_cast<std::uint32_t>(r);
      out.push_back({faultName(f) + " (seed " + std::to_string(seed) + ")", {}, f, seed});
    }
  return out;
}

FaultyRecording withFault(const Recording& recording, InputFault fault, std::uint32_t seed)
{
  FaultyRecording out;
  out.recording = recording;
  auto& scans = out.recording.scans;
  out.original.resize(scans.size());
  std::iota(out.original.begin(), out.original.end(), std::size_t{0});
  Random rng(seed, 7);
  const double sign = rng.uniform() < 0.5 ? -1.0 : 1.0;
  switch (fault)
  {
    case InputFault::kOdometryScale:
      distortOdometry(scans, 1.0 + 0.03 * sign, 0.0);
      return out;
    case InputFault::kHeadingDrift:
      distortOdometry(scans, 1.0, 0.003 * sign);
      return out;
    case InputFault::kStampJitter:
    {
      std::vector<double> periods;
      for (std::size_t i = 1; i < scans.size(); ++i) periods.push_back(scans[i].stamp - scans[i - 1].stamp);
      const double jitter = 0.2 * linemap::median(periods);
      for (auto& s : scans) s.stamp += jitter * (2.0 * rng.uniform() - 1.0);
      keepIncreasing(scans);
      return out;
    }
    case InputFault::kFrontEndSlip:
    {
      FrontEndSlip slip;
      slip.scan = static_cast<std::size_t>(0.5 * rng.uniform() * static_cast<double>(scans.size()));
      const double direction = 2.0 * linemap::kPi * rng.uniform();
      slip.slip =
          Pose2(0.3 * std::cos(direction), 0.3 * std::sin(direction), sign * 5.0 * linemap::kPi / 180.0);
      out.slip = slip;
      return out;
    }
    case InputFault::kDroppedScans:
    case InputFault::kLateStart:
      break;
  }
  // Removing scans: keep[i] says whether input scan i stays.
  std::vector<bool> keep(recording.scans.size(), true);
  if (fault == InputFault::kDroppedScans)
    for (std::size_t i = 1; i < keep.size(); ++i) keep[i] = rng.uniform() >= 0.1;
  else
  {
    const double share = 0.02 + 0.08 * rng.uniform();
    const auto first = static_cast<std::size_t>(share * static_cast<double>(keep.size()));
    for (std::size_t i = 0; i < first && i < keep.size(); ++i) keep[i] = false;
  }
  return withScansKept(recording, keep);
}

std::vector<Relation> truthRelations(const Recording& recording, double spacing, double loop_distance,
                                     double loop_path)
{
  // Samples along the true path.
  struct Sample
  {
    double stamp, path;
    Pose2 pose;
  };
  std::vector<Sample> samples;
  double path = 0.0, since = spacing;
  const Pose2* previous = nullptr;
  for (const auto& kf : recording.keyframes)
  {
    if (previous)
    {
      const double step = std::hypot(kf.pose.x - previous->x, kf.pose.y - previous->y);
      path += step;
      since += step;
    }
    previous = &kf.pose;
    if (since < spacing) continue;
    since = 0.0;
    samples.push_back({recording.scans.at(kf.scan_index).stamp, path, kf.pose});
  }
  std::vector<Relation> out;
  auto relate = [&](const Sample& a, const Sample& b) {
    out.push_back({a.stamp, b.stamp, a.pose.inverse() * b.pose});
  };
  for (std::size_t a = 0; a < samples.size(); ++a)
  {
    for (std::size_t b = a + 1; b <= a + 2 && b < samples.size(); ++b) relate(samples[a], samples[b]);
    std::optional<std::size_t> revisit;
    double nearest = loop_distance;
    for (std::size_t b = a + 1; b < samples.size(); ++b)
    {
      if (samples[b].path - samples[a].path <= loop_path) continue;
      const double d =
          std::hypot(samples[b].pose.x - samples[a].pose.x, samples[b].pose.y - samples[a].pose.y);
      if (d <= nearest)
      {
        nearest = d;
        revisit = b;
      }
    }
    if (revisit) relate(samples[a], samples[*revisit]);
  }
  return out;
}

RobustnessRun runVariant(const Recording& recording, const std::vector<double>& stamps,
                         const std::vector<Relation>& relations, const linemap::ParamSet& defaults,
                         const RobustnessVariant& variant, bool use_odometry, const std::string& figure)
{
  linemap::ParamSet params = defaults;
  for (const auto& o : variant.overrides) applyOverride(params, o);
  const auto slam_params = line_map_merging::LaserSlamParams::fromParams(params);
  FaultyRecording input;
  if (variant.fault)
    input = withFault(recording, *variant.fault, variant.seed);
  else
  {
    input.recording = recording;
    input.original.resize(recording.scans.size());
    std::iota(input.original.begin(), input.original.end(), std::size_t{0});
  }
  const SlamRecordingResult slam = runSlam(input.recording, slam_params, use_odometry, input.slip);
  std::vector<std::pair<double, Pose2>> trajectory;
  for (std::size_t i = 0; i < slam.scan_poses.size(); ++i)
    trajectory.push_back({stamps.at(input.original[i]), slam.scan_poses[i]});
  RobustnessRun run;
  run.variant = variant;
  run.error = relationsError(relations, trajectory);
  // True poses of the scans (a simulated world's keyframes): each closure measured against them.
  std::vector<const Pose2*> truth(input.recording.scans.size(), nullptr);
  for (const auto& kf : input.recording.keyframes) truth[kf.scan_index] = &kf.pose;
  for (const auto& e : slam.loop_edges)
  {
    const Pose2* a = truth[slam.keyframes[e.from].scan_index];
    const Pose2* b = truth[slam.keyframes[e.to].scan_index];
    if (!a || !b) continue;
    const Pose2 t = a->inverse() * *b;
    const Eigen::Vector2d d(e.measurement.x - t.x, e.measurement.y - t.y);
    if (std::sqrt(d.dot(e.translation_weights * d)) > 0.1 ||
        std::fabs(linemap::normalizeAngle(e.measurement.theta - t.theta)) * slam_params.loop_sigma_theta /
                e.sigma_theta >
            0.02)
      ++run.false_closures;
  }
  if (!figure.empty())
  {
    const auto residuals = relationResiduals(relations, trajectory);
    drawSlamRun(input.recording, slam, &residuals, variant.label, figure);
    std::ofstream out(figure + ".txt");
    out << std::setprecision(17);
    for (const auto& [stamp, p] : trajectory)
      out << stamp << " " << p.x << " " << p.y << " " << p.theta << "\n";
  }
  run.counters = slam.counters;
  run.cpu_seconds = slam.cpu_seconds;
  return run;
}

RobustnessSummary summarize(std::vector<RobustnessRun>& runs, double failure_ratio, double failure_error)
{
  RobustnessSummary s;
  std::vector<double> errors;
  for (const auto& r : runs)
  {
    errors.push_back(r.error.translation_mean);
    if (r.variant.label == "defaults") s.defaults = r.error.translation_mean;
    if (r.error.translation_mean >= s.worst)
    {
      s.worst = r.error.translation_mean;
      s.worst_label = r.variant.label;
    }
  }
  if (errors.empty()) return s;
  std::sort(errors.begin(), errors.end());
  s.median = linemap::median(errors);
  // Nearest rank.
  const auto rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(errors.size())));
  s.p90 = errors[std::max<std::size_t>(rank, 1) - 1];
  for (auto& r : runs)
  {
    const double e = r.error.translation_mean;
    std::ostringstream why;
    why << std::fixed << std::setprecision(4);
    if (r.error.used == 0)
      why << "no relation measured";
    else if (s.defaults > 0.0 && e > failure_ratio * s.defaults)
      why << e << " m > " << failure_ratio << " x the defaults' " << s.defaults << " m";
    else if (e > failure_error)
      why << e << " m > " << failure_error << " m";
    r.failure = why.str();
    if (!r.failure.empty()) ++s.failures;
    if (!r.variant.fault) continue;
    auto tally =
        std::find_if(s.by_fault.begin(), s.by_fault.end(),
                     [&](const RobustnessSummary::FaultTally& t) { return t.fault == *r.variant.fault; });
    if (tally == s.by_fault.end()) tally = s.by_fault.insert(s.by_fault.end(), {*r.variant.fault});
    ++tally->runs;
    tally->failures += r.failure.empty() ? 0 : 1;
    tally->worst = std::max(tally->worst, e);
  }
  return s;
}

}  // namespace line_map_eval
