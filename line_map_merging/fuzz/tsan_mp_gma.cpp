// ThreadSanitizer check of MP-GMA's parallel adjustment: a CAE-RLSM map of about 10^4 leaves
// (a grid of walls seen from many keyframes) adjusted with 2 worker threads, several times.
// Built and run by scripts/sanitize.sh tsan; exits non-zero (TSan report) on a data race.
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"

int main()
{
  linemap::ParamSet params;
  params.set("threads", "2");
  auto merger = line_map_merging::makeMerger("cae", params);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  // 100 keyframes x 100 segments = 10^4 leaves on ~10^3 walls (each wall seen by 10 keyframes).
  const int keyframes = 100, per_keyframe = 100;
  for (int k = 0; k < keyframes; ++k)
  {
    line_map_merging::Keyframe kf;
    kf.index = static_cast<std::uint64_t>(k);
    kf.stamp = 0.1 * k;
    kf.pose = linemap::Pose2(0.0, 0.0, 0.0);
    const int block = k / 10;
    for (int j = 0; j < per_keyframe; ++j)
    {
      // Walls on a 3 m grid, 1.5 m long, alternating horizontal and vertical; each group of ten
      // keyframes sees its own block of the grid.
      const double gx = 3.0 * (j % 10) + 40.0 * block, gy = 3.0 * (j / 10);
      const linemap::Vec2 a(gx + noise(rng), gy + noise(rng));
      const linemap::Vec2 b =
          (j % 2) ? linemap::Vec2(gx + 1.5, a.y() + noise(rng)) : linemap::Vec2(a.x() + noise(rng), gy + 1.5);
      kf.segments.emplace_back(a, b);
    }
    merger->addKeyframe(kf);
  }
  std::printf("leaves %zu, map segments %zu\n", merger->leafCount(), merger->segmentCount());
  for (int round = 0; round < 3; ++round)
  {
    std::vector<std::pair<std::uint64_t, linemap::Pose2>> poses;
    for (int k = 0; k < keyframes; ++k)
      poses.emplace_back(k,
                         linemap::Pose2(0.05 * k + 0.02 * std::sin(k + round), 0.01 * round, 0.002 * round));
    const auto r = merger->adjust(poses);
    std::printf("adjust %d: moved %zu split %zu merged %zu, map segments %zu\n", round, r.moved, r.split,
                r.merged, merger->segmentCount());
  }
  return 0;
}
