#include <gtest/gtest.h>

#include <cmath>

#include "linemap/small_helpers.hpp"
#include "linemap/time_jump_detector.hpp"

using linemap::TimeJumpDetector;

TEST(TimeJumpDetector, StampsGoingBackWithinToleranceAreNotAJump)
{
  TimeJumpDetector d(1.0);
  EXPECT_FALSE(d.observe(0.0, 100.0));
  EXPECT_FALSE(d.observe(0.0, 99.2));  // 0.8 s back: reordering, not a restart
  EXPECT_DOUBLE_EQ(d.lastStamp(), 100.0);
  EXPECT_TRUE(d.observe(0.0, 98.5));  // 1.5 s before the newest
  EXPECT_EQ(d.jumps(), 1u);
  EXPECT_DOUBLE_EQ(d.lastStamp(), 98.5);  // starts afresh from the jump
  EXPECT_FALSE(d.observe(0.0, 98.6));
}

TEST(TimeJumpDetector, ClockGoingBackIsAJumpAndNamesTheClock)
{
  TimeJumpDetector d(1.0);
  EXPECT_FALSE(d.observe(50.0, 0.0));
  EXPECT_TRUE(d.observe(10.0, 0.0));
  EXPECT_NE(d.cause().find("clock"), std::string::npos);
  EXPECT_FALSE(d.observe(std::nan(""), std::nan("")));  // unknown readings never jump
}

TEST(TimeJumpDetector, StreamsAreComparedEachWithItself)
{
  TimeJumpDetector d(1.0, {"scan", "segment set"});
  EXPECT_FALSE(d.observe(0.0, 200.0, 0));
  EXPECT_FALSE(d.observe(0.0, 150.0, 1));  // another stream may lag behind
  EXPECT_DOUBLE_EQ(d.newestStamp(), 200.0);
  EXPECT_TRUE(d.observe(0.0, 140.0, 1));
  EXPECT_NE(d.cause().find("segment set"), std::string::npos);
  EXPECT_DOUBLE_EQ(d.lastStamp(0), 0.0);  // a jump on one stream restarts all
}

TEST(SmallHelpers, MedianAndBaseName)
{
  EXPECT_DOUBLE_EQ(linemap::median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(linemap::median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_TRUE(std::isnan(linemap::median({})));
  EXPECT_EQ(linemap::baseName("/a/b/intel.clf"), "intel.clf");
  EXPECT_EQ(linemap::baseName("intel.clf"), "intel.clf");
  EXPECT_EQ(linemap::fileStem("/logs/intel.clf.bz2"), "intel");
  EXPECT_EQ(linemap::fileStem("/worlds/.hidden"), ".hidden");
}

TEST(SmallHelpers, ToNumberTakesOnlyAWholeNumberInRange)
{
  EXPECT_DOUBLE_EQ(*linemap::toNumber("0.25"), 0.25);
  EXPECT_DOUBLE_EQ(*linemap::toNumber("-3e2"), -300.0);
  EXPECT_TRUE(std::isinf(*linemap::toNumber("inf")));
  for (const char* bad : {"", "x", "1.5m", "0.5 ", "1e999", "--1"})
    EXPECT_FALSE(linemap::toNumber(bad).has_value()) << "'" << bad << "'";
}
