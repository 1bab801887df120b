#include "line_map_merging/online/trajectory_anchor.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "linemap/params.hpp"

namespace line_map_merging
{
void OdometryHistory::add(double stamp, const linemap::Pose2& pose)
{
  if (!std::isfinite(stamp)) return;
  if (poses_.empty() || stamp > poses_.back().first)
  {
    poses_.emplace_back(stamp, pose);
    return;
  }
  const auto at = std::lower_bound(poses_.begin(), poses_.end(), stamp,
                                   [](const auto& p, double s) { return p.first < s; });
  if (at->first != stamp) poses_.emplace(at, stamp, pose);
}

std::optional<linemap::Pose2> OdometryHistory::at(double stamp, double tolerance, double max_gap) const
{
  if (poses_.empty() || !std::isfinite(stamp)) return std::nullopt;
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), stamp,
                                      [](const auto& p, double s) { return p.first < s; });
  const auto before = after == poses_.begin() ? poses_.end() : std::prev(after);
  // The nearest recorded scan within the tolerance: a node of the back end is one of the scans.
  const double dt_after = after == poses_.end() ? INFINITY : after->first - stamp;
  const double dt_before = before == poses_.end() ? INFINITY : stamp - before->first;
  if (std::min(dt_after, dt_before) <= tolerance)
    return dt_after <= dt_before ? after->second : before->second;
  if (after == poses_.end() || before == poses_.end() || after->first - before->first > max_gap)
    return std::nullopt;
  return linemap::interpolate(before->second, after->second, dt_before / (after->first - before->first));
}

CorrectionMode correctionModeFromString(const std::string& key, const std::string& value)
{
  if (value == "nearest") return CorrectionMode::kNearest;
  if (value == "interpolate") return CorrectionMode::kInterpolate;
  throw linemap::ParameterError("parameter '" + key + "': expected 'nearest' or 'interpolate', got '" +
                                value + "'");
}

NodeCorrections nodeCorrections(const OdometryHistory& history,
                                const std::vector<std::pair<double, linemap::Pose2>>& nodes, double tolerance,
                                double max_gap)
{
  NodeCorrections out;
  auto& c = out.corrections;
  c.reserve(nodes.size());
  bool sorted = true;
  for (const auto& [stamp, pose] : nodes)
  {
    const auto odom = history.at(stamp, tolerance, max_gap);
    if (!odom)
    {
      ++out.unmatched;
      continue;
    }
    sorted = sorted && (c.empty() || c.back().first < stamp);
    c.emplace_back(stamp, pose * odom->inverse());
  }
  // A back end lists its nodes in time order; otherwise in stamp order, the last of a repeated stamp.
  if (!sorted)
  {
    std::stable_sort(c.begin(), c.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    auto last = c.begin();
    for (auto it = c.begin(); it != c.end(); ++it)
      if (it + 1 == c.end() || (it + 1)->first != it->first) *last++ = *it;
    c.erase(last, c.end());
  }
  return out;
}

linemap::Pose2 correctionAt(const std::vector<std::pair<double, linemap::Pose2>>& corrections, double stamp,
                            CorrectionMode mode)
{
  const auto after = std::lower_bound(corrections.begin(), corrections.end(), stamp,
                                      [](const auto& c, double s) { return c.first < s; });
  if (after == corrections.begin()) return after->second;
  if (after == corrections.end()) return corrections.back().second;
  const auto& before = *(after - 1);
  const double span = after->first - before.first;
  const double t = span > 0.0 ? (stamp - before.first) / span : 0.0;
  if (mode == CorrectionMode::kNearest) return t <= 0.5 ? before.second : after->second;
  return linemap::interpolate(before.second, after->second, t);
}

}  // namespace line_map_merging
