// Likelihood field and scan matcher against closed forms: the field of one point is the Gaussian of
// the distance; a scan cast from a known pose is found again from a displaced prior.
#include <ceres/cubic_interpolation.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "line_map_merging/slam/likelihood_grid.hpp"
#include "line_map_merging/slam/scan_matcher.hpp"
#include "line_map_merging/slam/scan_surfaces.hpp"
#include "slam_world.hpp"

using line_map_merging::correlativeSearch;
using line_map_merging::LikelihoodGrid;
using line_map_merging::refineMatch;
using line_map_merging::RefinementParams;
using line_map_merging::SearchWindow;
using linemap::Pose2;
using linemap::Vec2;

TEST(LikelihoodGrid, OnePointIsTheGaussianOfTheDistance)
{
  const double res = 0.02, sigma = 0.05;
  const LikelihoodGrid grid({{1.0, 2.0}}, res, sigma, 0.3);
  // Cell centres lie on the grid of the origin; the field at a cell is exp(-d^2 / 2 sigma^2) of
  // the distance from that cell's centre to the point.
  for (double d : {0.0, 0.04, 0.08, 0.12})
  {
    const double x = 1.0 + d;
    const long ix = std::lround((x - grid.origin().x()) / res);
    const double cx = grid.origin().x() + ix * res;
    const long iy = std::lround((2.0 - grid.origin().y()) / res);
    const double cy = grid.origin().y() + iy * res;
    const double dist = std::hypot(cx - 1.0, cy - 2.0);
    EXPECT_NEAR(grid.nearest(x, 2.0), std::exp(-dist * dist / (2 * sigma * sigma)), 1e-9) << "d = " << d;
  }
  // Beyond 3 sigma: nothing; outside the grid: 0.
  EXPECT_EQ(grid.nearest(1.2, 2.0), 0.0);
  EXPECT_EQ(grid.nearest(50.0, 50.0), 0.0);
}

TEST(LikelihoodGrid, OneSegmentIsTheGaussianOfTheDistanceToIt)
{
  const double res = 0.02, sigma = 0.05;
  const Vec2 a(1.0, 2.0), b(2.5, 2.7);  // oblique: the cells near it lie off its bounding box's rows
  const LikelihoodGrid grid({a, b}, {{a, b}}, res, sigma, 0.3);
  int near = 0;
  for (double x = 0.7; x <= 2.8; x += 0.013)
    for (double y = 1.7; y <= 3.0; y += 0.011)
    {
      const double cx = grid.origin().x() + std::lround((x - grid.origin().x()) / res) * res;
      const double cy = grid.origin().y() + std::lround((y - grid.origin().y()) / res) * res;
      const double d = linemap::distanceToSegment({cx, cy}, a, b);
      const double expected = d >= 3.0 * sigma ? 0.0 : std::exp(-d * d / (2 * sigma * sigma));
      ASSERT_NEAR(grid.nearest(x, y), expected, 1e-9) << x << " " << y;
      near += expected > 0.5 ? 1 : 0;
    }
  EXPECT_GT(near, 1000);
}

TEST(LikelihoodGrid, RoundsAsLround)
{
  const double below_half = std::nextafter(0.5, 0.0);
  for (double v : {0.0,
                   -0.0,
                   0.5,
                   -0.5,
                   1.5,
                   -1.5,
                   2.5,
                   -2.5,
                   below_half,
                   -below_half,
                   0.49,
                   0.51,
                   -0.51,
                   1e-300,
                   123456.5,
                   -123456.5,
                   4503599627370495.5,
                   4503599627370497.0,
                   -7.0e15,
                   3.9e18,
                   -3.9e18})
    EXPECT_EQ(line_map_merging::roundHalfAway(v), std::lround(v)) << v;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> any(-1e4, 1e4);
  for (int i = 0; i < 100000; ++i)
  {
    const double v = any(random);
    ASSERT_EQ(line_map_merging::roundHalfAway(v), std::lround(v)) << v;
  }
}

