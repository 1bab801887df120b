#include "line_map_merging/localization/fleet_placement.hpp"

#include <cmath>
#include <stdexcept>

#include "line_map_merging/map/free_space_witness.hpp"

namespace line_map_merging
{
std::vector<linemap::Vec2> segmentPoints(const std::vector<linemap::Segment2>& segments,
                                         const linemap::Pose2& pose, double spacing)
{
  std::vector<linemap::Vec2> out;
  for (const linemap::Segment2& s : segments)
  {
    const double length = s.length();
    if (!std::isfinite(length)) continue;
    const int steps = std::max(1, static_cast<int>(std::ceil(length / spacing)));
    for (int i = 0; i <= steps; ++i)
      out.push_back(pose.apply(s.start + (s.end - s.start) * (static_cast<double>(i) / steps)));
  }
  return out;
}

FleetPlacement::FleetPlacement(const LocalizerParams& params, double point_spacing)
    : params_(params), point_spacing_(point_spacing)
{
  if (!(point_spacing_ > 0.0)) throw std::invalid_argument("fleet placement: point_spacing must be positive");
  // Searched beside the merging: the global searches are repeated as seldom as for a SLAM mapping apart.
  params_.research_every = params_.research_every_apart;
}

void FleetPlacement::setMap(const std::vector<linemap::Segment2>& segments)
{
  map_ = segments;
  for (auto& [robot, search] : searches_)
    if (search.localizer) search.localizer->setMap(map_);
}

std::optional<linemap::Pose2> FleetPlacement::addScan(std::size_t robot, double stamp,
                                                      const std::vector<linemap::Segment2>& segments,
                                                      const linemap::Pose2& laser,
                                                      const linemap::Pose2& mount)
{
  Search& search = searches_[robot];
  if (search.placed) return std::nullopt;
  if (!search.localizer) search.localizer = std::make_unique<LineMapLocalizer>(map_, params_);
  ++search.scans;
  const linemap::Pose2 base = laser * mount.inverse();
  if (search.last_base) search.travelled += (base.translation() - search.last_base->translation()).norm();
  search.last_base = base;
  if (search.sights.empty() ||
      (search.sights.back().laser.translation() - laser.translation()).norm() >= sight_spacing ||
      std::fabs(linemap::normalizeAngle(search.sights.back().laser.theta - laser.theta)) >= sight_turn)
    search.sights.push_back({laser, segments});

  LocalizerScan scan;
  scan.stamp = stamp;
  scan.points = segmentPoints(segments, mount, point_spacing_);
  scan.odom = base;  // the robot's own SLAM pose: smooth enough to predict with
  scan.sensor = mount.translation();
  const LocalizerResult result = search.localizer->addScan(scan);
  if (!result.localized)
  {
    search.confirmation.reset();
    return std::nullopt;
  }
  // The same scan in both frames: the robot's map frame in the fleet's.
  const linemap::Pose2 implied = result.pose * base.inverse();
  switch (search.confirmation.add(implied, search.travelled, result.outcome == LocalizerOutcome::kRecovered))
  {
    case PlaceConfirmation::Verdict::kBroken:
      search.localizer->startGlobalLocalization();
      return std::nullopt;
    case PlaceConfirmation::Verdict::kHolding:
      return std::nullopt;
    case PlaceConfirmation::Verdict::kConfirmed:
      break;
  }
  if (seenThroughLength(robot, implied, map_) > max_seen_through)
  {
    ++search.refused;
    search.confirmation.reset();
    search.localizer->startGlobalLocalization();
    return std::nullopt;
  }
  search.placed = refined(search, implied);
  search.localizer.reset();
  return search.placed;
}

linemap::Pose2 FleetPlacement::refined(const Search& search, const linemap::Pose2& placed) const
{
  // Every sight at once, in the robot's own map frame: the whole way it came, not one scan, pins the
  // rotation down.
  std::vector<linemap::Vec2> points;
  for (const Sight& sight : search.sights)
  {
    const std::vector<linemap::Vec2> seen = segmentPoints(sight.segments, sight.laser, point_spacing_);
    points.insert(points.end(), seen.begin(), seen.end());
  }
  SegmentMatchParams match = params_.match;
  match.check_free_side = false;  // the points come from many places
  const LocalizationSegmentIndex index(map_, params_.index_cell, match.max_distance);
  const SegmentMatch m = matchToSegments(index, points, placed, std::nullopt, match);
  if (!m.valid) return placed;
  const linemap::Pose2 change = placed.inverse() * m.pose;
  const bool near = std::hypot(change.x, change.y) <= PlaceConfirmation::max_xy &&
                    std::fabs(change.theta) <= PlaceConfirmation::max_theta;
  return near ? m.pose : placed;
}

double FleetPlacement::seenThroughLength(std::size_t robot, const linemap::Pose2& placed,
                                         const std::vector<linemap::Segment2>& map) const
{
  const auto it = searches_.find(robot);
  if (it == searches_.end()) return 0.0;
  std::vector<FreeSpaceWitness> witnesses;
  for (const Sight& sight : it->second.sights)
  {
    const linemap::Pose2 laser = placed * sight.laser;
    for (const linemap::Segment2& s : sight.segments)
    {
      FreeSpaceWitness w;
      if (makeWitness(laser.translation(), s.transformed(laser), see_through_margin, w))
        witnesses.push_back(w);
    }
  }
  // Per map segment, bins of about 0.1 m: seen through by some witness and in place by none.
  constexpr double bin = 0.1;
  constexpr std::size_t max_bins = 32;
  double length = 0.0;
  for (const linemap::Segment2& m : map)
  {
    const double segment_length = m.length();
    if (!(segment_length > 0.0)) continue;
    const std::size_t bins = std::min(
        max_bins, std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(segment_length / bin))));
    std::uint32_t through = 0, in_place = 0;
    const double min_x = std::min(m.start.x(), m.end.x()), max_x = std::max(m.start.x(), m.end.x());
    const double min_y = std::min(m.start.y(), m.end.y()), max_y = std::max(m.start.y(), m.end.y());
    for (const FreeSpaceWitness& w : witnesses)
    {
      if (max_x < w.box[0] || min_x > w.box[2] || max_y < w.box[1] || min_y > w.box[3]) continue;
      through |= insideBins(m, w.free, 3, bins);
      in_place |= insideBins(m, w.band, 4, bins);
    }
    const std::uint32_t seen_through = through & ~in_place;
    length +=
        segment_length * static_cast<double>(__builtin_popcount(seen_through)) / static_cast<double>(bins);
  }
  return length;
}

std::optional<linemap::Pose2> FleetPlacement::placement(std::size_t robot) const
{
  const auto it = searches_.find(robot);
  return it == searches_.end() ? std::nullopt : it->second.placed;
}

std::size_t FleetPlacement::searched(std::size_t robot) const
{
  const auto it = searches_.find(robot);
  return it == searches_.end() ? 0 : it->second.scans;
}

std::vector<std::pair<std::string, std::string>> FleetPlacement::diagnostics() const
{
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [robot, search] : searches_)
  {
    std::string state;
    if (search.placed)
      state = "placed after " + std::to_string(search.scans) + " scans at (" +
              std::to_string(search.placed->x) + ", " + std::to_string(search.placed->y) + ", " +
              std::to_string(search.placed->theta) + ")";
    else
      state = "looked for in the fleet's map: " + std::to_string(search.scans) + " scans, " +
              std::to_string(search.refused) + " places refused as seeing through its walls";
    out.emplace_back("robot " + std::to_string(robot), state);
  }
  return out;
}

}  // namespace line_map_merging
