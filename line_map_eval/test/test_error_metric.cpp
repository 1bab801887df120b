// Error metric e, provenance by the fusion conditions, and the map statistics (Table III).
#include <gtest/gtest.h>

#include <cmath>

#include "line_map_eval/metrics/error_metric.hpp"
#include "line_map_eval/metrics/map_statistics.hpp"

using line_map_eval::assignToMapSegments;
using line_map_eval::computeErrorMetric;
using line_map_eval::computeMapStatistics;
using line_map_eval::ErrorMetricResult;
using line_map_eval::MapStatistics;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
const std::vector<Segment2> kMap = {Segment2(Vec2(0, 0), Vec2(10, 0)), Segment2(Vec2(0, 5), Vec2(0, 10))};
}

TEST(ErrorMetric, MeanOfMidpointDistancesToTheFinalLines)
{
  const std::vector<Segment2> originals = {
      Segment2(Vec2(1, 0.1), Vec2(3, 0.1)),    // midpoint (2, 0.1): 0.1
      Segment2(Vec2(4, -0.3), Vec2(6, -0.1)),  // midpoint (5, -0.2): 0.2 (the tilt does not matter)
      Segment2(Vec2(0.3, 6), Vec2(0.3, 8)),    // to x = 0: 0.3
      Segment2(Vec2(12, 0.4), Vec2(14, 0.4)),  // beyond the segment's end: 0.4 to its LINE
      Segment2(Vec2(50, 50), Vec2(51, 50)),    // not merged
  };
  const ErrorMetricResult r = computeErrorMetric(originals, {0, 0, 1, 0, -1}, kMap);
  EXPECT_EQ(r.assigned, 4u);
  EXPECT_EQ(r.unassigned, 1u);
  EXPECT_NEAR(r.mean_error, (0.1 + 0.2 + 0.3 + 0.4) / 4.0, 1e-12);
  EXPECT_NEAR(r.max_error, 0.4, 1e-12);
}

TEST(ErrorMetric, BadProvenanceIsRejected)
{
  const std::vector<Segment2> originals = {Segment2(Vec2(1, 0), Vec2(2, 0))};
  EXPECT_THROW(computeErrorMetric(originals, {}, kMap), std::invalid_argument);
  try
  {
    computeErrorMetric(originals, {2}, kMap);
    FAIL() << "index 2 of a two-segment map accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("original segment 0"), std::string::npos) << e.what();
  }
  const ErrorMetricResult none = computeErrorMetric({}, {}, kMap);
  EXPECT_EQ(none.assigned, 0u);
  EXPECT_EQ(none.mean_error, 0.0);
}

TEST(ErrorMetric, AssignmentByTheFusionConditions)
{
  std::vector<Segment2> map = kMap;
  map.push_back(Segment2(Vec2(0, 0.08), Vec2(10, 0.08)));  // a second, parallel line 8 cm up
  line_map_merging::FusionParams fp;
  fp.max_angle = 4.0 * linemap::kPi / 180.0;
  fp.max_distance = 0.1;
  fp.min_overlap = 0.0;
  const std::vector<Segment2> originals = {
      Segment2(Vec2(1, 0.01), Vec2(3, 0.01)),    // 1 cm from map 0, 7 cm from map 2: map 0
      Segment2(Vec2(1, 0.06), Vec2(3, 0.06)),    // 6 cm from map 0, 2 cm from map 2: map 2
      Segment2(Vec2(0.02, 6), Vec2(0.02, 9)),    // along map 1
      Segment2(Vec2(2, 0.5), Vec2(4, 0.5)),      // too far from every line
      Segment2(Vec2(5, -1), Vec2(5, 1)),         // crosses map 0 at 90 degrees
      Segment2(Vec2(11, 0.01), Vec2(12, 0.01)),  // on map 0's line but 1 m past its end
  };
  const std::vector<int> a = assignToMapSegments(originals, map, fp);
  ASSERT_EQ(a.size(), originals.size());
  EXPECT_EQ(a[0], 0);
  EXPECT_EQ(a[1], 2);
  EXPECT_EQ(a[2], 1);
  EXPECT_EQ(a[3], -1);
  EXPECT_EQ(a[4], -1);
  EXPECT_EQ(a[5], -1);
  const ErrorMetricResult r = computeErrorMetric(originals, a, map);
  EXPECT_EQ(r.assigned, 3u);
  EXPECT_NEAR(r.mean_error, (0.01 + 0.02 + 0.02) / 3.0, 1e-12);
}

TEST(MapStatistics, LengthsAndReductionRateByHand)
{
  const std::vector<Segment2> map = {Segment2(Vec2(0, 0), Vec2(3, 4)),        // 5
                                     Segment2(Vec2(1, 1), Vec2(1, 3)),        // 2
                                     Segment2(Vec2(-2, 0), Vec2(6, 0)),       // 8
                                     Segment2(Vec2(0, 0), Vec2(-0.6, 0.8))};  // 1
  const MapStatistics s = computeMapStatistics(map, 40);
  EXPECT_EQ(s.segment_count, 4u);
  EXPECT_EQ(s.original_count, 40u);
  EXPECT_NEAR(s.shortest_length, 1.0, 1e-12);
  EXPECT_NEAR(s.longest_length, 8.0, 1e-12);
  EXPECT_NEAR(s.mean_length, 4.0, 1e-12);
  EXPECT_NEAR(s.total_length, 16.0, 1e-12);
  EXPECT_NEAR(s.reduction_rate, 0.1, 1e-12);

  const MapStatistics empty = computeMapStatistics({}, 0);
  EXPECT_EQ(empty.segment_count, 0u);
  EXPECT_EQ(empty.shortest_length, 0.0);
  EXPECT_EQ(empty.reduction_rate, 0.0);
}
