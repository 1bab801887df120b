// libFuzzer target: scan preprocessing and every extractor of the pipeline on arbitrary scan
// geometry and ranges (NaN, inf, negative, huge values included). Unusable geometry must end in
// ScanError; everything else must give finite segments whose point indices stay in range.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "fuzz_check.hpp"
#include "line_extraction/extractor.hpp"
#include "line_extraction/line_extractor.hpp"
#include "linemap/params.hpp"

namespace
{
// Either a plausible value in [lo, hi] or any double (NaN, inf, denormals), so that both the
// validation and the algorithms behind it are reached.
double fuzzDouble(FuzzedDataProvider& in, double lo, double hi)
{
  if (in.ConsumeIntegralInRange<int>(0, 7) != 0) return in.ConsumeFloatingPointInRange<double>(lo, hi);
  const auto bits = in.ConsumeIntegral<std::uint64_t>();  // any bit pattern: NaN, inf, huge
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// Ranges: runs of a wall-like linear ramp (so the algorithms find lines) mixed with raw floats.
std::vector<float> fuzzRanges(FuzzedDataProvider& in)
{
  const std::size_t count = in.ConsumeIntegralInRange<std::size_t>(0, 1100);
  std::vector<float> ranges;
  ranges.reserve(count);
  while (ranges.size() < count && in.remaining_bytes() > 0)
  {
    const int kind = in.ConsumeIntegralInRange<int>(0, 3);
    const std::size_t run = in.ConsumeIntegralInRange<std::size_t>(1, 64);
    if (kind == 0)
    {
      for (std::size_t i = 0; i < run && ranges.size() < count; ++i)
      {
        const auto bits = in.ConsumeIntegral<std::uint32_t>();  // any bit pattern: NaN, inf, negative
        float v;
        std::memcpy(&v, &bits, sizeof v);
        ranges.push_back(v);
      }
    }
    else
    {
      const float start = in.ConsumeFloatingPointInRange<float>(0.0f, 40.0f);
      const float step = in.ConsumeFloatingPointInRange<float>(-0.2f, 0.2f);
      const float noise = kind == 3 ? in.ConsumeFloatingPointInRange<float>(0.0f, 0.05f) : 0.0f;
      for (std::size_t i = 0; i < run && ranges.size() < count; ++i)
        ranges.push_back(start + step * static_cast<float>(i) + ((i % 2) ? noise : -noise));
    }
  }
  return ranges;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  FuzzedDataProvider in(data, size);
  const auto& names = line_extraction::extractorNames();
  linemap::ParamSet params;
  params.set("algorithm", names[in.ConsumeIntegralInRange<std::size_t>(0, names.size() - 1)]);
  params.set("clustering", in.ConsumeBool() ? "true" : "false");
  params.set("remove_isolated", in.ConsumeBool() ? "true" : "false");
  params.set("merge", in.ConsumeBool() ? "true" : "false");
  params.set("min_points", std::to_string(in.ConsumeIntegralInRange<int>(2, 8)));

  line_extraction::ScanInput scan;
  scan.angle_min = fuzzDouble(in, -M_PI, M_PI);
  scan.angle_increment = fuzzDouble(in, 1e-4, 0.1);
  scan.range_min = fuzzDouble(in, 0.0, 1.0);
  scan.range_max = fuzzDouble(in, 0.5, 100.0);
  const bool with_intensities = in.ConsumeIntegralInRange<int>(0, 15) == 0;

  std::vector<float> ranges = fuzzRanges(in);
  scan.ranges = ranges.empty() ? nullptr : ranges.data();
  scan.count = ranges.size();
  std::vector<float> intensities;
  if (with_intensities)
  {
    intensities.assign(ranges.size() + (in.ConsumeBool() ? 1 : 0), 1.0f);
    scan.intensities = intensities.data();
    scan.intensity_count = intensities.size();
  }

  try
  {
    line_extraction::LineExtractor extractor(params);
    const auto& result = extractor.extract(scan);
    const auto& prepared = extractor.preparedScan();
    check(prepared.size() <= scan.count);
    for (const auto& s : result.segments)
    {
      check(std::isfinite(s.start.x()) && std::isfinite(s.start.y()) && std::isfinite(s.end.x()) &&
            std::isfinite(s.end.y()) && std::isfinite(s.angle) && std::isfinite(s.radius));
      check(s.index_begin >= 0 && s.index_begin <= s.index_end &&
            s.index_end <= static_cast<int>(result.point_indices.size()));
      for (int k = s.index_begin; k < s.index_end; ++k)
        check(result.point_indices[k] >= 0 && result.point_indices[k] < static_cast<int>(prepared.size()));
    }
  }
  catch (const line_extraction::ScanError&)
  {
    // Unusable geometry, rejected with a message naming the field: the expected outcome.
  }
  catch (const linemap::ParameterError&)
  {
  }
  return 0;
}
