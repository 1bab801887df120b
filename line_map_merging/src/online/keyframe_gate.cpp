#include "line_map_merging/online/keyframe_gate.hpp"

#include <cmath>
#include <string>

namespace line_map_merging
{
KeyframeGateParams KeyframeGateParams::fromParams(const linemap::ParamSet& params)
{
  KeyframeGateParams p;
  p.distance = params.getNonNegative("keyframe_distance", p.distance);
  p.angle = params.getNonNegative("keyframe_angle", p.angle);
  return p;
}

bool KeyframeGate::wouldAccept(const linemap::Pose2& pose) const
{
  if (!last_) return true;
  const double dx = pose.x - last_->x, dy = pose.y - last_->y;
  const double turn = std::abs(linemap::normalizeAngle(pose.theta - last_->theta));
  return std::hypot(dx, dy) >= params_.distance || turn >= params_.angle;
}

bool KeyframeGate::accept(const linemap::Pose2& pose)
{
  if (!wouldAccept(pose)) return false;
  last_ = pose;
  return true;
}

}  // namespace line_map_merging
