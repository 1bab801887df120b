// What the CAE-RLSM tests share: the names they use unqualified and the keyframe poses adjust() takes.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/cae_rlsm.hpp"

using line_map_merging::CaeParams;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using line_map_merging::MapSegment;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

/// Keyframe i at p[i], as CaeRlsm::adjust takes them.
inline std::vector<std::pair<std::uint64_t, Pose2>> indexedPoses(const std::vector<Pose2>& p)
{
  std::vector<std::pair<std::uint64_t, Pose2>> out;
  for (std::size_t i = 0; i < p.size(); ++i) out.emplace_back(i, p[i]);
  return out;
}
