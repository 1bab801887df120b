// The SLAM's and the localizer's built-in parameter defaults are the shipped config/slam.yaml's and
// config/localization.yaml's: a tool or a program that runs
// the library without the file (not found, or not given) maps as the documented figures were measured.
// Once, config/slam.yaml's surface_lambda (0.1745) and the built-in 10 degrees differed in the fifth digit,
// and linemap_relations started outside the repository reported another Intel error than the README.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "line_extraction/extractor.hpp"
#include "line_extraction/line_extractor.hpp"
#include "line_extraction/sensor_model.hpp"
#include "line_extraction/submap_extraction.hpp"
#include "line_map_eval/batch/batch.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"
#include "line_map_eval/metrics/map_metrics.hpp"
#include "line_map_eval/metrics/map_quality.hpp"
#include "line_map_eval/metrics/structure_coverage.hpp"
#include "line_map_eval/online/map_evaluator.hpp"
#include "line_map_eval/online/online_evaluator.hpp"
#include "line_map_merging/localization/line_map_localizer.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "line_map_merging/online/concurrent_mapper.hpp"
#include "line_map_merging/online/keyframe_gate.hpp"
#include "line_map_merging/online/map_level_lines.hpp"
#include "line_map_merging/online/online_mapper.hpp"
#include "line_map_merging/slam/laser_slam_params.hpp"

using line_map_merging::LaserSlamParams;

namespace
{
void expectSameWindow(const line_map_merging::SearchWindow& built_in,
                      const line_map_merging::SearchWindow& shipped, const char* which)
{
  SCOPED_TRACE(which);
  EXPECT_EQ(built_in.linear, shipped.linear);
  EXPECT_EQ(built_in.angular, shipped.angular);
  EXPECT_EQ(built_in.linear_step, shipped.linear_step);
  EXPECT_EQ(built_in.angular_step, shipped.angular_step);
  EXPECT_EQ(built_in.translation_penalty, shipped.translation_penalty);
  EXPECT_EQ(built_in.rotation_penalty, shipped.rotation_penalty);
}
}  // namespace

TEST(ShippedConfig, SlamDefaultsAreTheConfigFiles)
{
  const LaserSlamParams built_in;
  const LaserSlamParams shipped = LaserSlamParams::fromParams(
      line_map_eval::loadParameterFiles({LINEMAP_SOURCE_DIR "/config/slam.yaml"}));
#define EXPECT_SAME(field) EXPECT_EQ(built_in.field, shipped.field) << #field
  EXPECT_SAME(max_range);
  EXPECT_SAME(min_points);
  EXPECT_SAME(resolution);
  EXPECT_SAME(sigma);
  expectSameWindow(built_in.window, shipped.window, "front_end/window");
  expectSameWindow(built_in.window_no_odometry, shipped.window_no_odometry, "front_end/window_no_odometry");
  EXPECT_SAME(refinement.translation_weight);
  EXPECT_SAME(refinement.rotation_weight);
  EXPECT_SAME(refinement.max_iterations);
  EXPECT_SAME(min_score);
  EXPECT_SAME(widen_ratio);
  EXPECT_SAME(filter_distance);
  EXPECT_SAME(filter_angle);
  EXPECT_SAME(keyframe_distance);
  EXPECT_SAME(keyframe_angle);
  EXPECT_SAME(local_map_keyframes);
  EXPECT_SAME(surfaces.lambda);
  EXPECT_SAME(surfaces.range_sigma);
  EXPECT_SAME(odometry_jump.step);
  EXPECT_SAME(odometry_jump.turn);
  EXPECT_SAME(odometry_jump.speed);
  EXPECT_SAME(odometry_jump.turn_rate);
  EXPECT_SAME(time_jump_tolerance);
  EXPECT_SAME(isotropic_ratio);
  EXPECT_SAME(min_weight);
  EXPECT_SAME(edge_sigma_xy);
  EXPECT_SAME(edge_sigma_theta);
  EXPECT_SAME(odometry_sigma_xy);
  EXPECT_SAME(odometry_sigma_theta);
  EXPECT_SAME(edge_odometry_disagreement);
  EXPECT_SAME(loop_sigma_xy);
  EXPECT_SAME(loop_sigma_theta);
  EXPECT_SAME(loop_loss_scale);
  EXPECT_SAME(loop_min_path);
  EXPECT_SAME(loop_radius);
  EXPECT_SAME(loop_radius_growth);
  EXPECT_SAME(loop_max_radius);
  EXPECT_SAME(loop_angle);
  EXPECT_SAME(loop_angle_growth);
  EXPECT_SAME(loop_max_angle);
  EXPECT_SAME(loop_resolution);
  EXPECT_SAME(loop_angular_step);
  EXPECT_SAME(loop_submap_path);
  EXPECT_SAME(loop_candidates);
  EXPECT_SAME(loop_every);
  EXPECT_SAME(loop_min_score);
  EXPECT_SAME(loop_min_score_ratio);
  EXPECT_SAME(loop_ambiguity_distance);
  EXPECT_SAME(loop_ambiguity_margin);
  EXPECT_SAME(loop_ridge_closures);
  EXPECT_SAME(loop_in_view_only);
  EXPECT_SAME(suspect_edge_follows_odometry);
  EXPECT_SAME(loop_min_in_view);
  EXPECT_SAME(loop_consistency_probability);
  EXPECT_SAME(loop_scale_by_disagreement);
  EXPECT_SAME(loop_max_error_xy);
  EXPECT_SAME(loop_max_error_theta);
  EXPECT_SAME(loop_corroborate_xy);
  EXPECT_SAME(loop_corroborate_theta);
  EXPECT_SAME(loop_agreement_xy);
  EXPECT_SAME(loop_agreement_theta);
  EXPECT_SAME(loop_pending_keyframes);
  EXPECT_SAME(loop_consensus);
  EXPECT_SAME(loop_consensus_waiting);
  EXPECT_SAME(loop_consistent_xy);
  EXPECT_SAME(loop_consistent_theta);
#undef EXPECT_SAME
}

