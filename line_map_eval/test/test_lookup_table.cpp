// Gaussian lookup table: peak, symmetry, closed-form values and normalisation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "eval_test_helpers.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"

using line_map_eval::Cell;
using line_map_eval::LookupTable;
using line_map_eval::LookupTableParams;
using line_map_eval::test_helpers::lookupTableParams;
using linemap::Vec2;

TEST(LookupTable, IsolatedPointPeakSymmetryAndGaussianValues)
{
  // (1.025, 2.025) is the centre of global cell (20, 40) at 5 cm.
  const LookupTable t = LookupTable::build({Vec2(1.025, 2.025)}, lookupTableParams(0.05, 0.05));
  const Cell c{20, 40};
  EXPECT_EQ(t.cellOf(Vec2(1.025, 2.025)), c);
  EXPECT_FLOAT_EQ(t.at(c), 1.0f);
  EXPECT_EQ(t.occupiedCells(), 1u);
  for (int k = 1; k <= 3; ++k)
  {
    // d = k cells = k sigma: exp(-k^2 / 2).
    const float expected = static_cast<float>(std::exp(-0.5 * k * k));
    EXPECT_NEAR(t.at({c.x + k, c.y}), expected, 1e-6) << k;
    EXPECT_EQ(t.at({c.x + k, c.y}), t.at({c.x - k, c.y}));
    EXPECT_EQ(t.at({c.x, c.y + k}), t.at({c.x, c.y - k}));
    EXPECT_EQ(t.at({c.x + k, c.y}), t.at({c.x, c.y + k}));
  }
  EXPECT_NEAR(t.at({c.x + 1, c.y + 1}), std::exp(-1.0), 1e-6);
  EXPECT_NEAR(t.at({c.x - 2, c.y + 1}), std::exp(-2.5), 1e-6);
  // Truncation at 3 sigma: (3, 1) cells is sqrt(10) sigma away, (4, 0) four sigma.
  EXPECT_EQ(t.at({c.x + 3, c.y + 1}), 0.0f);
  EXPECT_EQ(t.at({c.x + 4, c.y}), 0.0f);
  EXPECT_EQ(t.at({c.x + 1000, c.y}), 0.0f);  // outside the window
  for (const float v : t.values())
  {
    EXPECT_GE(v, 0.0f);
    EXPECT_LE(v, 1.0f);
  }
  EXPECT_NEAR(t.valueAt(Vec2(1.075, 2.025)), std::exp(-0.5), 1e-6);
}

TEST(LookupTable, WiderKernelFollowsExpOfDistance)
{
  // sigma = 2 cells: cell k away holds exp(-(0.05 k)^2 / (2 * 0.1^2)) = exp(-k^2 / 8).
  const LookupTable t = LookupTable::build({Vec2(-0.475, 0.325)}, lookupTableParams(0.05, 0.1));
  const Cell c = t.cellOf(Vec2(-0.475, 0.325));
  EXPECT_EQ(c, (Cell{-10, 6}));
  EXPECT_FLOAT_EQ(t.at(c), 1.0f);
  for (int k = 1; k <= 6; ++k) EXPECT_NEAR(t.at({c.x, c.y - k}), std::exp(-k * k / 8.0), 1e-6) << k;
  EXPECT_EQ(t.at({c.x, c.y - 7}), 0.0f);
}

TEST(LookupTable, OverlappingKernelsTakeTheMaximumNotTheSum)
{
  // Two points two cells apart, many repeats: the cell between them holds exp(-1/2), not 2 exp(-1/2).
  std::vector<Vec2> pts;
  for (int i = 0; i < 50; ++i)
  {
    pts.emplace_back(0.025, 0.025);
    pts.emplace_back(0.125, 0.025);
  }
  const LookupTable t = LookupTable::build(pts, lookupTableParams(0.05, 0.05));
  EXPECT_EQ(t.occupiedCells(), 2u);
  EXPECT_FLOAT_EQ(t.at({0, 0}), 1.0f);
  EXPECT_FLOAT_EQ(t.at({2, 0}), 1.0f);
  EXPECT_NEAR(t.at({1, 0}), std::exp(-0.5), 1e-6);
  EXPECT_NEAR(t.at({3, 0}), std::exp(-0.5), 1e-6);
  for (const float v : t.values()) EXPECT_LE(v, 1.0f);
}