/// Random walls and clutter: many tiles, written by points and by joins, up to the grid's edges.
LikelihoodGrid clutteredField(std::vector<Vec2>& points, std::vector<linemap::Segment2>& joins, double res,
                              double sigma, unsigned seed = 11, double size = 6.0)
{
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> where(0.0, size), step(0.005, 0.2);
  for (int wall = 0; wall < 12; ++wall)
  {
    const Vec2 a(where(random), where(random)), b(where(random), where(random));
    Vec2 last = a;
    points.push_back(a);
    for (double t = step(random); t < 1.0; t += step(random))
    {
      const Vec2 q = a + t * (b - a);
      points.push_back(q);
      joins.push_back({last, q});
      last = q;
    }
  }
  for (int i = 0; i < 200; ++i) points.emplace_back(where(random), where(random));
  return LikelihoodGrid(points, joins, res, sigma, 0.0);
}

/// Every cell of `grid` against the brute-force field of `points` and `joins`; returns the cells near one.
int expectBruteForceField(const LikelihoodGrid& grid, const std::vector<Vec2>& points,
                          const std::vector<linemap::Segment2>& joins, double res, double sigma)
{
  int written = 0;
  for (int iy = 0; iy < grid.height(); ++iy)
    for (int ix = 0; ix < grid.width(); ++ix)
    {
      const Vec2 centre = grid.origin() + Vec2(ix * res, iy * res);
      double d = std::numeric_limits<double>::infinity();
      for (const Vec2& p : points) d = std::min(d, (p - centre).norm());
      // Joins shorter than sigma are left to their end points' discs (the field's documented shortcut).
      for (const auto& j : joins)
        if ((j.end - j.start).norm() >= sigma)
          d = std::min(d, linemap::distanceToSegment(centre, j.start, j.end));
      const double expected = d >= 3.0 * sigma ? 0.0 : std::exp(-d * d / (2.0 * sigma * sigma));
      const double got = grid.cells()[static_cast<std::size_t>(iy) * grid.width() + ix];
      if (std::fabs(got - expected) > 1e-9)
      {
        ADD_FAILURE() << "cell " << ix << ", " << iy << ": " << got << " instead of " << expected;
        return written;
      }
      written += expected > 0.0 ? 1 : 0;
    }
  return written;
}

TEST(LikelihoodGrid, EveryCellIsTheGaussianOfItsNearestDistance)
{
  const double res = 0.025, sigma = 0.03;
  std::vector<Vec2> points;
  std::vector<linemap::Segment2> joins;
  const LikelihoodGrid grid = clutteredField(points, joins, res, sigma);
  EXPECT_GT(expectBruteForceField(grid, points, joins, res, sigma), grid.width() * grid.height() / 10);
}

TEST(LikelihoodGrid, AFieldBuiltWhereAnotherWasIsItsOwn)
{
  // Fields give their cells to the next one: what the last wrote must not show through in the next.
  const double res = 0.025, sigma = 0.03;
  std::vector<Vec2> points, smaller_points, larger_points;
  std::vector<linemap::Segment2> joins, smaller_joins, larger_joins;
  LikelihoodGrid grid = clutteredField(points, joins, res, sigma, 3, 8.0);
  grid = clutteredField(smaller_points, smaller_joins, res, sigma, 4, 5.0);  // the first one's cells, smaller
  EXPECT_GT(expectBruteForceField(grid, smaller_points, smaller_joins, res, sigma), 1000);
  const LikelihoodGrid copy = grid;
  grid = clutteredField(larger_points, larger_joins, res, sigma, 5, 9.0);  // grown
  EXPECT_GT(expectBruteForceField(grid, larger_points, larger_joins, res, sigma), 1000);
  EXPECT_GT(expectBruteForceField(copy, smaller_points, smaller_joins, res, sigma), 1000);
  {
    std::vector<Vec2> sparse{{0.0, 0.0}, {7.0, 7.0}};
    const LikelihoodGrid temporary(sparse, res, sigma, 0.0);
    EXPECT_GT(expectBruteForceField(temporary, sparse, {}, res, sigma), 20);
  }
  std::vector<Vec2> last_points;
  std::vector<linemap::Segment2> last_joins;
  const LikelihoodGrid last = clutteredField(last_points, last_joins, res, sigma, 6, 7.0);
  EXPECT_GT(expectBruteForceField(last, last_points, last_joins, res, sigma), 1000);
}

