#include "line_map_merging/localization/place_confirmation.hpp"

#include <cmath>

namespace line_map_merging
{
PlaceConfirmation::Verdict PlaceConfirmation::add(const linemap::Pose2& implied, double travelled, bool fresh)
{
  if (!started_ || fresh)
  {
    started_ = true;
    implied_ = implied;
    start_path_ = travelled;
  }
  const linemap::Pose2 drift = implied_.inverse() * implied;
  if (std::hypot(drift.x, drift.y) > max_xy || std::fabs(drift.theta) > max_theta)
  {
    started_ = false;
    return Verdict::kBroken;
  }
  return travelled - start_path_ >= path_ ? Verdict::kConfirmed : Verdict::kHolding;
}

}  // namespace line_map_merging
