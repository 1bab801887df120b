// libFuzzer target: Merger::load of arbitrary bytes (CAE-RLSM map files, YAML). A bad file must
// end in MapFileError with the current state kept; a loaded map must be finite and consistent.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_check.hpp"
#include "line_map_merging/mergers/merger.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const std::string path = "/tmp/linemap_fuzz_map_" + std::to_string(::getpid()) + ".yaml";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  linemap::ParamSet params;
  params.set("threads", "1");
  auto merger = line_map_merging::makeMerger("cae", params);
  try
  {
    merger->load(path);
  }
  catch (const line_map_merging::MapFileError&)
  {
    check(merger->segmentCount() == 0 && merger->keyframeCount() == 0);
    return 0;
  }
  const auto map = merger->map();
  check(map.size() == merger->segmentCount());
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    if (i > 0) check(map[i - 1].id < map[i].id);
    const auto& s = map[i].segment;
    check(std::isfinite(s.start.x()) && std::isfinite(s.start.y()) && std::isfinite(s.end.x()) &&
          std::isfinite(s.end.y()));
    if (merger->hasProvenance()) check(merger->leaves(map[i].id).size() == map[i].merged_count);
  }
  // A loaded map must accept new keyframes and an adjustment.
  line_map_merging::Keyframe kf;
  kf.index = 1000000;
  kf.segments.emplace_back(linemap::Vec2(0, 0), linemap::Vec2(1, 0));
  try
  {
    merger->addKeyframe(kf);
  }
  catch (const std::invalid_argument&)
  {
  }
  const auto keyframes = merger->keyframes();
  if (!keyframes.empty()) merger->adjust({{keyframes.front().index, linemap::Pose2(0.1, 0.0, 0.01)}});
  return 0;
}