TEST(LikelihoodGrid, InterpolatesAsCeres)
{
  std::vector<Vec2> points;
  std::vector<linemap::Segment2> joins;
  const LikelihoodGrid grid = clutteredField(points, joins, 0.025, 0.03);
  const ceres::Grid2D<double, 1> cells(grid.cells().data(), 0, grid.height(), 0, grid.width());
  const ceres::BiCubicInterpolator<ceres::Grid2D<double, 1>> reference(cells);
  std::mt19937 random(5);
  // Inside, on cell centres, and beyond the border (where the border cells repeat).
  std::uniform_real_distribution<double> row(-3.0, grid.height() + 3.0), col(-3.0, grid.width() + 3.0);
  for (int i = 0; i < 20000; ++i)
  {
    const double r = i % 10 == 0 ? std::floor(row(random)) : row(random);
    const double c = i % 10 == 0 ? std::floor(col(random)) : col(random);
    double f, dfdr, dfdc;
    reference.Evaluate(r, c, &f, &dfdr, &dfdc);
    double g_dr, g_dc;
    ASSERT_EQ(grid.interpolate(r, c), f) << r << ", " << c;
    ASSERT_EQ(grid.interpolate(r, c, &g_dr, &g_dc), f);
    ASSERT_EQ(g_dr, dfdr);
    ASSERT_EQ(g_dc, dfdc);
  }
}

// A wall seen at grazing incidence from 1 m is one chain of segments however far apart its points lie;
// a box in front of another wall is not joined to it.
TEST(ScanSurfaces, JoinAGrazingWallNotADepthJump)
{
  const std::vector<linemap::Segment2> walls = {
      {{0, 1}, {30, 1}}, {{6, -3}, {6, -1}}, {{3, -1.0}, {3, -0.5}}};
  const auto points = slam_world::scan(walls, Pose2(), 180, 20.0, 0.005, 3);
  const auto surfaces = line_map_merging::scanSurfaces(points, {});
  auto on = [](const Vec2& p, double x0, double y0, double x1, double y1) {
    return linemap::distanceToSegment(p, {x0, y0}, {x1, y1}) < 0.03;
  };
  std::size_t wall_points = 0, wall_joins = 0;
  double farthest = 0.0;
  for (const auto& p : points) wall_points += on(p, 0, 1, 30, 1) ? 1 : 0;
  for (const auto& s : surfaces)
  {
    const bool a_wall = on(s.start, 0, 1, 30, 1), b_wall = on(s.end, 0, 1, 30, 1);
    const bool a_box = on(s.start, 3, -1, 3, -0.5), b_box = on(s.end, 3, -1, 3, -0.5);
    EXPECT_EQ(a_box, b_box) << "joined across a depth jump";
    EXPECT_EQ(a_wall, b_wall);
    if (a_wall && b_wall)
    {
      ++wall_joins;
      farthest = std::max(farthest, std::max(s.start.x(), s.end.x()));
    }
  }
  ASSERT_GT(wall_points, 40u);
  EXPECT_EQ(wall_joins, wall_points - 1);  // one chain
  EXPECT_GT(farthest, 15.0);               // points metres apart at the far end
}

// Two thin posts side by side at 5 m, one beam each, with a wall far behind: the breakpoint test alone
// would join them (0.09 m apart at 5 m passes at 10 degrees), but no third point continues the pair, so
// they are two objects, not a surface.
TEST(ScanSurfaces, TwoPostsAreNotASurface)
{
  const auto beam = [](int i) { return -linemap::kPi / 2 + linemap::kPi * (i + 0.5) / 180; };
  std::vector<linemap::Segment2> walls = {{{15, -40}, {15, 40}}};
  for (int i : {90, 91})
  {
    const Vec2 c(5.0 * std::cos(beam(i)), 5.0 * std::sin(beam(i))),
        across(-std::sin(beam(i)), std::cos(beam(i)));
    walls.push_back({c - 0.01 * across, c + 0.01 * across});
  }
  const auto points = slam_world::scan(walls, Pose2(), 180, 20.0);
  std::size_t posts = 0;
  for (const auto& p : points) posts += p.norm() < 6.0 ? 1 : 0;
  ASSERT_EQ(posts, 2u);
  const auto surfaces = line_map_merging::scanSurfaces(points, {});
  for (const auto& s : surfaces)
    EXPECT_FALSE(s.start.norm() < 6.0 || s.end.norm() < 6.0) << "a post joined to " << s.end.transpose();
  EXPECT_GT(surfaces.size(), 30u);  // the far wall is still joined
}