TEST(LookupTable, WindowCoversTheKernelAroundEveryPoint)
{
  const LookupTable t = LookupTable::build({Vec2(-3.0, 7.0), Vec2(12.0, -4.0)}, lookupTableParams(0.1, 0.1));
  for (const Vec2& p : {Vec2(-3.0, 7.0), Vec2(12.0, -4.0)})
  {
    const Cell c = t.cellOf(p);
    EXPECT_FLOAT_EQ(t.at(c), 1.0f);
    EXPECT_NEAR(t.at({c.x - 3, c.y}), std::exp(-4.5), 1e-6);
    EXPECT_NEAR(t.at({c.x + 3, c.y}), std::exp(-4.5), 1e-6);
    EXPECT_NEAR(t.at({c.x, c.y - 3}), std::exp(-4.5), 1e-6);
    EXPECT_NEAR(t.at({c.x, c.y + 3}), std::exp(-4.5), 1e-6);
  }
  EXPECT_EQ(t.width() * t.height(), static_cast<int>(t.values().size()));
}

TEST(LookupTable, EmptyInputAndBadInput)
{
  const LookupTable empty = LookupTable::build({}, lookupTableParams(0.05, 0.05));
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(empty.valueAt(Vec2(0.0, 0.0)), 0.0f);
  EXPECT_THROW(LookupTable::build({Vec2(0.0, std::numeric_limits<double>::quiet_NaN())},
                                  lookupTableParams(0.05, 0.05)),
               std::invalid_argument);
  try
  {
    LookupTable::build({Vec2(0, 0)}, lookupTableParams(-0.05, 0.05));
    FAIL() << "negative resolution accepted";
  }
  catch (const linemap::ParameterError& e)
  {
    EXPECT_NE(std::string(e.what()).find("eval/resolution"), std::string::npos) << e.what();
  }
  // 10 km square at 1 mm: far beyond 1e8 cells.
  EXPECT_THROW(LookupTable::build({Vec2(0, 0), Vec2(1e4, 1e4)}, lookupTableParams(0.001, 0.05)),
               linemap::ParameterError);
}

TEST(LookupTable, ParamsFromParamSet)
{
  linemap::ParamSet ps;
  ps.set("eval/resolution", "0.02");
  ps.set("eval/sigma", "0.04");
  const LookupTableParams p = LookupTableParams::fromParams(ps);
  EXPECT_DOUBLE_EQ(p.resolution, 0.02);
  EXPECT_DOUBLE_EQ(p.sigma, 0.04);
  EXPECT_DOUBLE_EQ(p.kernel_radius, 3.0);
  ps.set("eval/sigma", "wide");
  EXPECT_THROW(LookupTableParams::fromParams(ps), linemap::ParameterError);
  ps.set("eval/sigma", "0");
  EXPECT_THROW(LookupTableParams::fromParams(ps), linemap::ParameterError);
}

TEST(LookupTable, RegisteredPointsOfARecording)
{
  line_map_eval::Recording rec;
  rec.geometry.angle_min = 0.0;
  rec.geometry.angle_increment = linemap::kPi / 2;
  rec.geometry.beam_count = 3;
  rec.geometry.range_min = 0.1;
  rec.geometry.range_max = 10.0;
  rec.base_to_laser = linemap::Pose2(0.1, 0.0, 0.0);
  line_map_eval::RecordedScan scan;
  scan.ranges = {1.0f, 10.0f, 2.0f};  // the middle beam is "no return"
  rec.scans = {scan, scan};
  rec.keyframes = {{1, linemap::Pose2(1.0, 2.0, linemap::kPi / 2)}};
  const std::vector<Vec2> pts = line_map_eval::registeredScanPoints(rec);
  ASSERT_EQ(pts.size(), 2u);
  // Laser at (1, 2.1) facing +y: beam 0 (along laser x) 1 m -> (1, 3.1); beam 2 (laser -x) 2 m -> (1, 0.1).
  EXPECT_NEAR(pts[0].x(), 1.0, 1e-12);
  EXPECT_NEAR(pts[0].y(), 3.1, 1e-12);
  EXPECT_NEAR(pts[1].x(), 1.0, 1e-12);
  EXPECT_NEAR(pts[1].y(), 0.1, 1e-12);
  rec.keyframes = {{5, linemap::Pose2()}};
  EXPECT_THROW(line_map_eval::registeredScanPoints(rec), std::invalid_argument);
}
