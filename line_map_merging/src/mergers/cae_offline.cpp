// Offline CAE-RLSM: a fresh CaeRlsm fed the stored keyframes in arrival order at their current poses.
#include "line_map_merging/mergers/cae_offline.hpp"

namespace line_map_merging
{
CaeOffline::CaeOffline(const CaeParams& params) : params_(params)
{
  params_.validate();
}

std::vector<MapSegment> CaeOffline::compute() const
{
  replay_ = std::make_unique<CaeRlsm>(params_);
  for (const Keyframe& k : stored()) replay_->addKeyframe(k);
  return replay_->map();
}

std::vector<Leaf> CaeOffline::leaves(std::uint64_t id) const
{
  cachedMap();  // builds replay_ when the cache is stale
  return replay_ ? replay_->leaves(id) : std::vector<Leaf>{};
}

}  // namespace line_map_merging