TEST(ScanMatcher, RecoversAKnownPoseFromADisplacedPrior)
{
  const auto walls = slam_world::room();
  const Pose2 truth(4.0, 3.5, 0.3);
  // Map: a dense scan from another pose, in the world frame.
  std::vector<Vec2> map;
  for (const Pose2& p : {Pose2(6.0, 4.0, 0.0), Pose2(6.0, 4.0, linemap::kPi)})
    for (const auto& q : slam_world::scan(walls, p, 720, 30.0)) map.push_back(p.apply(q));
  const LikelihoodGrid grid(map, 0.025, 0.04, 0.5);
  const auto points = slam_world::scan(walls, truth, 180, 30.0, 0.01, 7);
  ASSERT_GT(points.size(), 150u);
  const Pose2 prior = truth * Pose2(0.07, -0.06, 0.05);
  SearchWindow window{0.15, 0.1, 0.05, 0.005, 0.0, 0.0};
  const auto found = correlativeSearch(grid, points, prior, window, 1);
  ASSERT_EQ(found.size(), 1u);
  // The search alone is as good as its steps (with noise, one step off at most).
  EXPECT_NEAR(found[0].pose.x, truth.x, 0.05 + 1e-9);
  EXPECT_NEAR(found[0].pose.y, truth.y, 0.05 + 1e-9);
  EXPECT_NEAR(found[0].pose.theta, truth.theta, 0.005 + 1e-9);
  const auto refined =
      refineMatch(grid, points, found[0].pose, found[0].pose, RefinementParams{0.1, 0.1, 30});
  // The refinement goes below the steps (1 cm range noise; 2.5 cm cells).
  EXPECT_NEAR(refined.pose.x, truth.x, 0.01);
  EXPECT_NEAR(refined.pose.y, truth.y, 0.01);
  EXPECT_NEAR(refined.pose.theta, truth.theta, 0.002);
  EXPECT_GT(refined.score, 0.8);
  // From the prior itself the score is far lower: the field does discriminate.
  EXPECT_LT(line_map_merging::matchScore(grid, points, prior), 0.5);
}

TEST(ScanMatcher, CorridorKeepsThePriorAlongItsAxis)
{
  // Two long parallel walls: a scan fixes y and theta but not x.
  const std::vector<linemap::Segment2> walls = {{{-50, 0}, {50, 0}}, {{-50, 2}, {50, 2}}};
  const Pose2 truth(0.0, 1.0, 0.0);
  std::vector<Vec2> map;
  for (double x = -10; x <= 10; x += 0.01)
  {
    map.push_back({x, 0.0});
    map.push_back({x, 2.0});
  }
  const LikelihoodGrid grid(map, 0.025, 0.04, 0.5);
  const auto points = slam_world::scan(walls, truth, 180, 8.0);
  const Pose2 prior(0.12, 1.08, 0.03);
  SearchWindow window{0.2, 0.08, 0.025, 0.005, 2.0, 20.0};
  const auto found = correlativeSearch(grid, points, prior, window, 1);
  ASSERT_EQ(found.size(), 1u);
  const auto refined =
      refineMatch(grid, points, found[0].pose, found[0].pose, RefinementParams{2.0, 2.0, 30});
  EXPECT_NEAR(refined.pose.y, truth.y, 0.01);
  EXPECT_NEAR(refined.pose.theta, truth.theta, 0.003);
  // Along the axis nothing is measured: the penalty keeps the prior's x (not the window's edge).
  EXPECT_NEAR(refined.pose.x, prior.x, 0.03);
  // The spread of the score over the window says the same: poses 0.15 m along the axis score as well as
  // the best (every point still on a wall), none 0.15 m across it does.
  line_map_merging::TranslationScores spread;
  const auto best =
      correlativeSearch(grid, points, prior, SearchWindow{0.2, 0.08, 0.025, 0.005, 0.0, 0.0}, 1, &spread);
  ASSERT_EQ(spread.best.size(), 17u * 17u);
  const Vec2 at = best[0].pose.translation();
  EXPECT_NEAR(spread.bestAwayFrom(at, 0.0), best[0].score, 1e-12);
  EXPECT_GT(spread.bestAwayFrom(at, 0.15), 0.95 * best[0].score);
  double across = 0.0;
  for (int oy = -spread.reach; oy <= spread.reach; ++oy)
    for (int ox = -spread.reach; ox <= spread.reach; ++ox)
      if (std::fabs(spread.centre.y() + oy * spread.step - at.y()) >= 0.15)
        across = std::max(
            across, spread.best[static_cast<std::size_t>((oy + spread.reach) * 17 + ox + spread.reach)]);
  EXPECT_LT(across, 0.5 * best[0].score);
  EXPECT_EQ(spread.bestAwayFrom(at, 10.0), 0.0);
}

