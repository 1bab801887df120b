#include "line_map_merging/slam/laser_slam_params.hpp"

#include <string>

#include "line_extraction/param_checks.hpp"

namespace line_map_merging
{
namespace
{
using line_extraction::countParam;
using line_extraction::positiveParam;

void readWindow(const linemap::ParamSet& p, const std::string& block, SearchWindow& w)
{
  w.linear = p.getDouble(block + "/linear", w.linear);
  w.angular = p.getDouble(block + "/angular", w.angular);
  w.linear_step = p.getDouble(block + "/linear_step", w.linear_step);
  w.angular_step = p.getDouble(block + "/angular_step", w.angular_step);
  w.translation_penalty = p.getDouble(block + "/translation_penalty", w.translation_penalty);
  w.rotation_penalty = p.getDouble(block + "/rotation_penalty", w.rotation_penalty);
  if (!(w.linear >= 0.0) || !(w.angular >= 0.0) || !(w.angular_step > 0.0))
    throw linemap::ParameterError(block + "/linear, /angular must be >= 0 and /angular_step > 0");
}

/// The "front_end/..." keys.
void readFrontEnd(const linemap::ParamSet& p, LaserSlamParams& s)
{
  s.max_range = positiveParam(p, "front_end/max_range", s.max_range);
  s.min_points = countParam(p, "front_end/min_points", s.min_points, 3);
  s.resolution = positiveParam(p, "front_end/resolution", s.resolution);
  s.sigma = positiveParam(p, "front_end/sigma", s.sigma);
  readWindow(p, "front_end/window", s.window);
  readWindow(p, "front_end/window_no_odometry", s.window_no_odometry);
  s.refinement.translation_weight =
      p.getDouble("front_end/refinement/translation_weight", s.refinement.translation_weight);
  s.refinement.rotation_weight =
      p.getDouble("front_end/refinement/rotation_weight", s.refinement.rotation_weight);
  s.refinement.max_iterations = static_cast<int>(countParam(
      p, "front_end/refinement/max_iterations", static_cast<std::size_t>(s.refinement.max_iterations), 1));
  s.min_score = p.getDouble("front_end/min_score", s.min_score);
  s.widen_ratio = p.getDouble("front_end/widen_ratio", s.widen_ratio);
  if (!(s.widen_ratio >= 0.0 && s.widen_ratio <= 1.0))
    throw linemap::ParameterError("parameter 'front_end/widen_ratio' must be in [0, 1]");
  s.filter_distance = p.getDouble("front_end/filter_distance", s.filter_distance);
  s.filter_angle = p.getDouble("front_end/filter_angle", s.filter_angle);
  s.keyframe_distance = positiveParam(p, "front_end/keyframe_distance", s.keyframe_distance);
  s.keyframe_angle = positiveParam(p, "front_end/keyframe_angle", s.keyframe_angle);
  s.local_map_keyframes = countParam(p, "front_end/local_map_keyframes", s.local_map_keyframes, 1);
  s.surfaces.lambda = p.getDouble("front_end/surface_lambda", s.surfaces.lambda);
  if (!(s.surfaces.lambda >= 0.0 && s.surfaces.lambda < linemap::kPi / 2))
    throw linemap::ParameterError("parameter 'front_end/surface_lambda' must be in [0, pi/2) rad");
  s.surfaces.range_sigma = positiveParam(p, "front_end/range_sigma", s.surfaces.range_sigma);
  s.odometry_jump.step = positiveParam(p, "front_end/max_odometry_step", s.odometry_jump.step);
  s.odometry_jump.turn = positiveParam(p, "front_end/max_odometry_turn", s.odometry_jump.turn);
  s.odometry_jump.speed = p.getNonNegative("front_end/max_odometry_speed", s.odometry_jump.speed);
  s.odometry_jump.turn_rate = p.getNonNegative("front_end/max_odometry_turn_rate", s.odometry_jump.turn_rate);
  s.time_jump_tolerance = positiveParam(p, "front_end/time_jump_tolerance", s.time_jump_tolerance);
}

/// The "graph/..." keys.
void readGraph(const linemap::ParamSet& p, LaserSlamParams& s)
{
  s.edge_sigma_xy = positiveParam(p, "graph/edge_sigma_xy", s.edge_sigma_xy);
  s.edge_sigma_theta = positiveParam(p, "graph/edge_sigma_theta", s.edge_sigma_theta);
  s.odometry_sigma_xy = positiveParam(p, "graph/odometry_sigma_xy", s.odometry_sigma_xy);
  s.odometry_sigma_theta = positiveParam(p, "graph/odometry_sigma_theta", s.odometry_sigma_theta);
  s.edge_odometry_disagreement = p.getBool("graph/edge_odometry_disagreement", s.edge_odometry_disagreement);
  s.suspect_edge_follows_odometry =
      p.getBool("graph/suspect_edge_follows_odometry", s.suspect_edge_follows_odometry);
  s.loop_sigma_xy = positiveParam(p, "graph/loop_sigma_xy", s.loop_sigma_xy);
  s.loop_sigma_theta = positiveParam(p, "graph/loop_sigma_theta", s.loop_sigma_theta);
  s.loop_loss_scale = positiveParam(p, "graph/loop_loss_scale", s.loop_loss_scale);
}

/// The "loop/..." keys.
void readLoop(const linemap::ParamSet& p, LaserSlamParams& s)
{
  s.loop_min_path = p.getDouble("loop/min_path", s.loop_min_path);
  s.loop_radius = positiveParam(p, "loop/radius", s.loop_radius);
  s.loop_radius_growth = p.getDouble("loop/radius_growth", s.loop_radius_growth);
  s.loop_max_radius = positiveParam(p, "loop/max_radius", s.loop_max_radius);
  s.loop_angle = positiveParam(p, "loop/angle", s.loop_angle);
  s.loop_angle_growth = p.getDouble("loop/angle_growth", s.loop_angle_growth);
  s.loop_max_angle = positiveParam(p, "loop/max_angle", s.loop_max_angle);
  s.loop_resolution = positiveParam(p, "loop/resolution", s.loop_resolution);
  s.loop_angular_step = positiveParam(p, "loop/angular_step", s.loop_angular_step);
  if (p.has("loop/submap_keyframes"))
    throw linemap::ParameterError(
        "parameter 'loop/submap_keyframes' is now 'loop/submap_path' (metres of path on "
        "each side of the candidate; 1.2 = the former 6 keyframes at 0.2 m)");
  s.loop_submap_path = p.getNonNegative("loop/submap_path", s.loop_submap_path);
  s.loop_candidates = countParam(p, "loop/candidates", s.loop_candidates, 0);
  s.loop_every = countParam(p, "loop/every", s.loop_every, 1);
  s.loop_min_score = p.getDouble("loop/min_score", s.loop_min_score);
  s.loop_min_score_ratio = p.getNonNegative("loop/min_score_ratio", s.loop_min_score_ratio);
  s.loop_max_error_xy = positiveParam(p, "loop/max_error_xy", s.loop_max_error_xy);
  s.loop_max_error_theta = positiveParam(p, "loop/max_error_theta", s.loop_max_error_theta);
  s.loop_corroborate_xy = p.getDouble("loop/corroborate_xy", s.loop_corroborate_xy);
  s.loop_corroborate_theta = p.getDouble("loop/corroborate_theta", s.loop_corroborate_theta);
  s.loop_agreement_xy = p.getDouble("loop/agreement_xy", s.loop_agreement_xy);
  s.loop_agreement_theta = p.getDouble("loop/agreement_theta", s.loop_agreement_theta);
  s.loop_consensus = countParam(p, "loop/consensus", s.loop_consensus, 0);
  if (p.has("loop/consensus_keyframes"))
    throw linemap::ParameterError(
        "parameter 'loop/consensus_keyframes' is now 'loop/consensus_waiting' (a count "
        "of refused closures, not of keyframes)");
  s.loop_consensus_waiting = countParam(p, "loop/consensus_waiting", s.loop_consensus_waiting, 2);
  s.loop_pending_keyframes = countParam(p, "loop/pending_keyframes", s.loop_pending_keyframes, 1);
  s.loop_in_view_only = p.getBool("loop/in_view_only", s.loop_in_view_only);
  s.loop_min_in_view = p.getDouble("loop/min_in_view", s.loop_min_in_view);
  if (!(s.loop_min_in_view >= 0.0 && s.loop_min_in_view <= 1.0))
    throw linemap::ParameterError("parameter 'loop/min_in_view' must be in [0, 1]");
  s.loop_ambiguity_distance = p.getDouble("loop/ambiguity_distance", s.loop_ambiguity_distance);
  if (p.has("loop/ambiguity_ratio"))
    throw linemap::ParameterError(
        "parameter 'loop/ambiguity_ratio' is now 'loop/ambiguity_margin' (1 - ratio: the former 0.9 is 0.1)");
  s.loop_ambiguity_margin = p.getDouble("loop/ambiguity_margin", s.loop_ambiguity_margin);
  s.loop_ridge_closures = p.getBool("loop/ridge_closures", s.loop_ridge_closures);
  if (!(s.loop_ambiguity_margin >= 0.0 && s.loop_ambiguity_margin <= 1.0))
    throw linemap::ParameterError("parameter 'loop/ambiguity_margin' must be in [0, 1]");
  s.loop_consistency_probability =
      p.getDouble("loop/consistency_probability", s.loop_consistency_probability);
  if (!(s.loop_consistency_probability >= 0.0 && s.loop_consistency_probability < 1.0))
    throw linemap::ParameterError("parameter 'loop/consistency_probability' must be in [0, 1)");
  s.loop_scale_by_disagreement = p.getDouble("loop/scale_by_disagreement", s.loop_scale_by_disagreement);
  s.loop_consistent_xy = p.getDouble("loop/consistent_xy", s.loop_consistent_xy);
  s.loop_consistent_theta = p.getDouble("loop/consistent_theta", s.loop_consistent_theta);
}

}  // namespace

LaserSlamParams LaserSlamParams::fromParams(const linemap::ParamSet& p)
{
  LaserSlamParams s;
  readFrontEnd(p, s);
  readGraph(p, s);
  readLoop(p, s);
  s.isotropic_ratio = p.getDouble("isotropic_ratio", s.isotropic_ratio);
  if (!(s.isotropic_ratio >= 0.0 && s.isotropic_ratio <= 1.0))
    throw linemap::ParameterError("parameter 'isotropic_ratio' must be in [0, 1]");
  s.min_weight = p.getDouble("min_weight", s.min_weight);
  if (!(s.min_weight > 0.0 && s.min_weight <= 1.0))
    throw linemap::ParameterError("parameter 'min_weight' must be in (0, 1]");
  return s;
}

TranslationShape matchShape(const MatchResult& match, const LaserSlamParams& params)
{
  if (params.isotropic_ratio <= 0.0) return {};
  return translationShape(match.curvature, params.isotropic_ratio, params.min_weight);
}

}  // namespace line_map_merging