TEST(ShippedConfig, LocalizerDefaultsAreTheConfigFile)
{
  const line_map_merging::LocalizerParams built_in;
  const auto shipped = line_map_merging::LocalizerParams::fromParams(
      line_map_eval::loadParameterFiles({LINEMAP_SOURCE_DIR "/config/localization.yaml"}));
#define EXPECT_SAME(field) EXPECT_EQ(built_in.field, shipped.field) << #field
  EXPECT_SAME(max_range);
  EXPECT_SAME(min_points);
  EXPECT_SAME(match.max_distance);
  EXPECT_SAME(match.refine_distance);
  EXPECT_SAME(match.loss_scale);
  EXPECT_SAME(match.point_sigma);
  EXPECT_SAME(match.inlier_distance);
  EXPECT_SAME(match.max_iterations);
  EXPECT_SAME(match.check_free_side);
  EXPECT_SAME(index_cell);
  EXPECT_SAME(odom_sigma_xy);
  EXPECT_SAME(odom_sigma_xy_per_m);
  EXPECT_SAME(odom_sigma_theta);
  EXPECT_SAME(odom_sigma_theta_per_rad);
  EXPECT_SAME(odom_sigma_theta_per_m);
  EXPECT_SAME(no_odom_sigma_xy);
  EXPECT_SAME(no_odom_sigma_theta);
  EXPECT_SAME(odometry_jump.step);
  EXPECT_SAME(odometry_jump.turn);
  EXPECT_SAME(odometry_jump.speed);
  EXPECT_SAME(odometry_jump.turn_rate);
  EXPECT_SAME(time_jump_tolerance);
  EXPECT_SAME(retry_inlier_share);
  expectSameWindow(built_in.retry_window, shipped.retry_window, "retry_window");
  expectSameWindow(built_in.jump_window, shipped.jump_window, "jump_window");
  EXPECT_SAME(lost_inlier_share);
  EXPECT_SAME(lost_scans);
  EXPECT_SAME(doubt_share);
  EXPECT_SAME(doubt_research_every);
  EXPECT_SAME(doubt_hypotheses);
  EXPECT_SAME(global.coarse_resolution);
  EXPECT_SAME(global.coarse_sigma);
  EXPECT_SAME(global.coarse_angular_step);
  EXPECT_SAME(global.fine_resolution);
  EXPECT_SAME(global.fine_sigma);
  EXPECT_SAME(global.fine_angular_step);
  EXPECT_SAME(global.max_points);
  EXPECT_SAME(global.candidates);
  EXPECT_SAME(global.separation);
  EXPECT_SAME(global.separation_angle);
  EXPECT_SAME(global.sample_spacing);
  EXPECT_SAME(hypothesis_min_share);
  EXPECT_SAME(hypothesis_smoothing);
  EXPECT_SAME(hypotheses);
  EXPECT_SAME(research_every);
  EXPECT_SAME(research_every_apart);
  EXPECT_SAME(accept_share);
  EXPECT_SAME(accept_margin);
  EXPECT_SAME(accept_travel);
  EXPECT_SAME(accept_turn);
  EXPECT_SAME(accept_scans);
#undef EXPECT_SAME
}