namespace
{
/// The translation shape of a refinement at `pose` of a scan of `walls` (beams, range) in the field
/// of `map`, started at the truth.
line_map_merging::TranslationShape shapeAt(const std::vector<Vec2>& map,
                                           const std::vector<linemap::Segment2>& walls, const Pose2& pose,
                                           int beams, double range)
{
  const LikelihoodGrid field(map, 0.025, 0.04, 0.5);
  const auto match = refineMatch(field, slam_world::scan(walls, pose, beams, range), pose, pose,
                                 RefinementParams{2.0, 2.0, 30});
  return line_map_merging::translationShape(match.curvature, 0.1, 1e-3);
}
}  // namespace

// The refinement's curvature says what the scan determines: in a corridor along x, nothing along
// x; in the room with boxes and a niche, both directions.
// The border of a window of translations centre + (i, j) step, |i|, |j| <= reach: the outermost ring, its
// outward direction (a corner's diagonal); inside, none.
TEST(ScanMatcher, BorderDirectionOfTheWindow)
{
  line_map_merging::TranslationScores spread;
  spread.centre = linemap::Vec2(1.0, 2.0);
  spread.step = 0.1;
  spread.reach = 5;
  const auto direction = [&](double x, double y) { return spread.borderDirection(linemap::Vec2(x, y)); };
  EXPECT_TRUE(direction(1.5, 2.0).isApprox(linemap::Vec2(1.0, 0.0)));
  EXPECT_TRUE(direction(1.2, 1.5).isApprox(linemap::Vec2(0.0, -1.0)));
  const double h = std::sqrt(0.5);
  EXPECT_TRUE(direction(0.5, 2.5).isApprox(linemap::Vec2(-h, h)));
  EXPECT_EQ(direction(1.4, 2.4).norm(), 0.0);  // one step inside
  EXPECT_EQ(direction(1.0, 2.0).norm(), 0.0);
  line_map_merging::TranslationScores none;  // no grid: no border
  EXPECT_EQ(none.borderDirection(linemap::Vec2(5.0, 5.0)).norm(), 0.0);
}

// Translations scoring 1 along the diagonal x = y through the window's centre, 0.5 elsewhere: the ridge
// runs along (1, 1) / sqrt 2 from -reach to +reach steps of the diagonal either side of the centre, and off
// it the best score is 0.5; a cell 0.3 m off the line scoring 1 is a rival across it.
TEST(ScanMatcher, RidgeOfTranslationsAlongADiagonal)
{
  line_map_merging::TranslationScores spread;
  spread.centre = linemap::Vec2(1.0, 2.0);
  spread.step = 0.1;
  spread.reach = 5;
  const int side = 2 * spread.reach + 1;
  spread.best.assign(static_cast<std::size_t>(side * side), 0.5);
  const auto cell = [&](int ox, int oy) -> double&
  { return spread.best[static_cast<std::size_t>((oy + spread.reach) * side + ox + spread.reach)]; };
  for (int i = -spread.reach; i <= spread.reach; ++i) cell(i, i) = 1.0;
  const linemap::Vec2 at(1.1, 2.1);  // one step up the diagonal
  const auto ridge = spread.ridgeThrough(at, 0.9);
  ASSERT_TRUE(ridge);
  const double h = std::sqrt(0.5), diagonal_step = 0.1 * std::sqrt(2.0);
  EXPECT_NEAR(std::fabs(ridge->direction.dot(linemap::Vec2(h, h))), 1.0, 1e-9);
  // From the centre's -5 steps to +5 steps, seen from +1: -6 and +4 diagonal steps (signs by direction).
  const double sign = ridge->direction.x() > 0.0 ? 1.0 : -1.0;
  EXPECT_NEAR(sign > 0.0 ? ridge->from : -ridge->to, -6.0 * diagonal_step, 1e-9);
  EXPECT_NEAR(sign > 0.0 ? ridge->to : -ridge->from, 4.0 * diagonal_step, 1e-9);
  EXPECT_DOUBLE_EQ(spread.bestAcross(at, ridge->direction, 0.3), 0.5);
  // A rival (4, 1) steps from the centre: 3 steps of x off the diagonal, 0.3 / sqrt 2 = 0.21 m across it.
  cell(4, 1) = 1.0;
  EXPECT_DOUBLE_EQ(spread.bestAcross(at, ridge->direction, 0.3), 0.5);
  EXPECT_DOUBLE_EQ(spread.bestAcross(at, ridge->direction, 0.2), 1.0);
  // Nothing scoring the threshold but the best itself: no line.
  std::fill(spread.best.begin(), spread.best.end(), 0.5);
  cell(1, 1) = 1.0;
  EXPECT_FALSE(spread.ridgeThrough(at, 0.9));
}

