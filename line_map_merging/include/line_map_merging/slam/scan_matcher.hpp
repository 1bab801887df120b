// Scan-to-map matching on a likelihood field (ROS-free): a brute-force correlative search over a
// window of poses (Olson 2009; it cannot be trapped in a local optimum inside the window, and it is
// what gives the front end its robustness to bad odometry and the loop closer its reach), then a
// Ceres least-squares refinement of the best candidate on the bicubically interpolated field
// (sub-cell precision the search's grid steps cannot give).
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

#include "line_map_merging/slam/likelihood_grid.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
struct SearchWindow
{
  double linear = 0.1;         ///< [m] half width in x and y
  double angular = 0.05;       ///< [rad] half width
  double linear_step = 0.0;    ///< [m]; rounded to whole cells, 0 = one cell
  double angular_step = 0.01;  ///< [rad]
  /// Candidates further from the window's centre score lower, by exp(-(w_t d^2 + w_r a^2)): among
  /// equally good poses (a corridor) the one nearest the prior wins.
  double translation_penalty = 0.0;  ///< [1/m^2]
  double rotation_penalty = 0.0;     ///< [1/rad^2]
};

/// The best score over a search's headings at each translation of its grid (without the penalty): how
/// the score spreads over the window, e.g. whether a pose far from the best scores nearly as well.
struct TranslationScores
{
  linemap::Vec2 centre = linemap::Vec2::Zero();  ///< the window's centre
  double step = 0.0;                             ///< [m] between translations
  int reach = -1;                                ///< translations from -reach to reach steps in x and y
  std::vector<double> best;                      ///< row-major, y outer
  /// The best score among translations at least `distance` from `at` (0 when there is none).
  double bestAwayFrom(const linemap::Vec2& at, double distance) const;
  /// The outward unit direction of the window's border where `at` lies on its outermost translations (a
  /// corner's diagonal), zero inside or without a grid: a best found there is no peak along it, since the
  /// score may go on rising beyond the window.
  linemap::Vec2 borderDirection(const linemap::Vec2& at) const;
  /// The line the translations scoring `threshold` or more spread along from `at` (the principal axis of
  /// their offsets), and how far along it they reach either side: a corridor's slid matches.
  struct Ridge
  {
    linemap::Vec2 direction = linemap::Vec2::UnitX();  ///< unit
    double from = 0.0, to = 0.0;  ///< [m] the least and greatest offset along `direction`
  };
  std::optional<Ridge> ridgeThrough(const linemap::Vec2& at, double threshold) const;
  /// The best score among translations at least `distance` off the line through `at` along `direction`.
  double bestAcross(const linemap::Vec2& at, const linemap::Vec2& direction, double distance) const;
};

struct RefinementParams
{
  /// Weights of the prior's residuals against the points' (whose total weight is 1): they hold the
  /// pose where the scan alone does not (a corridor along its axis).
  double translation_weight = 1.0;  ///< [1/m]
  double rotation_weight = 1.0;     ///< [1/rad]
  int max_iterations = 20;
};

struct MatchResult
{
  linemap::Pose2 pose;
  double score = 0.0;  ///< mean field value of the points at `pose`, in [0, 1]
  /// Minus the Hessian of the score at `pose` over (x, y, theta), without the prior: how sharply the
  /// scan fixes each direction. Filled by refineMatch; a corridor's is near zero along its axis.
  Eigen::Matrix3d curvature = Eigen::Matrix3d::Zero();
};

/// What a match determines of a relative pose, as a shape over the translation: the curvature's
/// (x, y) block scaled so that its best-determined direction has weight 1, and every direction
/// determined at least `isotropic_ratio` as well as that one counted as fully determined (weight 1).
/// Below that ratio a direction's weight falls in proportion (down to `floor`): the match barely
/// says where along it the pose lies.
struct TranslationShape
{
  Eigen::Matrix2d weights = Eigen::Matrix2d::Identity();  ///< symmetric, eigenvalues in [floor, 1]
  double ratio = 1.0;       ///< weakest / strongest curvature of the translation block
  bool degenerate = false;  ///< some direction weighs less than 1
  /// The length of `v` in the shape's metric: |v| along determined directions, less along others.
  double norm(const linemap::Vec2& v) const { return std::sqrt(std::max(0.0, v.dot(weights * v))); }
};
TranslationShape translationShape(const Eigen::Matrix3d& curvature, double isotropic_ratio, double floor);
/// How far from the pose, in the root-mean-square, the points that fix a match's heading lie [m]: the
/// curvature's heading term over its translation block's strongest. A turn by dtheta moves them by about
/// lever * dtheta, so a match pinned to within s in translation is pinned to about s / lever in heading.
/// Zero where the curvature is empty (an unrefined match).
double matchLeverArm(const Eigen::Matrix3d& curvature);
/// A match's pose where its `shape` determines the translation, a `prior` pose elsewhere (in proportion to
/// each direction's weight); the match's heading. The front end keeps the odometry's prediction so; a loop
/// closure the graph's estimate: along a corridor's axis a match slides between look-alike stretches (seen
/// from the other end, a door's far jamb where the near one was), and the weak pulls of a few slid closures
/// add up to a slide of the whole pass.
linemap::Pose2 heldToEstimate(const linemap::Pose2& match, const linemap::Pose2& prior,
                              const TranslationShape& shape);

/// Mean nearest-cell field value of `points` (in the frame whose pose is sought) at `pose`.
double matchScore(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                  const linemap::Pose2& pose);

/// The `keep` best poses of the window around `center`, best first (score without the penalty);
/// with `spread`, also the best score at each translation.
std::vector<MatchResult> correlativeSearch(const LikelihoodGrid& grid,
                                           const std::vector<linemap::Vec2>& points,
                                           const linemap::Pose2& center, const SearchWindow& window,
                                           std::size_t keep = 1, TranslationScores* spread = nullptr);

/// Least-squares refinement from `initial`, held towards `prior`; the result's score is the mean
/// interpolated field value.
MatchResult refineMatch(const LikelihoodGrid& grid, const std::vector<linemap::Vec2>& points,
                        const linemap::Pose2& initial, const linemap::Pose2& prior,
                        const RefinementParams& params);

}  // namespace line_map_merging
