// CAE-RLSM state: parameters, keyframe bookkeeping and read access to the provenance tree.
#include "line_map_merging/mergers/cae_rlsm.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace line_map_merging
{
CaeParams CaeParams::fromParams(const linemap::ParamSet& params)
{
  CaeParams p;
  p.fusion = FusionParams::fromParams(params);
  p.threads = params.getInt("threads", p.threads);
  if (p.threads < 0)
    throw linemap::ParameterError("parameter 'threads': " + std::to_string(p.threads) +
                                  " must be >= 0 (0 = all cores)");
  linemap::readFields(params,
                      {{"consistent_adjustment", &CaeParams::consistent_adjustment},
                       {"spatial_index", &CaeParams::spatial_index},
                       {"map_merge", &CaeParams::map_merge},
                       {"absorb_contained", &CaeParams::absorb_contained},
                       {"regroup_on_adjust", &CaeParams::regroup_on_adjust},
                       {"incremental_regroup", &CaeParams::incremental_regroup},
                       {"resolve_crossings", &CaeParams::resolve_crossings},
                       {"crossing_overhang", &CaeParams::crossing_overhang},
                       {"crossing_chain_angle", &CaeParams::crossing_chain_angle},
                       {"single_view_min_length", &CaeParams::single_view_min_length},
                       {"see_through", &CaeParams::see_through},
                       {"see_through_margin", &CaeParams::see_through_margin},
                       {"see_through_views", &CaeParams::see_through_views}},
                      p);
  p.validate();
  return p;
}

void CaeParams::validate() const
{
  fusion.validate();
  // A segment cut at a crossing ends there up to rounding, which must not count as an overhang again.
  if (!(crossing_overhang >= 1e-3 && std::isfinite(crossing_overhang)))
    throw linemap::ParameterError("parameter 'crossing_overhang': " + std::to_string(crossing_overhang) +
                                  " is not a finite distance >= 0.001 m");
  if (!(crossing_chain_angle >= 0.0 && crossing_chain_angle < 0.5 * linemap::kPi))
    throw linemap::ParameterError("parameter 'crossing_chain_angle': " +
                                  std::to_string(crossing_chain_angle) + " is not in [0, pi/2) rad");
  if (!(single_view_min_length >= 0.0 && std::isfinite(single_view_min_length)))
    throw linemap::ParameterError("parameter 'single_view_min_length': " +
                                  std::to_string(single_view_min_length) + " is not a finite length >= 0 m");
  if (!(see_through_margin > 0.0 && std::isfinite(see_through_margin)))
    throw linemap::ParameterError("parameter 'see_through_margin': " + std::to_string(see_through_margin) +
                                  " is not a finite distance > 0 m");
  if (see_through_views < 1 || see_through_views > 1000)
    throw linemap::ParameterError("parameter 'see_through_views': " + std::to_string(see_through_views) +
                                  " is not in [1, 1000]");
}

CaeRlsm::CaeRlsm(const CaeParams& params) : params_(params)
{
  params_.validate();
}

AddResult CaeRlsm::addKeyframe(const Keyframe& keyframe)
{
  const linemap::Pose2& p = keyframe.pose;
  if (!(std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate && std::isfinite(p.theta)))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) +
                                ": pose is not finite or lies beyond " + std::to_string(kMaxCoordinate) +
                                " m");
  const linemap::Pose2& m = keyframe.mount;
  if (!(std::abs(m.x) <= kMaxCoordinate && std::abs(m.y) <= kMaxCoordinate && std::isfinite(m.theta)))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) +
                                ": mount is not finite or lies beyond " + std::to_string(kMaxCoordinate) +
                                " m");
  if (!std::isfinite(keyframe.stamp))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) + ": stamp is not finite");
  if (slot_of_.count(keyframe.index))
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.index) + ": index already merged");

  const auto slot = static_cast<std::uint32_t>(keyframes_.size());
  slot_of_.emplace(keyframe.index, slot);
  keyframes_.push_back({keyframe.index, keyframe.stamp, p, m});
  keyframes_.back().session = session_;
  transforms_.emplace_back();
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  transforms_.back() << c, -s, p.x, s, c, p.y;

  AddResult result;
  IdQueue touched;
  if (params_.see_through && session_ > 0)
  {
    const StepTimes<kStepCount>::Scope timed(steps_, kKeyframeSeeThrough);
    result.retired = retireSeenThrough(slot, keyframe.segments, touched);
  }
  insertOriginals(slot, keyframe.segments, result, touched);
  finishKeyframe(touched, kKeyframeOtm);
  return result;
}

