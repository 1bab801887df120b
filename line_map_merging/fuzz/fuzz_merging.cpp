// libFuzzer target: the online mergers (CAE-RLSM = OTM-ILSM + MP-GMA, and the others) on an
// arbitrary interleaving of addKeyframe / adjust / map / leaves / reset, with non-finite and huge
// values and duplicate keyframe indices. Bad keyframes must be refused with std::invalid_argument
// and leave the map unchanged; the map must stay finite and its ids unique and sorted.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

// Before fuzz_check.hpp: its check() macro would break Boost.Geometry's concepts::check.
#include "line_map_merging/mergers/cae_rlsm.hpp"
// clang-format off
#include "fuzz_check.hpp"
// clang-format on
#include "line_map_merging/mergers/merger.hpp"

namespace
{
// Mostly coordinates of a small world (so segments actually fuse); sometimes any double.
// Extreme values only for `wild` (CAE-RLSM); the competing methods get bounded values.
bool wild = true;

double coord(FuzzedDataProvider& in)
{
  switch (in.ConsumeIntegralInRange<int>(wild ? 0 : 2, 15))
  {
    case 0:
    {
      // Any bit pattern: NaN, inf, denormals, huge.
      const auto bits = in.ConsumeIntegral<std::uint64_t>();
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
    case 1:
      return in.ConsumeBool() ? 1e300 : -1e300;
    default:
      return in.ConsumeIntegralInRange<int>(-400, 400) * 0.025;
  }
}

linemap::Pose2 pose(FuzzedDataProvider& in)
{
  return linemap::Pose2(coord(in), coord(in), coord(in));
}

void checkMap(const line_map_merging::Merger& merger)
{
  const auto map = merger.map();
  check(map.size() == merger.segmentCount());
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    if (i > 0) check(map[i - 1].id < map[i].id);
    const auto& s = map[i].segment;
    check(std::isfinite(s.start.x()) && std::isfinite(s.start.y()) && std::isfinite(s.end.x()) &&
          std::isfinite(s.end.y()));
    check(map[i].merged_count >= 1);
  }
  const auto keyframes = merger.keyframes();
  check(keyframes.size() == merger.keyframeCount());
  for (std::size_t i = 1; i < keyframes.size(); ++i) check(keyframes[i - 1].index < keyframes[i].index);
}

/// A keyframe of wild segments: merged or rejected one by one, or refused whole leaving the map as it was.
void addKeyframe(FuzzedDataProvider& in, line_map_merging::Merger& merger, int step)
{
  line_map_merging::Keyframe kf;
  kf.index = in.ConsumeIntegralInRange<std::uint64_t>(0, 12);
  kf.stamp = in.ConsumeIntegralInRange<int>(0, 7) == 0 ? coord(in) : step * 0.1;
  kf.pose = pose(in);
  if (in.ConsumeIntegralInRange<int>(0, 7) == 0) kf.mount = pose(in);
  const int n = in.ConsumeIntegralInRange<int>(0, 12);
  for (int k = 0; k < n; ++k)
  {
    linemap::Vec2 a(coord(in), coord(in));
    linemap::Vec2 b = in.ConsumeBool() ? a : linemap::Vec2(coord(in), coord(in));
    kf.segments.emplace_back(a, b);
  }
  const auto before = merger.segmentCount();
  const auto leaves_before = merger.leafCount();
  try
  {
    const auto r = merger.addKeyframe(kf);
    check(r.merged + r.rejected == kf.segments.size());
  }
  catch (const std::invalid_argument&)
  {
    check(merger.segmentCount() == before && merger.leafCount() == leaves_before);
  }
}

/// New poses for some keyframes, known or not.
void adjust(FuzzedDataProvider& in, line_map_merging::Merger& merger)
{
  std::vector<std::pair<std::uint64_t, linemap::Pose2>> poses;
  const int n = in.ConsumeIntegralInRange<int>(0, 8);
  for (int k = 0; k < n; ++k) poses.emplace_back(in.ConsumeIntegralInRange<std::uint64_t>(0, 14), pose(in));
  try
  {
    const auto r = merger.adjust(poses);
    check(r.moved + r.unknown <= poses.size());
  }
  catch (const std::invalid_argument&)
  {
    // A non-finite pose refused by name.
  }
}

/// The leaves of a map segment (as many as it merged) and of any id.
void readLeaves(FuzzedDataProvider& in, line_map_merging::Merger& merger)
{
  const auto map = merger.map();
  if (!map.empty())
  {
    const auto& m = map[in.ConsumeIntegralInRange<std::size_t>(0, map.size() - 1)];
    const auto leaves = merger.leaves(m.id);
    if (merger.hasProvenance()) check(leaves.size() == m.merged_count);
  }
  merger.leaves(in.ConsumeIntegral<std::uint64_t>());
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  FuzzedDataProvider in(data, size);
  const auto& names = line_map_merging::mergerNames();
  // Most inputs go to "cae"; the first byte may pick another method.
  std::string name = "cae";
  if (in.ConsumeIntegralInRange<int>(0, 3) == 0)
    name = names[in.ConsumeIntegralInRange<std::size_t>(0, names.size() - 1)];
  wild = name == "cae";
  linemap::ParamSet params;
  params.set("threads", "1");
  params.set("consistent_adjustment", in.ConsumeBool() ? "true" : "false");
  params.set("spatial_index", in.ConsumeBool() ? "true" : "false");
  std::unique_ptr<line_map_merging::Merger> merger;
  try
  {
    merger = line_map_merging::makeMerger(name, params);
  }
  catch (const linemap::ParameterError&)
  {
    return 0;  // a method without these keys refusing them is fine
  }

  for (int step = 0; step < 64 && in.remaining_bytes() > 0; ++step)
  {
    switch (in.ConsumeIntegralInRange<int>(0, 9))
    {
      case 0:
      case 1:
      case 2:
      case 3:
        addKeyframe(in, *merger, step);
        break;
      case 4:
      case 5:
        adjust(in, *merger);
        break;
      case 6:
      case 7:
        checkMap(*merger);
        break;
      case 8:
        readLeaves(in, *merger);
        break;
      default:
        if (auto* cae = dynamic_cast<line_map_merging::CaeRlsm*>(merger.get()); cae && in.ConsumeBool())
        {
          // Continued as a new session: later keyframes judge the originals so far (see_through).
          const std::uint32_t session = cae->session();
          cae->loadText(cae->mapText(), "fuzz");
          check(cae->session() <= session + 1);
        }
        if (in.ConsumeIntegralInRange<int>(0, 3) == 0) merger->reset();
        check(merger->segmentCount() <= merger->leafCount() || !merger->hasProvenance());
        break;
    }
  }
  checkMap(*merger);
  return 0;
}