namespace
{
/// Whether a file's text and a fallback the code asked with are one setting: numbers within half a unit of
/// the file's last written digit (the files round an angle of whole degrees to the digits they write),
/// other values as written (booleans, names).
bool sameValue(const std::string& file, const std::string& fallback)
{
  char* end_file = nullptr;
  char* end_fallback = nullptr;
  const double a = std::strtod(file.c_str(), &end_file), b = std::strtod(fallback.c_str(), &end_fallback);
  if (file.empty() || *end_file != '\0' || fallback.empty() || *end_fallback != '\0') return file == fallback;
  const std::size_t exponent_at = file.find_first_of("eE");
  const std::string mantissa = file.substr(0, exponent_at);
  const std::size_t point = mantissa.find('.');
  const int decimals = point == std::string::npos ? 0 : static_cast<int>(mantissa.size() - point - 1);
  const int exponent = exponent_at == std::string::npos ? 0 : std::atoi(file.c_str() + exponent_at + 1);
  return std::fabs(a - b) <= 0.5 * std::pow(10.0, exponent - decimals);
}

/// The keys of `params` (a config file) whose value differs from the fallback the code reads it with.
std::map<std::string, std::string> differing(const linemap::ParamSet& params,
                                             const std::map<std::string, std::string>& fallbacks)
{
  std::map<std::string, std::string> out;
  for (const auto& [key, fallback] : fallbacks)
  {
    if (fallback.find('|') != std::string::npos)
      out[key] = "read with different built-in defaults: " + fallback;
    else if (params.has(key) && !sameValue(params.values().at(key), fallback))
      out[key] = "file " + params.values().at(key) + ", built in " + fallback;
  }
  return out;
}
}  // namespace

// The same for every parameter the extraction, the mergers and the evaluation read
// (config/line_extraction.yaml, line_map_merging.yaml, line_map_eval.yaml, read together as linemap_batch and
// the launch files do): the fallback each getter is asked with is what a nodelet started without the files
// uses.
TEST(ShippedConfig, PipelineDefaultsAreTheConfigFiles)
{
  linemap::ParamSet params = line_map_eval::loadParameterFiles(
      {LINEMAP_SOURCE_DIR "/config/line_extraction.yaml", LINEMAP_SOURCE_DIR "/config/line_map_merging.yaml",
       LINEMAP_SOURCE_DIR "/config/line_map_eval.yaml"});
  std::map<std::string, std::string> fallbacks;
  params.noteFallbacks(&fallbacks);
  line_extraction::PipelineParams::fromParams(params);
  line_extraction::SubmapParams::fromParams(params);
  line_extraction::SensorModel::fromParams(params);
  for (const auto& name : line_extraction::extractorNames()) line_extraction::makeExtractor(name, params);
  for (const auto& name : line_map_merging::mergerNames())
  {
    line_map_merging::makeMerger(name, params);
    line_map_merging::ConcurrentMapper::fromParams(name, params);
  }
  line_map_merging::KeyframeGateParams::fromParams(params);
  line_map_merging::MapLevelParams::fromParams(params);
  line_map_merging::OnlineMapperParams::fromParams(params);
  line_map_eval::CoverageParams::fromParams(params);
  line_map_eval::QualityParams::fromParams(params);
  line_map_eval::LookupTableParams::fromParams(params);
  line_map_eval::GroundTruthParams::fromParams(params);
  line_map_eval::StructureParams::fromParams(params);
  line_map_eval::EvaluatorParams::fromParams(params);
  line_map_eval::OnlineEvaluatorParams::fromParams(params);
  EXPECT_GT(fallbacks.size(), 50u);  // the getters did note what they read
  for (const auto& [key, what] : differing(params, fallbacks)) ADD_FAILURE() << key << ": " << what;
}

// The batch tool reads the three pipeline files into one set, as the nodelets read each into their own
// namespace: a key two files set differently would reach one component with the other's value (the
// evaluator's cores once ran the merger's MP-GMA on one thread in every batch run).
TEST(ShippedConfig, NoKeyIsSetDifferentlyByTwoPipelineFiles)
{
  const std::vector<std::string> names = {"line_extraction.yaml", "line_map_merging.yaml",
                                          "line_map_eval.yaml"};
  std::vector<linemap::ParamSet> files;
  for (const auto& name : names)
    files.push_back(line_map_eval::loadParameterFiles({std::string(LINEMAP_SOURCE_DIR "/config/") + name}));
  for (std::size_t i = 0; i < files.size(); ++i)
    for (std::size_t j = i + 1; j < files.size(); ++j)
      for (const auto& [key, value] : files[i].values())
      {
        if (files[j].has(key))
        {
          EXPECT_EQ(value, files[j].values().at(key)) << key << " in " << names[i] << " and " << names[j];
        }
      }
}