AddResult CaeRlsm::addOriginals(std::uint64_t keyframe, const std::vector<Segment2>& segments)
{
  const auto slot = slot_of_.find(keyframe);
  if (slot == slot_of_.end())
    throw std::invalid_argument("keyframe " + std::to_string(keyframe) +
                                ": no such keyframe for its originals");
  AddResult result;
  IdQueue touched;
  insertOriginals(slot->second, segments, result, touched);
  finishKeyframe(touched, kKeyframeOtm);
  return result;
}

void CaeRlsm::insertOriginals(std::uint32_t slot, const std::vector<Segment2>& segments, AddResult& result,
                              IdQueue& touched)
{
  const StepTimes<kStepCount>::Scope timed(steps_, kKeyframeOtm);
  const linemap::Pose2& pose = keyframes_[slot].pose;
  for (const Segment2& local : segments)
  {
    // A finite segment under a huge (finite) pose can still overflow in the map frame.
    const Segment2 global = local.transformed(pose);
    if (!isValidSegment(local) || !isValidSegment(global))
    {
      ++result.rejected;
      continue;
    }
    const auto leaf = static_cast<std::uint32_t>(leaves_.size());
    leaves_.push_back({slot, local});
    touched.insert(insertSegment(global, leaf));
    ++result.merged;
  }
}

void CaeRlsm::finishKeyframe(const IdQueue& touched, std::size_t offset)
{
  IdQueue changed;
  if (params_.map_merge)
  {
    const StepTimes<kStepCount>::Scope timed(steps_, offset + (kKeyframeMapMerge - kKeyframeOtm));
    mergeMapSegments(touched, &changed);
  }
  if (params_.resolve_crossings)
  {
    const StepTimes<kStepCount>::Scope timed(steps_, offset + (kKeyframeCrossings - kKeyframeOtm));
    changed.insert(touched.begin(), touched.end());
    IdQueue cut;
    resolveCrossings(std::move(changed), nullptr, &cut);
    mergeCutSegments(std::move(cut));
  }
}

std::vector<MapSegment> CaeRlsm::map() const
{
  std::vector<MapSegment> out;
  out.reserve(nodes_.size());
  for (const auto& [id, node] : nodes_)
    if (shown(node)) out.push_back({id, node.segment, static_cast<std::uint32_t>(node.leaves.size())});
  std::sort(out.begin(), out.end(), [](const MapSegment& a, const MapSegment& b) { return a.id < b.id; });
  return out;
}

bool CaeRlsm::shown(const Node& node) const
{
  if (params_.single_view_min_length <= 0.0 || node.segment.length() >= params_.single_view_min_length)
    return true;
  for (std::uint32_t leaf : node.leaves)
    if (leaves_[leaf].slot != leaves_[node.leaves.front()].slot) return true;
  return false;
}

std::size_t CaeRlsm::segmentCount() const
{
  std::size_t n = 0;
  for (const auto& entry : nodes_) n += shown(entry.second);
  return n;
}

std::vector<KeyframeInfo> CaeRlsm::keyframes() const
{
  std::vector<KeyframeInfo> out = keyframes_;
  std::sort(out.begin(), out.end(),
            [](const KeyframeInfo& a, const KeyframeInfo& b) { return a.index < b.index; });
  return out;
}

std::vector<Leaf> CaeRlsm::leaves(std::uint64_t id) const
{
  std::vector<Leaf> out;
  auto it = nodes_.find(id);
  if (it == nodes_.end()) return out;
  for (std::uint32_t l : it->second.leaves)
    out.push_back({keyframes_[leaves_[l].slot].index, leaves_[l].local});
  return out;
}

void CaeRlsm::reset()
{
  keyframes_.clear();
  transforms_.clear();
  slot_of_.clear();
  leaves_.clear();
  nodes_.clear();
  index_.clear();
  index_stale_ = false;
  next_id_ = 0;
  session_ = 0;
  see_through_votes_.clear();
  retired_leaves_ = retired_segments_ = 0;
  checkpoint_ = RegroupCheckpoint();
  steps_.clear();
}

}  // namespace line_map_merging
