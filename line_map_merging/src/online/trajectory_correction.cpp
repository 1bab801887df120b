#include "line_map_merging/online/trajectory_correction.hpp"

#include <algorithm>
#include <cmath>

#include "line_map_merging/online/trajectory_anchor.hpp"

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
  if (best)
  {
    // Another scan the caller saw lies nearer to the stamp than the keyframe's own scan.
    const KeyframeInfo& k = keyframes[*best];
    const double dt = stamp - k.stamp;
    if (dt > 0.0 && !(2.0 * dt < k.scan_gap_after)) return std::nullopt;
    if (dt < 0.0 && !(-2.0 * dt < k.scan_gap_before)) return std::nullopt;
  }
  return best;
}

void ScanGapTracker::scan(double stamp)
{
  const double inf = std::numeric_limits<double>::infinity();
  const double gap = stamp > last_stamp_ ? stamp - last_stamp_ : inf;  // NaN last: unknown
  if (waiting_)
  {
    gaps_[*waiting_].second = gap;
    waiting_.reset();
  }
  last_gap_ = gap;
  last_stamp_ = stamp;
}

void ScanGapTracker::keyframe(std::uint64_t index)
{
  gaps_[index] = {last_gap_, std::numeric_limits<double>::infinity()};
  waiting_ = index;
}

void ScanGapTracker::fill(std::vector<KeyframeInfo>& keyframes) const
{
  for (KeyframeInfo& k : keyframes)
  {
    const auto it = gaps_.find(k.index);
    if (it == gaps_.end()) continue;
    k.scan_gap_before = it->second.first;
    k.scan_gap_after = it->second.second;
  }
}

void ScanGapTracker::clear()
{
  *this = ScanGapTracker();
}

std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched)
{
  return correctKeyframes(keyframes, matched, {});
}

namespace
{
/// Each keyframe's pose in the continuous frame: its odometry pose, or its map pose moved by the
/// map->odom of the nearest keyframe with an odometry pose (before it, else after it), or, without
/// any odometry pose, its map pose.
std::vector<linemap::Pose2> continuousPoses(const std::vector<KeyframeInfo>& keyframes,
                                            const std::map<std::uint64_t, linemap::Pose2>& odom)
{
  std::vector<linemap::Pose2> continuous(keyframes.size());
  std::optional<linemap::Pose2> map_to_odom;
  std::optional<std::size_t> first_with_odom;
  for (std::size_t i = 0; i < keyframes.size(); ++i)
  {
    auto it = odom.find(keyframes[i].index);
    if (it != odom.end())
    {
      continuous[i] = it->second;
      map_to_odom = keyframes[i].pose * it->second.inverse();
      if (!first_with_odom) first_with_odom = i;
    }
    else
      continuous[i] = map_to_odom ? map_to_odom->inverse() * keyframes[i].pose : keyframes[i].pose;
  }
  if (first_with_odom)
  {
    const KeyframeInfo& k = keyframes[*first_with_odom];
    const linemap::Pose2 first_map_to_odom = k.pose * odom.at(k.index).inverse();
    for (std::size_t i = 0; i < *first_with_odom; ++i)
      continuous[i] = first_map_to_odom.inverse() * keyframes[i].pose;
  }
  return continuous;
}
}  // namespace

std::vector<std::pair<std::uint64_t, linemap::Pose2>> correctKeyframes(
    const std::vector<KeyframeInfo>& keyframes, const std::map<std::uint64_t, linemap::Pose2>& matched,
    const std::map<std::uint64_t, linemap::Pose2>& odom)
{
  std::vector<std::pair<std::uint64_t, linemap::Pose2>> out;
  const std::vector<linemap::Pose2> continuous = continuousPoses(keyframes, odom);
  // Corrections (new pose * continuous pose^-1) of the matched keyframes, in stamp order.
  std::vector<std::pair<double, linemap::Pose2>> corrections;
  for (std::size_t i = 0; i < keyframes.size(); ++i)
  {
    auto it = matched.find(keyframes[i].index);
    if (it != matched.end())
      corrections.emplace_back(keyframes[i].stamp, it->second * continuous[i].inverse());
  }
  if (corrections.empty()) return out;
  out.reserve(keyframes.size());
  for (std::size_t i = 0; i < keyframes.size(); ++i)
  {
    const KeyframeInfo& k = keyframes[i];
    auto it = matched.find(k.index);
    if (it != matched.end())
      out.emplace_back(k.index, it->second);
    else
      out.emplace_back(k.index,
                       correctionAt(corrections, k.stamp, CorrectionMode::kInterpolate) * continuous[i]);
  }
  return out;
}

}  // namespace line_map_merging
