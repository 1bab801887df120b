// Total-least-squares fit and its covariance against closed forms and Monte Carlo.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "line_extraction/line_fit.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
Vec2 onLine(double angle, double radius, double t, double offset = 0.0)
{
  const Vec2 n(std::cos(angle), std::sin(angle)), u(-std::sin(angle), std::cos(angle));
  return (radius + offset) * n + t * u;
}

PreparedScan scanOf(const std::vector<Vec2>& pts)
{
  PreparedScan s;
  for (const Vec2& p : pts)
  {
    s.points.push_back(p);
    s.ranges.push_back(p.norm());
    s.angles.push_back(std::atan2(p.y(), p.x()));
    s.beam_index.push_back(static_cast<int>(s.beam_index.size()));
  }
  return s;
}
}  // namespace

TEST(LineFit, PointsSymmetricAboutLineGiveExactLine)
{
  const double angle = 0.7, radius = 2.0, d = 0.05;
  LineSums sums;
  for (int k = -2; k <= 2; ++k)
  {
    sums.add(onLine(angle, radius, k, d));
    sums.add(onLine(angle, radius, k, -d));
  }
  const LineFit fit = fitLine(sums, 0.01);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.angle, angle, 1e-12);
  EXPECT_NEAR(fit.radius, radius, 1e-12);
  EXPECT_NEAR(fit.sum_squared_residuals, 10 * d * d, 1e-12);
}

TEST(LineFit, RadiusIsNonNegativeAndAngleWraps)
{
  // The line y = -2: normal points down, angle -pi/2.
  LineSums sums;
  for (double x : {-1.0, 0.0, 2.0, 3.5}) sums.add(Vec2(x, -2.0));
  const LineFit fit = fitLine(sums, 0.01);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.radius, 2.0, 1e-12);
  EXPECT_NEAR(fit.angle, -kPi / 2, 1e-12);
  // The line x = -3: angle pi.
  sums.clear();
  for (double y : {-1.0, 0.5, 2.0}) sums.add(Vec2(-3.0, y));
  const LineFit f2 = fitLine(sums, 0.01);
  EXPECT_NEAR(f2.radius, 3.0, 1e-12);
  EXPECT_NEAR(std::abs(f2.angle), kPi, 1e-12);
}

TEST(LineFit, DegenerateInputsAreInvalid)
{
  LineSums sums;
  EXPECT_FALSE(fitLine(sums, 0.01).valid);
  sums.add(Vec2(1, 1));
  EXPECT_FALSE(fitLine(sums, 0.01).valid);
  sums.add(Vec2(1, 1));
  EXPECT_FALSE(fitLine(sums, 0.01).valid);
  LineNormal n;
  EXPECT_FALSE(fitNormal(sums, n));
}

TEST(LineFit, CovarianceMatchesHandComputation)
{
  // Points (1,0), (1,1), (1,2) on x = 1: angle 0, t = y, mean t = 1, sum (t - mean)^2 = 2.
  // sigma = 0.1: var(a) = 0.01/2, var(r) = 0.01/3 + 1 * 0.005, cov = 1 * 0.005.
  LineSums sums;
  sums.add(Vec2(1, 0));
  sums.add(Vec2(1, 1));
  sums.add(Vec2(1, 2));
  const LineFit fit = fitLine(sums, 0.1);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.angle, 0.0, 1e-12);
  EXPECT_NEAR(fit.radius, 1.0, 1e-12);
  EXPECT_NEAR(fit.covariance(1, 1), 0.005, 1e-12);
  EXPECT_NEAR(fit.covariance(0, 0), 0.01 / 3.0 + 0.005, 1e-12);
  EXPECT_NEAR(fit.covariance(0, 1), 0.005, 1e-12);
  EXPECT_NEAR(fit.covariance(1, 0), 0.005, 1e-12);
}