TEST(ScanMatcher, CurvatureShapesTheTranslation)
{
  const std::vector<linemap::Segment2> walls = {{{-50, 0}, {50, 0}}, {{-50, 2}, {50, 2}}};
  std::vector<Vec2> map;
  for (double x = -10; x <= 10; x += 0.01)
  {
    map.push_back({x, 0.0});
    map.push_back({x, 2.0});
  }
  const auto corridor_shape = shapeAt(map, walls, Pose2(0.0, 1.0, 0.0), 180, 8.0);
  // Beams end within 8 m on walls of 100 m: along x the score changes by interpolation ripple only,
  // two orders of magnitude below across.
  EXPECT_LT(corridor_shape.ratio, 0.01);
  EXPECT_TRUE(corridor_shape.degenerate);
  // Weights: ratio / isotropic_ratio along (< 0.1 here), 1 across.
  EXPECT_LT(corridor_shape.weights(0, 0), 0.1);
  EXPECT_NEAR(corridor_shape.weights(1, 1), 1.0, 1e-3);
  EXPECT_LT(corridor_shape.norm(Vec2(0.5, 0.0)), 0.5 * std::sqrt(0.1));
  EXPECT_NEAR(corridor_shape.norm(Vec2(0.0, 0.2)), 0.2, 1e-3);

  const auto room_walls = slam_world::room();
  std::vector<Vec2> room_points;
  for (const auto& w : room_walls)
    for (double t = 0.0; t <= 1.0; t += 0.005) room_points.push_back(w.start + t * (w.end - w.start));
  const auto room_shape = shapeAt(room_points, room_walls, Pose2(6.0, 4.0, 0.3), 360, 20.0);
  EXPECT_GT(room_shape.ratio, 0.1);
  EXPECT_FALSE(room_shape.degenerate);
  EXPECT_NEAR(room_shape.norm(Vec2(0.3, 0.4)), 0.5, 1e-9);  // isotropic: the plain length
}

TEST(ScanMatcher, EmptyInputsGiveNoMatch)
{
  const LikelihoodGrid empty;
  EXPECT_TRUE(correlativeSearch(empty, {{1.0, 0.0}}, Pose2(), SearchWindow{}, 1).empty());
  const LikelihoodGrid grid({{1.0, 0.0}}, 0.05, 0.05, 0.2);
  EXPECT_TRUE(correlativeSearch(grid, {}, Pose2(), SearchWindow{}, 1).empty());
  EXPECT_EQ(refineMatch(grid, {}, Pose2(1, 2, 3), Pose2(), RefinementParams{}).score, 0.0);
}

