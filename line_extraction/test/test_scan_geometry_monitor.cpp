// The scan geometry monitor against hand-computed geometries: angle_max is checked against
// angle_min + (n - 1) * angle_increment within about one increment, and a change of angle_min,
// increment or beam count from one scan to the next is counted, the first scan being no change.
#include <gtest/gtest.h>

#include "line_extraction/scan_geometry_monitor.hpp"

using line_extraction::ScanGeometryMonitor;

TEST(ScanGeometryMonitor, AngleMaxWithinOneIncrementIsConsistent)
{
  ScanGeometryMonitor monitor;
  // 181 beams of 0.01 rad from -0.9: angle_max = -0.9 + 180 * 0.01 = 0.9.
  auto found = monitor.observe(-0.9f, 0.9f, 0.01f, 181);
  EXPECT_FALSE(found.inconsistent_angle_max);
  EXPECT_NEAR(found.expected_angle_max, 0.9, 1e-6);
  // A driver writing angle_min + n * increment (0.91) is tolerated.
  EXPECT_FALSE(monitor.observe(-0.9f, 0.91f, 0.01f, 181).inconsistent_angle_max);
  // Two increments off is not.
  found = monitor.observe(-0.9f, 0.92f, 0.01f, 181);
  EXPECT_TRUE(found.inconsistent_angle_max);
  EXPECT_NEAR(found.expected_angle_max, 0.9, 1e-6);
  EXPECT_EQ(monitor.inconsistentAngleMax(), 1u);
  EXPECT_EQ(monitor.changes(), 0u);
}

TEST(ScanGeometryMonitor, UnusableIncrementsAreNotJudgedHere)
{
  ScanGeometryMonitor monitor;
  EXPECT_FALSE(monitor.observe(0.0f, 5.0f, 0.0f, 100).inconsistent_angle_max);
  EXPECT_FALSE(monitor.observe(0.0f, 5.0f, -0.01f, 100).inconsistent_angle_max);
  EXPECT_FALSE(monitor.observe(0.0f, 5.0f, 0.01f, 1).inconsistent_angle_max);
  EXPECT_EQ(monitor.inconsistentAngleMax(), 0u);
}

TEST(ScanGeometryMonitor, ChangesAreCountedFromTheSecondScanOn)
{
  ScanGeometryMonitor monitor;
  EXPECT_FALSE(monitor.observe(-1.0f, 1.0f, 0.02f, 101).changed);  // the first scan
  EXPECT_FALSE(monitor.observe(-1.0f, 1.0f, 0.02f, 101).changed);
  EXPECT_TRUE(monitor.observe(-1.0f, 1.0f, 0.02f, 100).changed);   // count
  EXPECT_TRUE(monitor.observe(-1.0f, 1.0f, 0.01f, 100).changed);   // increment
  EXPECT_TRUE(monitor.observe(-0.5f, 1.0f, 0.01f, 100).changed);   // angle_min
  EXPECT_FALSE(monitor.observe(-0.5f, 2.0f, 0.01f, 100).changed);  // angle_max is no part of it
  EXPECT_EQ(monitor.changes(), 3u);
}
