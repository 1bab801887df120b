// Once warmed up on a scan geometry, the pipeline and this package's extractors do
// not touch the heap: operator new is counted while extracting.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "line_extraction/line_extractor.hpp"
#include "synthetic_scans.hpp"

namespace
{
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size)
{
  if (counting) ++allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept
{
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept
{
  std::free(p);
}

using namespace line_extraction;
using linemap::kPi;

TEST(Allocation, NoHeapUseAfterWarmUp)
{
  // 180-beam scans of a room from several poses, with noise and invalid beams.
  std::vector<std::vector<float>> scans;
  for (int k = 0; k < 20; ++k)
  {
    scans.push_back(line_extraction_test::squareRoomRanges(4.0, -2 + 0.2 * k, 1.5 - 0.15 * k, 0.3 * k, 180,
                                                           -kPi / 2, kPi / 180, 0.01, k + 1));
    for (int i = k; i < 180; i += 17) scans.back()[i] = std::nanf("");
  }
  for (const char* name : {"srg", "split_merge", "iepf", "smsm", "incremental", "line_regression"})
  {
    for (const char* clustering : {"false", "true"})
    {
      SCOPED_TRACE(std::string(name) + " clustering " + clustering);
      linemap::ParamSet params;
      params.set("algorithm", name);
      params.set("clustering", clustering);
      params.set("remove_isolated", clustering);  // both optional stages in the second run
      LineExtractor extractor(params);
      ScanInput scan;
      scan.count = 180;
      scan.angle_min = -kPi / 2;
      scan.angle_increment = kPi / 180;
      scan.range_min = 0.05;
      scan.range_max = 30.0;
      std::size_t segments = 0;
      // The first pass sizes the buffers: the counter must see that.
      allocations = 0;
      counting = true;
      for (const auto& r : scans)
      {
        scan.ranges = r.data();
        extractor.extract(scan);
      }
      counting = false;
      EXPECT_GT(allocations.load(), 0);
      allocations = 0;
      counting = true;
      for (const auto& r : scans)
      {
        scan.ranges = r.data();
        segments += extractor.extract(scan).segments.size();
      }
      counting = false;
      EXPECT_EQ(allocations.load(), 0);
      EXPECT_GT(segments, 40u);  // the walls were found, so the hot path ran
    }
  }
}
