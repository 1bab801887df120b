// O2TO-ILSM: a fresh OTO-ILSM fed the stored keyframes in arrival order at their current poses.
#include "line_map_merging/mergers/o2to_ilsm.hpp"

#include "line_map_merging/mergers/oto_ilsm.hpp"

namespace line_map_merging
{
O2toIlsm::O2toIlsm(const FusionParams& params) : params_(params)
{
  params_.validate();
}

std::vector<MapSegment> O2toIlsm::compute() const
{
  OtoIlsm replay(params_);
  for (const Keyframe& k : stored()) replay.addKeyframe(k);
  return replay.map();
}

}  // namespace line_map_merging