// Every translation's score is the mean field value of the scan's points in their shifted cells, those off
// the grid counting 0, summed in the points' order: a direct lookup per point is the reference, and both
// every window must equal it bit for bit, points far off the grid and points partly off it included: steps
// of one cell and of several (the front end's strided windows of 5 and 13 translations a side have loops of
// their own), wide windows and narrow ones.
TEST(ScanMatcher, EveryTranslationScoresTheMeanOfItsShiftedCells)
{
  std::vector<Vec2> walls;
  for (double t = 0.0; t <= 4.0; t += 0.05)
  {
    walls.emplace_back(t, 0.0);
    walls.emplace_back(t, 3.0);
    if (t <= 3.0)
    {
      walls.emplace_back(0.0, t);
      walls.emplace_back(4.0, t);
    }
  }
  const LikelihoodGrid grid(walls, 0.1, 0.1, 0.5);
  std::vector<Vec2> scan;
  for (std::size_t i = 0; i < walls.size(); i += 3) scan.push_back(walls[i] - Vec2(2.03, 1.46));
  for (const Vec2& far : {Vec2(30.0, 0.0), Vec2(-0.2, 25.0), Vec2(2.4, 0.9)}) scan.push_back(far);
  const Pose2 centre(1.95, 1.52, 0.02);
  for (const SearchWindow window : {SearchWindow{1.0, 0.06, 0.1, 0.015, 0.0, 0.0},   // 21 x 21 translations
                                    SearchWindow{2.5, 0.06, 0.1, 0.015, 0.0, 0.0},   // 51 x 51
                                    SearchWindow{0.1, 0.06, 0.1, 0.015, 0.0, 0.0},   // 3 x 3
                                    SearchWindow{0.4, 0.06, 0.2, 0.015, 0.0, 0.0},   // 5 x 5, every 2nd cell
                                    SearchWindow{1.2, 0.06, 0.2, 0.015, 0.0, 0.0},   // 13 x 13, every 2nd
                                    SearchWindow{0.9, 0.06, 0.3, 0.015, 0.0, 0.0}})  // 7 x 7, every 3rd
  {
    line_map_merging::TranslationScores spread;
    const auto found = correlativeSearch(grid, scan, centre, window, 1, &spread);
    ASSERT_EQ(found.size(), 1u);
    const int reach = spread.reach, side = 2 * reach + 1;
    const long step = std::lround(window.linear_step / 0.1);
    ASSERT_EQ(reach, static_cast<int>(std::lround(window.linear / window.linear_step)));
    std::vector<double> expected(static_cast<std::size_t>(side) * side, 0.0);
    for (int a = -4; a <= 4; ++a)
    {
      const double theta = centre.theta + a * window.angular_step;
      const double c = std::cos(theta), s = std::sin(theta);
      for (int oy = -reach; oy <= reach; ++oy)
        for (int ox = -reach; ox <= reach; ++ox)
        {
          double sum = 0.0;
          for (const Vec2& p : scan)
          {
            const long x =
                std::lround((c * p.x() - s * p.y() + centre.x - grid.origin().x()) / 0.1) + ox * step;
            const long y =
                std::lround((s * p.x() + c * p.y() + centre.y - grid.origin().y()) / 0.1) + oy * step;
            if (x >= 0 && y >= 0 && x < grid.width() && y < grid.height())
              sum += grid.cells()[static_cast<std::size_t>(y * grid.width() + x)];
          }
          double& e = expected[static_cast<std::size_t>((oy + reach) * side + ox + reach)];
          e = std::max(e, sum * (1.0 / static_cast<double>(scan.size())));
        }
    }
    for (std::size_t i = 0; i < expected.size(); ++i)
      ASSERT_EQ(spread.best[i], expected[i]) << "translation " << i;
    // The room's walls, seen from its middle, score highest where the scan was taken from (to the nearest
    // translation of the window).
    EXPECT_NEAR(found.front().pose.x, 2.03, 0.5 * window.linear_step + 0.001);
    EXPECT_NEAR(found.front().pose.y, 1.46, 0.5 * window.linear_step + 0.001);
    EXPECT_GT(found.front().score, 0.5);
  }
}

// A scan that fixes its heading only by walls beside it: points on two walls along x from the pose to L
// ahead. A turn by dtheta moves a point at x across its wall by x dtheta, so the heading's curvature over
// the translation's is the mean of x squared: the lever arm is L / sqrt(3), whatever the field's width.
TEST(ScanMatcher, LeverArmOfWallsBesideThePose)
{
  EXPECT_NEAR(line_map_merging::matchLeverArm(Eigen::Vector3d(4.0, 1.0, 4.0 * 2.5 * 2.5).asDiagonal()), 2.5,
              1e-12);
  EXPECT_EQ(line_map_merging::matchLeverArm(Eigen::Matrix3d::Zero()), 0.0);
  for (double length : {1.5, 6.0})
  {
    std::vector<Vec2> map, points;
    for (double x = -1.0; x <= length + 1.0; x += 0.01)
    {
      map.push_back({x, 0.0});
      map.push_back({x, 2.0});
    }
    for (double x = 0.0; x <= length; x += 0.02)
    {
      points.push_back({x, -1.0});
      points.push_back({x, 1.0});
    }
    const LikelihoodGrid field(map, 0.025, 0.04, 0.5);
    const Pose2 truth(0.0, 1.0, 0.0);
    const auto match = refineMatch(field, points, truth, truth, RefinementParams{2.0, 2.0, 30});
    EXPECT_NEAR(line_map_merging::matchLeverArm(match.curvature), length / std::sqrt(3.0), 0.1 * length)
        << length;
  }
}
