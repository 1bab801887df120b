// Collinear merge: one wall cut in two is joined, two parallel walls stay apart.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "line_extraction/collinear_merge.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
// Points (x, y(x)) for x from x0 in steps dx, with Gaussian noise in y.
void addPoints(PreparedScan& s, double x0, double dx, int n, double y, double sigma, std::mt19937& rng)
{
  std::normal_distribution<double> noise(0.0, sigma);
  for (int i = 0; i < n; ++i)
  {
    const Vec2 p(x0 + i * dx, y + noise(rng));
    s.points.push_back(p);
    s.ranges.push_back(p.norm());
    s.angles.push_back(std::atan2(p.y(), p.x()));
    s.beam_index.push_back(static_cast<int>(s.beam_index.size()));
  }
}

void fitAndAppend(const PreparedScan& s, PointRange r, ExtractionResult& out)
{
  appendSegment(s, fitLine(sumRange(s, r.begin, r.end), 0.01), r, out);
}
}  // namespace

TEST(CollinearMerge, JoinsTwoHalvesOfOneWall)
{
  std::mt19937 rng(5);
  PreparedScan scan;
  addPoints(scan, 2.0, -0.05, 80, 2.0, 0.01, rng);  // wall y = 2 from x = 2 to x = -1.95
  ExtractionResult in, out;
  fitAndAppend(scan, {0, 40}, in);
  fitAndAppend(scan, {40, 80}, in);
  CollinearMerger merger;
  merger.merge(scan, in, out, false);
  ASSERT_EQ(out.segments.size(), 1u);
  const Segment& s = out.segments[0];
  EXPECT_EQ(s.num_points, 80);
  EXPECT_EQ(s.index_end - s.index_begin, 80);
  EXPECT_NEAR(s.radius, 2.0, 0.005);
  EXPECT_NEAR(s.angle, kPi / 2, 0.01);
  EXPECT_NEAR(s.start.x(), 2.0, 0.01);
  EXPECT_NEAR(s.end.x(), -1.95, 0.01);
  // The merged covariance is that of the refit of all 80 points: smaller than either half's.
  EXPECT_LT(s.covariance(1, 1), in.segments[0].covariance(1, 1) * 0.5);
}

TEST(CollinearMerge, KeepsParallelWallsApart)
{
  std::mt19937 rng(6);
  PreparedScan scan;
  addPoints(scan, 2.0, -0.05, 40, 2.0, 0.01, rng);
  addPoints(scan, 0.0, -0.05, 40, 2.2, 0.01, rng);  // 0.2 m farther, continuing leftwards
  ExtractionResult in, out;
  fitAndAppend(scan, {0, 40}, in);
  fitAndAppend(scan, {40, 80}, in);
  CollinearMerger merger;
  merger.merge(scan, in, out, false);
  ASSERT_EQ(out.segments.size(), 2u);
  EXPECT_NEAR(out.segments[0].radius, 2.0, 0.01);
  EXPECT_NEAR(out.segments[1].radius, 2.2, 0.01);
}

TEST(CollinearMerge, MahalanobisComparesLinesThroughTheOrigin)
{
  // (0.001, a) and (0.001, a + pi) are parallel lines 2 mm apart on either side of
  // the origin: compared as (0.001, a) vs (-0.001, a) they differ by 2 mm, not by pi.
  Segment a, b;
  a.radius = 0.001;
  a.angle = 0.3;
  b.radius = 0.001;
  b.angle = 0.3 + kPi;
  a.covariance = b.covariance = Eigen::Matrix2d::Identity() * 1e-4;
  // As (-0.001, 0.3): radius difference 0.002, angle difference 0.
  EXPECT_NEAR(lineMahalanobis(a, b), 0.002 * 0.002 / 2e-4, 1e-9);
}

TEST(CollinearMerge, WrapJoinsLastIntoFirst)
{
  std::mt19937 rng(7);
  PreparedScan scan;
  addPoints(scan, 0.0, 0.05, 30, 2.0, 0.005, rng);    // wall y = 2, x from 0 rightwards
  addPoints(scan, -1.5, 0.05, 30, -2.0, 0.005, rng);  // wall y = -2 in between
  addPoints(scan, -1.5, 0.05, 30, 2.0, 0.005, rng);   // wall y = 2 again, x from -1.5 to -0.05
  ExtractionResult in, out;
  fitAndAppend(scan, {0, 30}, in);
  fitAndAppend(scan, {30, 60}, in);
  fitAndAppend(scan, {60, 90}, in);
  CollinearMergeParams params;
  CollinearMerger merger(params);
  merger.merge(scan, in, out, true);
  ASSERT_EQ(out.segments.size(), 2u);
  EXPECT_EQ(out.segments[0].num_points, 60);
  EXPECT_NEAR(out.segments[0].radius, 2.0, 0.005);
  // Starts at the last segment's first point, ends at the first segment's last.
  EXPECT_NEAR(out.segments[0].start.x(), -1.5, 0.01);
  EXPECT_NEAR(out.segments[0].end.x(), 1.45, 0.01);
  EXPECT_EQ(out.segments[1].num_points, 30);
}

TEST(CollinearMerge, GapLimitKeepsADoorwayOpen)
{
  // One wall y = 2 with a 1 m doorway between x = 0 and x = -1.
  std::mt19937 rng(8);
  PreparedScan scan;
  addPoints(scan, 2.0, -0.05, 41, 2.0, 0.005, rng);   // x from 2 to 0
  addPoints(scan, -1.0, -0.05, 41, 2.0, 0.005, rng);  // x from -1 to -3
  ExtractionResult in;
  fitAndAppend(scan, {0, 41}, in);
  fitAndAppend(scan, {41, 82}, in);
  CollinearMergeParams params;
  params.max_gap = 0.5;
  CollinearMerger gated(params);
  ExtractionResult out;
  gated.merge(scan, in, out, false);
  EXPECT_EQ(out.segments.size(), 2u);
  params.max_gap = 1.5;
  CollinearMerger wide(params);
  out.clear();
  wide.merge(scan, in, out, false);
  EXPECT_EQ(out.segments.size(), 1u);
}
