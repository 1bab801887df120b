// The laser SLAM's parameters (LaserSlamParams, read from config/slam.yaml's keys) and the one
// computation on them that the front end and the loop closer share: what a match determines
// (matchShape).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/scan_surfaces.hpp"
#include "linemap/geometry.hpp"
#include "linemap/odometry_jump.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
struct LaserSlamParams
{
  // Scan points.
  double max_range = 20.0;  ///< [m] farther points are dropped (sparse, and small angle errors grow there)
  std::size_t min_points = 20;  ///< fewer valid points: the scan is not matched (pose predicted)
  // Front end.
  double resolution = 0.025;  ///< [m] local likelihood field
  /// [m] its spread: about that of a scan point about a map point (both ranges noisy, plus a cell)
  double sigma = 0.03;
  SearchWindow window{0.1, 0.12, 0.05, 0.006, 2.0, 20.0};            ///< with odometry
  SearchWindow window_no_odometry{0.3, 0.3, 0.05, 0.008, 2.0, 5.0};  ///< without or off the odometry
  RefinementParams refinement{2.0, 2.0, 20};
  double min_score = 0.25;  ///< refined field score below: the prediction is kept
  /// The wide window is also searched when the normal one's match scores below this fraction of the
  /// run's recent matches (a running mean), or finds its best heading on the window's border.
  double widen_ratio = 0.75;
  double filter_distance = 0.02;         ///< [m] with odometry, scans that moved less are not matched
  double filter_angle = 0.01;            ///< [rad]
  double keyframe_distance = 0.2;        ///< [m]
  double keyframe_angle = 0.17;          ///< [rad]
  std::size_t local_map_keyframes = 20;  ///< keyframes in the local map
  /// With lambda > 0 the local map's field is of the keyframes' surfaces (scanSurfaces), not of their
  /// points alone: a wall at grazing incidence is then a line, not a row of dots that holds a scan at
  /// the keyframe's pose along a corridor. 0: the points alone.
  SurfaceParams surfaces{0.1745, 0.01};  ///< lambda about 10 degrees, as config/slam.yaml writes it
  /// Odometry moving more between two scans is a jump, not used for that step.
  linemap::OdometryJumpLimits odometry_jump;
  double time_jump_tolerance = 1.0;  ///< [s] a stamp this much before the last one: time jumped back
  /// What a match determines, as a weight per direction of the translation (its score's curvature;
  /// TranslationShape): a direction fixed at least this fraction as sharply as the best one counts
  /// fully, a weaker one in proportion. The front end takes the match's translation in the
  /// determined directions and keeps the prediction in the others (a corridor's axis); a closure's
  /// information takes the same shape, and its acceptance tests measure its disagreement in that
  /// metric. 0: every match determines everything (isotropic).
  double isotropic_ratio = 0.05;
  /// Floor of a direction's weight: only keeps the information invertible. A closure sliding along a
  /// corridor must not hold the estimate along it, and many weakly held closures add up.
  double min_weight = 1e-6;
  // Back end.
  double edge_sigma_xy = 0.02, edge_sigma_theta = 0.002;        ///< matched chain edges
  double odometry_sigma_xy = 0.2, odometry_sigma_theta = 0.05;  ///< chain edges with unmatched scans
  /// A matched chain edge whose disagreement with the odometry's motion over the same keyframe step lies far
  /// beyond the run's usual ones (a slip of the front end or of the odometry) is no more certain than the
  /// two agree (the disagreement added in quadrature to its sigmas), and the loop search looks across it
  /// until a closure spans it (ConstraintBuilder::suspectEdge).
  bool edge_odometry_disagreement = true;
  /// Such an edge takes the odometry's motion as its mean (its sigmas still widened by the disagreement)
  /// when the new keyframe's scan fits the previous keyframe's better there than at the match's: a slip of
  /// the front end carries its local map along, the scan pair does not move.
  bool suspect_edge_follows_odometry = true;
  double loop_sigma_xy = 0.05, loop_sigma_theta = 0.01;
  double loop_loss_scale = 1.0;  ///< Cauchy scale, in standard deviations
  double loop_min_path = 5.0;    ///< [m] path between a keyframe and a candidate
  /// The loop match uses only the scan points (at the estimate) inside some submap keyframe's view cone
  /// (submap_view.hpp): a place the submap never looked at cannot tell where the scan lies.
  bool loop_in_view_only = true;
  /// With loop_in_view_only: a scan with a smaller share of its points in view is not matched (a sliver of
  /// overlap fits in many places, and fixes a pose less well).
  double loop_min_in_view = 0.5;
  double loop_radius = 0.6;          ///< [m] search radius just after a closure
  double loop_radius_growth = 0.05;  ///< [m per m of path since the last closure]
  double loop_max_radius = 3.0;      ///< [m]
  double loop_angle = 0.15;          ///< [rad]
  double loop_angle_growth = 0.01;   ///< [rad per m]
  double loop_max_angle = 0.5;       ///< [rad]
  double loop_resolution = 0.1;      ///< [m] coarse field of the wide search
  double loop_angular_step = 0.015;  ///< [rad]
  /// [m] a loop candidate's submap: its neighbouring keyframes over this much path on each side, counted as
  /// keyframes at keyframe_distance (submapKeyframes): the same stretch of building whatever the spacing.
  double loop_submap_path = 1.2;
  std::size_t loop_candidates = 2;  ///< submaps tried per keyframe
  std::size_t loop_every = 1;       ///< keyframes between attempts
  /// A closure's refined score must reach loop_min_score, or loop_min_score_ratio times the front end's
  /// typical match score where that is lower: a sensor whose consecutive scans meet each other's surfaces
  /// loosely (coarse ranges, far sparse walls) gives every true closure a lower score too. 0: the former
  /// alone.
  double loop_min_score = 0.55;
  double loop_min_score_ratio = 0.65;
  /// The score a closure must reach when the front end's matches typically score `front_end_score` (0:
  /// not known yet).
  double loopMinScore(double front_end_score) const
  {
    return loop_min_score_ratio > 0.0 && front_end_score > 0.0
               ? std::min(loop_min_score, loop_min_score_ratio * front_end_score)
               : loop_min_score;
  }
  /// A closure whose coarse search finds another pose at least ambiguity_distance away scoring within
  /// ambiguity_margin of the best (a fraction of its score) is refused (a corridor seen from inside), as is
  /// a best on the search window's border along a direction the match determines (ConstraintBuilder:
  /// ambiguity 1); either 0: no check. A margin, not the rival's share of the best: near 1 a share leaves
  /// no room to loosen the test.
  double loop_ambiguity_distance = 0.3;  ///< [m]
  double loop_ambiguity_margin = 0.1;
  /// Across a suspect chain edge no closure spans yet, a match ambiguous only along one line through its best
  /// (a corridor's slid matches, no rival across it) is matched again where that line passes the estimate
  /// and goes in for the direction across it and the heading; along the line the edge keeps the estimate.
  bool loop_ridge_closures = true;
  /// Whether a match whose rival scores `ambiguity` (a fraction of the best) is refused as ambiguous.
  bool ambiguous(double ambiguity) const
  {
    return loop_ambiguity_distance > 0.0 && loop_ambiguity_margin > 0.0 &&
           ambiguity >= 1.0 - loop_ambiguity_margin;
  }
  /// A closure is refused when its disagreement with the estimate is beyond this quantile of the chi-square
  /// distribution (3 degrees of freedom) in the metric of the combined uncertainty: the closure's own
  /// covariance plus that of the estimate's relative pose along the graph's most certain path
  /// (relativeCovariance). 0: no such test.
  double loop_consistency_probability = 0.999;
  /// An unambiguous closure goes in under a Cauchy scale of this many times its disagreement with the
  /// estimate (in standard deviations), so a true closure after a long drift is applied, not damped
  /// like an outlier; 0: always the graph's loop_loss_scale.
  double loop_scale_by_disagreement = 2.0;
  double loop_max_error_xy = 0.3;     ///< [m] a closure the optimised graph misses by more is removed
  double loop_max_error_theta = 0.1;  ///< [rad]
  /// A closure the estimate misses by more than these needs a second one implying the same correction
  /// (within agreement_*) from one of the next pending_keyframes keyframes; both then go in under a
  /// loss as wide as twice the correction. Off by default (1e9, as config/slam.yaml writes it): on the
  /// Intel and ACES corridors, closures sliding along a corridor corroborated each other.
  double loop_corroborate_xy = 1.0e9;     ///< [m]
  double loop_corroborate_theta = 1.0e9;  ///< [rad]
  double loop_agreement_xy = 0.1;         ///< [m]
  double loop_agreement_theta = 0.03;     ///< [rad]
  std::size_t loop_pending_keyframes = 10;
  /// A closure refused as inconsistent with the chain waits for others: when loop_consensus of the
  /// waiting ones, from as many different keyframes, agree with each other (closure_consensus.hpp: within
  /// the consistency gate, by cycles tight enough to tell their corrections from none), they outvote the
  /// chain and go in together: a front-end slip the chain cannot see is repaired. 0: the chain always wins.
  std::size_t loop_consensus = 3;
  /// The newest this many refused closures wait (the pairwise tests cost their square per refusal).
  std::size_t loop_consensus_waiting = 50;
  /// A closure the current estimate meets within these is added without optimising at once.
  double loop_consistent_xy = 0.03;     ///< [m]
  double loop_consistent_theta = 0.01;  ///< [rad]

  /// The keyframes on each side of a loop candidate in its submap (at least 1).
  std::size_t submapKeyframes() const
  {
    return static_cast<std::size_t>(std::max(1.0, std::round(loop_submap_path / keyframe_distance)));
  }

  /// Keys as in config/slam.yaml (e.g. "window/linear", "loop/min_score"); throws
  /// linemap::ParameterError naming the key.
  static LaserSlamParams fromParams(const linemap::ParamSet& params);
};

/// The translation shape of a match (identity when isotropic_ratio is 0).
TranslationShape matchShape(const MatchResult& match, const LaserSlamParams& params);

}  // namespace line_map_merging
