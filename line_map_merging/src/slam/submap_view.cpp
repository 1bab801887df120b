#include "line_map_merging/slam/submap_view.hpp"

#include <algorithm>
#include <cmath>

namespace line_map_merging
{
ViewCone viewCone(const std::vector<linemap::Vec2>& points)
{
  ViewCone cone;
  if (points.empty()) return cone;
  cone.min_bearing = cone.max_bearing = std::atan2(points.front().y(), points.front().x());
  for (const auto& p : points)
  {
    const double bearing = std::atan2(p.y(), p.x());
    cone.min_bearing = std::min(cone.min_bearing, bearing);
    cone.max_bearing = std::max(cone.max_bearing, bearing);
    cone.max_range = std::max(cone.max_range, p.norm());
  }
  // Returns all around (or a cone across the rear, which atan2 splits at +-pi): every bearing is seen.
  cone.full_circle = cone.max_bearing - cone.min_bearing > 1.9 * linemap::kPi;
  return cone;
}

std::vector<bool> inView(const std::vector<linemap::Vec2>& points,
                         const std::vector<std::pair<linemap::Pose2, ViewCone>>& views, double range_margin)
{
  std::vector<bool> seen(points.size(), false);
  for (const auto& [pose, cone] : views)
  {
    const linemap::Pose2 into = pose.inverse();
    for (std::size_t i = 0; i < points.size(); ++i)
    {
      if (seen[i]) continue;
      const linemap::Vec2 d = into.apply(points[i]);
      if (d.norm() > cone.max_range + range_margin) continue;
      const double bearing = std::atan2(d.y(), d.x());
      seen[i] = cone.full_circle || (bearing >= cone.min_bearing && bearing <= cone.max_bearing);
    }
  }
  return seen;
}

}  // namespace line_map_merging
