// Lines in the unexplained points of the last few metres of scans (see the header).
#include "line_extraction/submap_extraction.hpp"

#include <algorithm>
#include <cmath>

#include "line_extraction/line_fit.hpp"
#include "line_extraction/param_checks.hpp"

namespace line_extraction
{
SubmapParams SubmapParams::fromParams(const linemap::ParamSet& ps)
{
  SubmapParams p;
  p.enabled = ps.getBool("submap/enabled", p.enabled);
  p.scan_distance = nonNegativeParam(ps, "submap/scan_distance", p.scan_distance);
  p.scan_angle = nonNegativeParam(ps, "submap/scan_angle", p.scan_angle);
  p.window_distance = positiveParam(ps, "submap/window_distance", p.window_distance);
  p.window_scans = intParamAtLeast(ps, "submap/window_scans", p.window_scans, 2);
  p.lines = p.lines.readOver(ps, "submap/", "min_scans");
  return p;
}

SubmapExtractor::SubmapExtractor(const SubmapParams& params, const SensorModel& sensor)
    : params_(params), sensor_(sensor), finder_(params.lines)
{
}

std::size_t SubmapExtractor::appendTo(const PreparedScan& scan, ExtractionResult& result,
                                      const Pose2& laser_pose)
{
  const std::vector<Segment>& found = update(scan, result, laser_pose);
  result.segments.insert(result.segments.end(), found.begin(), found.end());
  return found.size();
}

void SubmapExtractor::observeStamp(std::uint64_t stamp_ns)
{
  if (stamp_ns < last_stamp_ns_) reset();
  last_stamp_ns_ = stamp_ns;
}

void SubmapExtractor::reset()
{
  scans_.clear();
  scan_paths_.clear();
  points_.clear();
  pending_.clear();
  output_.clear();
  has_last_ = false;
  path_ = 0.0;
}

bool SubmapExtractor::admits(const Pose2& laser) const
{
  if (!has_last_) return true;
  const double moved = (laser.translation() - last_admitted_.translation()).norm();
  const double turned = std::abs(linemap::normalizeAngle(laser.theta - last_admitted_.theta));
  return moved >= params_.scan_distance || turned >= params_.scan_angle;
}

const std::vector<Segment>& SubmapExtractor::update(const PreparedScan& scan,
                                                    const ExtractionResult& extracted,
                                                    const Pose2& laser_pose)
{
  output_.clear();
  if (!params_.enabled) return output_;
  if (admits(laser_pose))
  {
    if (has_last_) path_ += (laser_pose.translation() - last_admitted_.translation()).norm();
    last_admitted_ = laser_pose;
    has_last_ = true;
    const std::size_t before = points_.size();
    addResiduals(scan, extracted, laser_pose);
    const std::size_t added = points_.size() - before;
    dropOldScans();  // erases a prefix of points_: the new ones stay the last `added`
    pending_.clear();
    finder_.index(points_, scans_);
    findLines(points_.size() - added);
  }
  emit(laser_pose);
  return output_;
}

void SubmapExtractor::addResiduals(const PreparedScan& scan, const ExtractionResult& extracted,
                                   const Pose2& laser)
{
  std::vector<char> explained(scan.size(), 0);
  for (const Segment& s : extracted.segments)
    for (int k = s.index_begin; k < s.index_end; ++k)
      explained[static_cast<std::size_t>(extracted.point_indices[static_cast<std::size_t>(k)])] = 1;
  const std::uint32_t id = next_scan_id_++;
  ResidualSource source;
  source.id = id;
  source.laser = laser;
  source.returns = ResidualReturns::of(scan.angles, scan.ranges);
  scans_.push_back(std::move(source));
  scan_paths_.push_back(path_);
  for (std::size_t i = 0; i < scan.size(); ++i)
  {
    if (explained[i]) continue;
    ResidualPoint w;
    w.p = laser.apply(scan.points[i]);
    w.sigma = static_cast<float>(sensor_.sigma(scan.ranges[i]));
    // The gap to either neighbour on one surface; the model's is 0 where it adds nothing.
    double gap2 = scan.gap2.empty() ? 0.0 : scan.gap2[i];
    if (!scan.gap2.empty() && i + 1 < scan.size()) gap2 = std::max(gap2, scan.gap2[i + 1]);
    w.gap = static_cast<float>(std::sqrt(gap2));
    w.source = id;
    if (i < scan.beam_index.size()) w.beam = scan.beam_index[i];
    points_.push_back(w);
  }
}

void SubmapExtractor::dropOldScans()
{
  std::size_t drop = 0;
  while (scans_.size() - drop > 1 && (static_cast<int>(scans_.size() - drop) > params_.window_scans ||
                                      path_ - scan_paths_[drop] > params_.window_distance))
    ++drop;
  if (drop == 0) return;
  const std::uint32_t oldest_kept = scans_[drop].id;
  scans_.erase(scans_.begin(), scans_.begin() + static_cast<std::ptrdiff_t>(drop));
  scan_paths_.erase(scan_paths_.begin(), scan_paths_.begin() + static_cast<std::ptrdiff_t>(drop));
  // Points are in scan order, so the dropped ones are a prefix.
  const auto keep = std::find_if(points_.begin(), points_.end(),
                                 [oldest_kept](const ResidualPoint& w) { return w.source >= oldest_kept; });
  points_.erase(points_.begin(), keep);
}

void SubmapExtractor::findLines(std::size_t first_new)
{
  for (std::size_t seed = first_new; seed < points_.size(); ++seed)
  {
    ResidualLine line;
    if (!finder_.grow(seed, line)) continue;
    std::vector<Vec2> members;
    members.reserve(line.members.size());
    for (const std::uint32_t m : line.members) members.push_back(points_[m].p);
    pending_.emplace_back(std::move(line), std::move(members));
    ++lines_found_;
  }
}

void SubmapExtractor::emit(const Pose2& laser)
{
  const Pose2 to_laser = laser.inverse();
  for (const auto& [line, members] : pending_)
  {
    LineSums sums;
    for (const Vec2& p : members) sums.add(to_laser.apply(p));
    const LineFit fit = fitLine(sums, line.sigma);
    if (!fit.valid) continue;
    Segment seg;
    seg.angle = fit.angle;
    seg.radius = fit.radius;
    seg.covariance = fit.covariance;
    // The endpoints projected onto the laser-frame fit (the same line up to rounding).
    const Vec2 a = to_laser.apply(line.start), b = to_laser.apply(line.end);
    seg.start = a - fit.normal * fit.signedDistance(a);
    seg.end = b - fit.normal * fit.signedDistance(b);
    seg.num_points = static_cast<int>(members.size());
    output_.push_back(seg);
  }
}

}  // namespace line_extraction
