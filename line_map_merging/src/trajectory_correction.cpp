#include "line_map_merging/trajectory_correction.hpp"

#include <algorithm>
#include <cmath>

namespace line_map_merging
{
std::optional<std::size_t> matchByStamp(const std::vector<KeyframeInfo>& keyframes, double stamp,
                                        double tolerance)
{
  if (keyframes.empty() || !std::isfinite(stamp)) return std::nullopt;
  auto it = std::lower_bound(keyframes.begin(), keyframes.end(), stamp,
                             [](const KeyframeInfo& k, double s) { return k.stamp < s; });
  std::optional<std::size_t> best;
  double best_dt = tolerance;
  for (auto c : {it, it == keyframes.begin() ? it : it - 1})
  {
    if (c == keyframes.end()) continue;
    const double dt = std::abs(c->stamp - stamp);
    if (dt <= best_dt)
    {
      best_dt = dt;
      best = static_cast<std::size_t>(c - keyframes.begin());
    }
  }
  return best;
}

std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched)
{
  std::vector<std::pair<std::uint64_t, linemap::Pose2>> out;
  // Corrections of the matched keyframes, in stamp order.
  std::vector<std::pair<double, linemap::Pose2>> corrections;
  for (const KeyframeInfo& k : keyframes)
  {
    auto it = matched.find(k.index);
    if (it != matched.end()) corrections.emplace_back(k.stamp, it->second * k.pose.inverse());
  }
  if (corrections.empty()) return out;
  out.reserve(keyframes.size());
  for (const KeyframeInfo& k : keyframes)
  {
    auto it = matched.find(k.index);
    if (it != matched.end())
    {
      out.emplace_back(k.index, it->second);
      continue;
    }
    auto after = std::lower_bound(corrections.begin(), corrections.end(), k.stamp,
                                  [](const auto& c, double s) { return c.first < s; });
    linemap::Pose2 correction;
    if (after == corrections.begin())
      correction = after->second;
    else if (after == corrections.end())
      correction = corrections.back().second;
    else
    {
      const auto& before = *(after - 1);
      const double span = after->first - before.first;
      const double t = span > 0.0 ? (k.stamp - before.first) / span : 0.0;
      correction = linemap::interpolate(before.second, after->second, t);
    }
    out.emplace_back(k.index, correction * k.pose);
  }
  return out;
}

}  // namespace line_map_merging
