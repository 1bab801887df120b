// Seeded region growing and its point gap: a stretch of a wall without readings wider than max_gap
// (0.3 m) splits it into two segments, and neither takes a point from the other side of the gap
// (the overlap resolution used to hand the first point of a touching collinear neighbour over).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "synthetic_scans.hpp"

using namespace line_extraction;
using linemap::kPi;

namespace
{
constexpr double kDeg = kPi / 180.0;

/// Ranges of beams from angle_min in steps of `increment` hitting the wall y = 1 (laser at the
/// origin, noiseless); beams whose angle lies in [gap_from, gap_to] return NaN (no reading).
std::vector<float> wallRanges(double angle_min, double increment, int beams, double gap_from = 1.0,
                              double gap_to = 0.0)
{
  std::vector<float> r(beams);
  for (int i = 0; i < beams; ++i)
  {
    const double a = angle_min + i * increment;
    r[i] = (a >= gap_from && a <= gap_to) ? std::numeric_limits<float>::quiet_NaN()
                                          : static_cast<float>(1.0 / std::sin(a));
  }
  return r;
}

const ExtractionResult& extractSrg(LineExtractor& extractor, const std::vector<float>& ranges,
                                   double angle_min, double increment)
{
  return extractor.extract(line_extraction_test::scanOf(ranges, angle_min, increment, 0.05, 30.0));
}

TEST(SeededRegionGrowing, DroppedReadingsWiderThanMaxGapSplitTheWall)
{
  // Beams 10 .. 80 degrees on y = 1, no readings between 30 and 50 degrees: the last hit before
  // is at x = 1/tan(29.5 deg) = 1.767 m, the first after at 1/tan(50.5 deg) = 0.824 m, 0.94 m apart.
  // Both parts are longer than min_length (3.9 m and 0.65 m) and have more than min_points hits.
  const double a0 = 10.0 * kDeg, inc = 0.5 * kDeg;
  const int beams = 141;
  const std::vector<float> ranges = wallRanges(a0, inc, beams, 29.9 * kDeg, 50.1 * kDeg);
  linemap::ParamSet params;
  params.set("merge", "false");  // the pipeline's collinear merge would bridge 0.94 m (merge_max_gap)
  LineExtractor extractor(params);
  const ExtractionResult& r = extractSrg(extractor, ranges, a0, inc);
  ASSERT_EQ(r.segments.size(), 2u);
  for (const Segment& s : r.segments)
  {
    EXPECT_NEAR(s.radius, 1.0, 1e-6);
    // Neither segment spans the unobserved stretch between x = 0.824 and 1.767 m.
    const double lo = std::min(s.start.x(), s.end.x()), hi = std::max(s.start.x(), s.end.x());
    const double before = 1.0 / std::tan(29.5 * kDeg), after = 1.0 / std::tan(50.5 * kDeg);
    EXPECT_TRUE(hi <= after + 1e-5 || lo >= before - 1e-5) << "segment from x " << lo << " to " << hi;
  }
}

}  // namespace
