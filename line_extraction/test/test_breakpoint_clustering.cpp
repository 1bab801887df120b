// Adaptive breakpoint detector against hand-computed split positions.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "line_extraction/breakpoint_clustering.hpp"
#include "line_extraction/preprocess.hpp"
#include "synthetic_scans.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
PreparedScan prepare(const std::vector<float>& r, double angle_min, double inc)
{
  return line_extraction_test::prepared(r, angle_min, inc);
}
}  // namespace

TEST(BreakpointClustering, SplitsAtJumpsAndDropsSmallClusters)
{
  // Beams 0..29 at 2 m, beam 30 alone at 3 m, beams 31..59 at 4 m (1 degree apart):
  // neighbours on an arc are 3.5 cm apart, far below r sin(1)/sin(9) + 3 sigma = 25 cm;
  // the jumps are 1 m.
  std::vector<float> r(60, 4.0f);
  for (int i = 0; i < 30; ++i) r[i] = 2.0f;
  r[30] = 3.0f;
  const PreparedScan scan = prepare(r, 0.0, kPi / 180);
  BreakpointParams params;  // lambda 10 deg, sigma 1 cm, min 3 points
  std::vector<PointRange> clusters;
  breakpointClusters(scan, {0, 60}, params, clusters);
  ASSERT_EQ(clusters.size(), 2u);
  EXPECT_EQ(clusters[0].begin, 0);
  EXPECT_EQ(clusters[0].end, 30);
  EXPECT_EQ(clusters[1].begin, 31);
  EXPECT_EQ(clusters[1].end, 60);
  params.min_points = 1;
  clusters.clear();
  breakpointClusters(scan, {0, 60}, params, clusters);
  EXPECT_EQ(clusters.size(), 3u);
}

TEST(BreakpointClustering, GrazingWallBreaksWhereIncidenceDropsBelowLambda)
{
  // Wall x = 1 seen by beams at 0, 1, ..., 88 degrees. Beam i meets it at incidence
  // 90 - i degrees and lies r(i-1) sin(1 deg) / cos(i deg) from the previous point.
  // Threshold r(i-1) sin(1 deg) / sin(9 deg) + 0.03: at i = 81, cos 81 = sin 9 and the
  // 3 cm margin keeps the points together; at i = 82 the gap is 0.80 m against 0.74 m.
  std::vector<float> r(89);
  for (int i = 0; i < 89; ++i) r[i] = static_cast<float>(1.0 / std::cos(i * kPi / 180));
  const PreparedScan scan = prepare(r, 0.0, kPi / 180);
  std::vector<PointRange> clusters;
  breakpointClusters(scan, {0, 89}, BreakpointParams(), clusters);
  ASSERT_GE(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].begin, 0);
  EXPECT_EQ(clusters[0].end, 82);
  EXPECT_TRUE(isBreakpoint(scan, 82, BreakpointParams()));
  EXPECT_FALSE(isBreakpoint(scan, 81, BreakpointParams()));
}

TEST(BreakpointClustering, InvalidBeamsWiderThanLambdaBreak)
{
  // Two points on the same 2 m arc but 12 degrees apart (beams between invalid):
  // beyond the model's reach, so a breakpoint.
  std::vector<float> r(40, 2.0f);
  for (int i = 10; i < 21; ++i) r[i] = std::nanf("");
  const PreparedScan scan = prepare(r, 0.0, kPi / 180);
  std::vector<PointRange> clusters;
  breakpointClusters(scan, {0, static_cast<int>(scan.size())}, BreakpointParams(), clusters);
  ASSERT_EQ(clusters.size(), 2u);
  EXPECT_EQ(clusters[0].end, 10);
}
