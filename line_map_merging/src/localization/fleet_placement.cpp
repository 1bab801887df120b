#include "line_map_merging/localization/fleet_placement.hpp"

#include <cmath>
#include <stdexcept>

#include "line_map_merging/map/free_space_witness.hpp"

namespace line_map_merging
{
std::vector<linemap::Vec2> segmentPoints(const std::vector<linemap::Segment2>& segments,
                                         const linemap::Pose2& pose, double spacing)
{
  std::vector<linemap::Segment2> moved;
  moved.reserve(segments.size());
  for (const linemap::Segment2& s : segments) moved.push_back(s.transformed(pose));
  return sampleSegments(moved, spacing);
}

FleetPlacement::FleetPlacement(const LocalizerParams& params, double confirm_path, double point_spacing)
    : params_(params), confirm_path_(confirm_path), point_spacing_(point_spacing)
{
  if (!(point_spacing_ > 0.0)) throw std::invalid_argument("fleet placement: point_spacing must be positive");
  if (!(confirm_path_ >= 0.0)) throw std::invalid_argument("fleet placement: confirm_path must be >= 0");
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
  Search& search = searches_.try_emplace(robot, confirm_path_).first->second;
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
  const std::vector<linemap::Vec2> points = sightPoints(search);
  const linemap::Pose2 placed = refined(points, implied);
  if (ambiguous(points, placed, map_))
  {
    ++search.ambiguous;
    search.confirmation.reset();
    return std::nullopt;
  }
  search.placed = placed;
  search.localizer.reset();
  return search.placed;
}

std::vector<linemap::Vec2> FleetPlacement::sightPoints(const Search& search) const
{
  std::vector<linemap::Vec2> points;
  for (const Sight& sight : search.sights)
  {
    const std::vector<linemap::Vec2> seen = segmentPoints(sight.segments, sight.laser, point_spacing_);
    points.insert(points.end(), seen.begin(), seen.end());
  }
  return points;
}

SegmentMatch FleetPlacement::matchSights(const LocalizationSegmentIndex& index,
                                         const std::vector<linemap::Vec2>& points,
                                         const linemap::Pose2& from) const
{
  SegmentMatchParams match = params_.match;
  match.check_free_side = false;  // the points come from many places
  return matchToSegments(index, points, from, std::nullopt, match);
}

linemap::Pose2 FleetPlacement::refined(const std::vector<linemap::Vec2>& points,
                                       const linemap::Pose2& placed) const
{
  // Every sight at once, in the robot's own map frame: the whole way it came, not one scan, pins the
  // rotation down.
  const SegmentMatch m = matchSights(
      LocalizationSegmentIndex(map_, params_.index_cell, params_.match.max_distance), points, placed);
  if (!m.valid) return placed;
  const linemap::Pose2 change = placed.inverse() * m.pose;
  const bool near = std::hypot(change.x, change.y) <= PlaceConfirmation::max_xy &&
                    std::fabs(change.theta) <= PlaceConfirmation::max_theta;
  return near ? m.pose : placed;
}

bool FleetPlacement::ambiguous(std::size_t robot, const linemap::Pose2& placed,
                               const std::vector<linemap::Segment2>& map) const
{
  const auto it = searches_.find(robot);
  return it != searches_.end() && ambiguous(sightPoints(it->second), placed, map);
}

bool FleetPlacement::ambiguous(const std::vector<linemap::Vec2>& points, const linemap::Pose2& placed,
                               const std::vector<linemap::Segment2>& map) const
{
  // The way the robot came searched for over the whole map: a rival placement elsewhere that explains it
  // about as well (a building alike half a turn away) leaves the place open until the robot has seen what
  // tells them apart. Evidence is counted in points explained, not as a share: what differs is a few pieces
  // of furniture among metres of look-alike walls.
  const LocalizationGlobalSearch global(map, params_.global);
  const SegmentMatchParams& match = params_.match;
  const LocalizationSegmentIndex index(map, params_.index_cell, match.max_distance);
  const auto explained = [&](const linemap::Pose2& pose)
  { return evaluateOnSegments(index, points, pose, match).score * static_cast<double>(points.size()); };
  const double own = explained(placed);
  const double needed = min_evidence / point_spacing_;
  const auto distinct = [&](const linemap::Pose2& pose)
  {
    const linemap::Pose2 apart = placed.inverse() * pose;
    return std::hypot(apart.x, apart.y) >= params_.global.separation ||
           std::fabs(linemap::normalizeAngle(apart.theta)) >= params_.global.separation_angle;
  };
  for (const MatchResult& candidate : global.search(points))
  {
    if (!distinct(candidate.pose)) continue;
    const SegmentMatch rival = matchSights(index, points, candidate.pose);  // may slide back onto `placed`
    if (rival.valid && distinct(rival.pose) && explained(rival.pose) > own - needed) return true;
  }
  return false;
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
    const std::string refused = std::to_string(search.refused) +
                                " places refused as seeing through its walls, " +
                                std::to_string(search.ambiguous) + " as ambiguous";
    std::string state;
    if (search.placed)
      state = "placed after " + std::to_string(search.scans) + " scans at (" +
              std::to_string(search.placed->x) + ", " + std::to_string(search.placed->y) + ", " +
              std::to_string(search.placed->theta) + "); " + refused;
    else
      state = "looked for in the fleet's map: " + std::to_string(search.scans) + " scans; " + refused;
    out.emplace_back("robot " + std::to_string(robot), state);
  }
  return out;
}

}  // namespace line_map_merging
