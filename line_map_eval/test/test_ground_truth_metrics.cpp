// Coverage, endpoint error and vertex accuracy against true walls, on a hand-made case.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "line_map_eval/ground_truth_metrics.hpp"

using line_map_eval::evaluateAgainstGroundTruth;
using line_map_eval::findCorners;
using line_map_eval::GroundTruthParams;
using line_map_eval::GroundTruthResult;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
GroundTruthParams defaults()
{
  GroundTruthParams p;
  p.coverage_tolerance = 0.05;
  p.sample_spacing = 0.01;
  p.association_angle = 10.0 * linemap::kPi / 180.0;
  p.association_distance = 0.2;
  p.corner_tolerance = 0.01;
  p.corner_min_angle = 20.0 * linemap::kPi / 180.0;
  p.vertex_radius = 0.3;
  return p;
}

// A: 4 m along x, B: 3 m up from A's end (corner at (4, 0)), C and D: two collinear walls far away.
const std::vector<Segment2> kWalls = {Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(4, 0), Vec2(4, 3)),
                                      Segment2(Vec2(10, 0), Vec2(12, 0)), Segment2(Vec2(12, 0), Vec2(14, 0))};
}  // namespace

TEST(GroundTruthMetrics, CornersAreWhereNonParallelWallsMeet)
{
  const std::vector<Vec2> corners = findCorners(kWalls, defaults());
  ASSERT_EQ(corners.size(), 1u);  // C meets D straight on: no corner
  EXPECT_NEAR(corners[0].x(), 4.0, 1e-12);
  EXPECT_NEAR(corners[0].y(), 0.0, 1e-12);
  // Three walls through one point are one corner.
  std::vector<Segment2> three = kWalls;
  three.push_back(Segment2(Vec2(4, 0), Vec2(6, 2)));
  EXPECT_EQ(findCorners(three, defaults()).size(), 1u);
}

TEST(GroundTruthMetrics, HandMadeCase)
{
  const std::vector<Segment2> map = {
      Segment2(Vec2(0, 0.02), Vec2(3, 0.02)),      // M1 on A, 2 cm off, stops 1 m short
      Segment2(Vec2(4.03, 0.105), Vec2(4.03, 3)),  // M2 on B, 3 cm off, starts 10.5 cm up
      Segment2(Vec2(3.5, -0.1), Vec2(3.9, -0.1)),  // M3 parallel to A, 10 cm off: covers nothing
  };
  const GroundTruthResult r = evaluateAgainstGroundTruth(kWalls, map, defaults());
  ASSERT_EQ(r.walls.size(), 4u);

  // A: samples x = 0, 0.01, ..., 4 (401); within 5 cm of M1 while x <= 3 + sqrt(0.05^2 - 0.02^2)
  // = 3.0458, i.e. x = 0 .. 3.04: 305 samples. M3 is 10 cm away everywhere.
  EXPECT_EQ(r.walls[0].associated, 2u);
  EXPECT_NEAR(r.walls[0].coverage, 305.0 / 401.0, 1e-12);
  // Start (0, 0): 2 cm to M1's start; end (4, 0): nearest is M3's end (3.9, -0.1) at 0.1 sqrt(2).
  EXPECT_NEAR(r.walls[0].endpoint_error, 0.1 * std::sqrt(2.0), 1e-12);

  // B: samples y = 0 .. 3 (301); within 5 cm of M2 when 0.105 - y <= 0.04, i.e. y >= 0.07: 294.
  EXPECT_EQ(r.walls[1].associated, 1u);
  EXPECT_NEAR(r.walls[1].coverage, 294.0 / 301.0, 1e-12);
  EXPECT_NEAR(r.walls[1].endpoint_error, std::hypot(0.03, 0.105), 1e-12);

  EXPECT_EQ(r.walls[2].associated, 0u);
  EXPECT_EQ(r.walls[2].coverage, 0.0);
  EXPECT_TRUE(std::isinf(r.walls[2].endpoint_error));
  EXPECT_EQ(r.undetected_walls, 2u);
  EXPECT_NEAR(r.max_endpoint_error, 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.coverage, (4.0 * 305.0 / 401.0 + 3.0 * 294.0 / 301.0) / 11.0, 1e-12);

  // Corner (4, 0): M2's start (0.1092 m) and M3's end (0.1414 m) lie within 0.3 m; M1's end is 1 m away.
  ASSERT_EQ(r.corners.size(), 1u);
  EXPECT_EQ(r.corners[0].endpoints, 2u);
  EXPECT_NEAR(r.corners[0].vertex_error, std::hypot(0.03, 0.105) + 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.mean_vertex_error, r.corners[0].vertex_error, 1e-12);
  EXPECT_EQ(r.missed_corners, 0u);
}

TEST(GroundTruthMetrics, PerfectMapAndEmptyMap)
{
  const std::vector<Segment2> walls(kWalls.begin(), kWalls.begin() + 2);
  const GroundTruthResult perfect = evaluateAgainstGroundTruth(walls, walls, defaults());
  EXPECT_DOUBLE_EQ(perfect.coverage, 1.0);
  EXPECT_DOUBLE_EQ(perfect.max_endpoint_error, 0.0);
  ASSERT_EQ(perfect.corners.size(), 1u);
  EXPECT_EQ(perfect.corners[0].endpoints, 2u);  // A's end and B's start, both exactly on the corner
  EXPECT_DOUBLE_EQ(perfect.corners[0].vertex_error, 0.0);

  const GroundTruthResult empty = evaluateAgainstGroundTruth(walls, {}, defaults());
  EXPECT_EQ(empty.coverage, 0.0);
  EXPECT_EQ(empty.undetected_walls, 2u);
  EXPECT_EQ(empty.missed_corners, 1u);
}

TEST(GroundTruthMetrics, BadInput)
{
  const std::vector<Segment2> zero = {Segment2(Vec2(1, 1), Vec2(1, 1))};
  EXPECT_THROW(evaluateAgainstGroundTruth(zero, {}, defaults()), std::invalid_argument);
  const std::vector<Segment2> nan = {Segment2(Vec2(0, 0), Vec2(std::nan(""), 1))};
  EXPECT_THROW(evaluateAgainstGroundTruth(kWalls, nan, defaults()), std::invalid_argument);
  linemap::ParamSet ps;
  ps.set("eval/gt_vertex_radius", "0");
  EXPECT_THROW(GroundTruthParams::fromParams(ps), linemap::ParameterError);
  ps.set("eval/gt_vertex_radius", "0.5");
  ps.set("eval/gt_association_angle_deg", "5");
  const GroundTruthParams p = GroundTruthParams::fromParams(ps);
  EXPECT_DOUBLE_EQ(p.vertex_radius, 0.5);
  EXPECT_NEAR(p.association_angle, 5.0 * linemap::kPi / 180.0, 1e-15);
}