TEST(LineFit, CovarianceMatchesMonteCarloSpread)
{
  const double angle = 0.5, radius = 3.0, sigma = 0.02;
  const int n = 20, trials = 20000;
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<Vec2> exact;
  for (int i = 0; i < n; ++i) exact.push_back(onLine(angle, radius, 1.0 + 3.0 * i / (n - 1)));
  LineSums exact_sums;
  for (const Vec2& p : exact) exact_sums.add(p);
  const Eigen::Matrix2d predicted = fitLine(exact_sums, sigma).covariance;

  double mr = 0, ma = 0, srr = 0, saa = 0, sra = 0;
  for (int k = 0; k < trials; ++k)
  {
    LineSums s;
    for (const Vec2& p : exact) s.add(p + Vec2(noise(rng), noise(rng)));
    const LineFit f = fitLine(s, sigma);
    const double dr = f.radius - radius, da = linemap::normalizeAngle(f.angle - angle);
    mr += dr;
    ma += da;
    srr += dr * dr;
    saa += da * da;
    sra += dr * da;
  }
  mr /= trials;
  ma /= trials;
  const double vr = srr / trials - mr * mr, va = saa / trials - ma * ma, cra = sra / trials - mr * ma;
  EXPECT_NEAR(vr / predicted(0, 0), 1.0, 0.1);
  EXPECT_NEAR(va / predicted(1, 1), 1.0, 0.1);
  EXPECT_NEAR(cra / predicted(0, 1), 1.0, 0.1);
  EXPECT_GT(predicted(0, 1), 0.0);  // mean t = 2.5 > 0
}

TEST(LineFit, FitNormalAgreesWithFitLine)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ang(-kPi, kPi), rad(0.1, 10.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int k = 0; k < 200; ++k)
  {
    const double a = ang(rng), r = rad(rng);
    LineSums s;
    for (int i = 0; i < 10; ++i) s.add(onLine(a, r, -1.0 + 0.3 * i, noise(rng)));
    const LineFit f = fitLine(s, 0.01);
    LineNormal n;
    ASSERT_TRUE(fitNormal(s, n));
    EXPECT_NEAR(n.nx, std::cos(f.angle), 1e-9);
    EXPECT_NEAR(n.ny, std::sin(f.angle), 1e-9);
    EXPECT_NEAR(n.radius, f.radius, 1e-9);
  }
}

TEST(LineFit, AppendSegmentProjectsEndpoints)
{
  // Points symmetric about y = 1 (no trend); endpoints are the first and
  // last member projected onto the fitted line y = 1.
  const PreparedScan scan = scanOf({{0.0, 1.1}, {1.0, 0.9}, {2.0, 0.9}, {3.0, 1.1}});
  const LineFit fit = fitLine(sumRange(scan, 0, 4), 0.01);
  ASSERT_NEAR(fit.radius, 1.0, 1e-12);
  ExtractionResult out;
  appendSegment(scan, fit, PointRange{0, 4}, out);
  const int members[] = {1, 2};
  appendSegment(scan, fit, members, 2, out);
  ASSERT_EQ(out.segments.size(), 2u);
  EXPECT_NEAR((out.segments[0].start - Vec2(0.0, 1.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((out.segments[0].end - Vec2(3.0, 1.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(out.segments[0].num_points, 4);
  EXPECT_NEAR((out.segments[1].start - Vec2(1.0, 1.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(out.segments[1].index_begin, 4);
  EXPECT_EQ(out.segments[1].index_end, 6);
  EXPECT_EQ(out.point_indices[4], 1);
}

TEST(LineFit, PrefixSumsMatchDirectSums)
{
  std::vector<Vec2> pts;
  for (int i = 0; i < 30; ++i) pts.emplace_back(0.1 * i * i, std::sin(0.3 * i));
  const PreparedScan scan = scanOf(pts);
  PrefixSums prefix;
  prefix.build(scan, {5, 30});
  const LineSums a = prefix.sums(7, 21), b = sumRange(scan, 7, 21);
  EXPECT_DOUBLE_EQ(a.n, 14.0);
  EXPECT_NEAR(a.sxx, b.sxx, 1e-9);
  EXPECT_NEAR(a.sxy, b.sxy, 1e-9);
  EXPECT_NEAR(a.sy, b.sy, 1e-9);
}

TEST(LineFit, ResolveOverlapsSplitsAtTheCorner)
{
  // Wall x = 2 (points 0..9), then wall y = 2 (points 10..19); corner at (2, 2).
  std::vector<Vec2> pts;
  for (int i = 0; i < 10; ++i) pts.emplace_back(2.0, -1.0 + 0.3 * i);
  for (int i = 0; i < 10; ++i) pts.emplace_back(1.9 - 0.3 * i, 2.0);
  const PreparedScan scan = scanOf(pts);
  std::vector<PointRange> segs{{0, 13}, {7, 20}};
  resolveOverlaps(scan, segs);
  EXPECT_EQ(segs[0].begin, 0);
  EXPECT_EQ(segs[0].end, 10);
  EXPECT_EQ(segs[1].begin, 10);
  EXPECT_EQ(segs[1].end, 20);
}
