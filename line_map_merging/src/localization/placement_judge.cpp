#include "line_map_merging/localization/placement_judge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "line_map_merging/localization/fleet_placement.hpp"
#include "line_map_merging/localization/place_confirmation.hpp"
#include "line_map_merging/map/free_space_witness.hpp"

namespace line_map_merging
{
Sight segmentSight(const linemap::Pose2& laser, const std::vector<linemap::Segment2>& segments,
                   double spacing)
{
  return {laser, segmentPoints(segments, linemap::Pose2(), spacing), segments};
}

Sight scanSight(const linemap::Pose2& laser, const std::vector<linemap::Vec2>& returns, double spacing,
                double fan, double gap)
{
  Sight sight{laser, {}, {}};
  for (const linemap::Vec2& p : returns)
    if (sight.points.empty() || (p - sight.points.back()).norm() >= spacing) sight.points.push_back(p);
  // Fans of beams: every beam of a fan reached at least its nearest return, so the fan's sector up to that
  // range, and the triangle under its chord, was crossed.
  std::size_t first = 0;
  while (first < returns.size())
  {
    const double start = std::atan2(returns[first].y(), returns[first].x());
    double last_angle = start, nearest = returns[first].norm();
    std::size_t end = first + 1;
    for (; end < returns.size(); ++end)
    {
      const double angle = std::atan2(returns[end].y(), returns[end].x());
      if (std::fabs(linemap::normalizeAngle(angle - last_angle)) > gap ||
          std::fabs(linemap::normalizeAngle(angle - start)) > fan)
        break;
      last_angle = angle;
      nearest = std::min(nearest, returns[end].norm());
    }
    if (end - first >= 2)
      sight.free.emplace_back(linemap::Vec2(nearest * std::cos(start), nearest * std::sin(start)),
                              linemap::Vec2(nearest * std::cos(last_angle), nearest * std::sin(last_angle)));
    first = end;
  }
  return sight;
}

Way::Way(double spacing, double turn, double window) : spacing_(spacing), turn_(turn), window_(window) {}

bool Way::move(const linemap::Pose2& laser)
{
  if (last_) path_ += (laser.translation() - last_->translation()).norm();
  last_ = laser;
  return sights_.empty() || (sights_.back().laser.translation() - laser.translation()).norm() >= spacing_ ||
         std::fabs(linemap::normalizeAngle(sights_.back().laser.theta - laser.theta)) >= turn_;
}

void Way::add(Sight sight)
{
  sights_.push_back(std::move(sight));
  sight_paths_.push_back(path_);
  while (sights_.size() > 1 && path_ - sight_paths_.front() > window_)
  {
    sights_.pop_front();
    sight_paths_.pop_front();
  }
}

std::vector<linemap::Vec2> Way::points() const
{
  std::vector<linemap::Vec2> out;
  for (const Sight& sight : sights_)
    for (const linemap::Vec2& p : sight.points) out.push_back(sight.laser.apply(p));
  return out;
}

void Way::clear()
{
  sights_.clear();
  sight_paths_.clear();
  last_.reset();
  path_ = 0.0;
}

PlacementJudge::PlacementJudge(const std::vector<linemap::Segment2>& map, const LocalizerParams& params,
                               double margin, double max_seen_through)
    : map_(map),
      params_(params),
      margin_(margin),
      max_seen_through_(max_seen_through),
      index_(map, params.index_cell, params.match.max_distance),
      global_(map, params.global)
{
}

SegmentMatch PlacementJudge::match(const std::vector<linemap::Vec2>& points, const linemap::Pose2& from) const
{
  SegmentMatchParams match = params_.match;
  match.check_free_side = false;  // the points come from many places
  return matchToSegments(index_, points, from, std::nullopt, match);
}

double PlacementJudge::explained(const std::vector<linemap::Vec2>& points, const linemap::Pose2& pose) const
{
  return evaluateOnSegments(index_, points, pose, params_.match).score * static_cast<double>(points.size());
}

linemap::Pose2 PlacementJudge::refined(const std::vector<linemap::Vec2>& points,
                                       const linemap::Pose2& placed) const
{
  const SegmentMatch m = match(points, placed);
  if (!m.valid) return placed;
  const linemap::Pose2 change = placed.inverse() * m.pose;
  const bool near = std::hypot(change.x, change.y) <= PlaceConfirmation::max_xy &&
                    std::fabs(change.theta) <= PlaceConfirmation::max_theta;
  return near ? m.pose : placed;
}

void PlacementJudge::setMapFreeSpace(const std::vector<Sighting>& sightings)
{
  OccupancyGridParams grid;
  grid.resolution = 0.1;
  map_free_ = buildOccupancyGrid(map_, sightings, grid);
  // Free cells within the margin of a wall are not counted: the map's and the way's registration error.
  const int reach = static_cast<int>(std::ceil(margin_ / grid.resolution));
  std::vector<std::int8_t> eroded = map_free_.cells;
  for (int row = 0; row < map_free_.height; ++row)
    for (int column = 0; column < map_free_.width; ++column)
    {
      if (map_free_.at(column, row) != OccupancyGrid::kOccupied) continue;
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx)
          if (dx * dx + dy * dy <= reach * reach && map_free_.contains(column + dx, row + dy))
            eroded[static_cast<std::size_t>(row + dy) * map_free_.width + column + dx] =
                OccupancyGrid::kUnknown;
    }
  map_free_.cells = std::move(eroded);
}

std::size_t PlacementJudge::pointsInFreeSpace(const std::vector<linemap::Vec2>& points,
                                              const linemap::Pose2& placed) const
{
  if (map_free_.cells.empty()) return 0;
  return static_cast<std::size_t>(std::count_if(
      points.begin(), points.end(),
      [&](const linemap::Vec2& p) { return map_free_.valueAt(placed.apply(p)) == OccupancyGrid::kFree; }));
}

bool PlacementJudge::apart(const linemap::Pose2& a, const linemap::Pose2& b) const
{
  const linemap::Pose2 d = a.inverse() * b;
  return std::hypot(d.x, d.y) >= params_.global.separation ||
         std::fabs(linemap::normalizeAngle(d.theta)) >= params_.global.separation_angle;
}

std::vector<PlacementJudge::Place> PlacementJudge::weigh(const std::vector<linemap::Vec2>& points,
                                                         const linemap::Pose2& placed,
                                                         const std::vector<linemap::Pose2>& also) const
{
  std::vector<Place> places;
  const linemap::Pose2 own = refined(points, placed);
  places.push_back({explained(points, own), own, false});
  for (const linemap::Pose2& start : also)
  {
    // Where the way has run out of the map the match may fail: the place is then weighed where it was.
    const SegmentMatch m = match(points, start);
    const linemap::Pose2 pose = m.valid && !apart(start, m.pose) ? m.pose : start;
    places.push_back({explained(points, pose), pose, true});
  }
  for (const MatchResult& candidate : global_.search(points))
  {
    const SegmentMatch m = match(points, candidate.pose);  // may slide onto another candidate
    if (m.valid) places.push_back({explained(points, m.pose), m.pose, false});
  }
  std::stable_sort(places.begin(), places.end(),
                   [](const Place& l, const Place& r) { return l.score > r.score; });
  return places;
}

const PlacementJudge::Contradiction& PlacementJudge::contradictionOf(const Way& way,
                                                                     const std::vector<linemap::Vec2>& points,
                                                                     const Place& place) const
{
  if (!place.contradiction)
    place.contradiction =
        Contradiction{seenThroughLength(way, place.pose), pointsInFreeSpace(points, place.pose)};
  return *place.contradiction;
}

const PlacementJudge::Place* PlacementJudge::best(const Way& way, const std::vector<linemap::Vec2>& points,
                                                  const std::vector<Place>& places, double min_evidence,
                                                  double rival_share) const
{
  // The best place is the one explaining most points that neither sees through walls nor puts more than a
  // tenth of the points (registration error, people) in the map's free space; one explaining less than half
  // of what the foremost place explains is none (where everything that fits is contradicted, nothing is).
  const double allowed_in_free = std::max(min_evidence, 0.1 * static_cast<double>(points.size()));
  std::vector<const Place*> uncontradicted;
  for (const Place& place : places)
  {
    if (place.score < 0.5 * places.front().score) break;
    const Contradiction& c = contradictionOf(way, points, place);
    if (c.seen_through > max_seen_through_ || static_cast<double>(c.in_free) > allowed_in_free) continue;
    uncontradicted.push_back(&place);
  }
  // Points where the map's scans saw free space contradict a place; points where they never looked contradict
  // nothing. So a place may explain less of the way only because the way runs out of the map there: the best
  // place yields to such a place, apart from it and explaining a rival's share of its points, when it puts
  // clearly more of the way in free space than the registration error and people would.
  const double clearly_more =
      std::max(min_evidence, kContradictionShare * static_cast<double>(points.size()));
  const auto yields = [&](const Place* p)
  {
    return std::any_of(uncontradicted.begin(), uncontradicted.end(),
                       [&](const Place* other)
                       {
                         return apart(p->pose, other->pose) && other->score >= rival_share * p->score &&
                                static_cast<double>(p->contradiction->in_free) >
                                    2.0 * static_cast<double>(other->contradiction->in_free) + clearly_more;
                       });
  };
  const auto chosen = std::find_if_not(uncontradicted.begin(), uncontradicted.end(), yields);
  return chosen == uncontradicted.end() ? nullptr : *chosen;
}

PlacementJudge::Verdict PlacementJudge::judge(const Way& way, const linemap::Pose2& placed,
                                              double min_evidence, double rival_share,
                                              const std::vector<linemap::Pose2>& also) const
{
  const std::vector<linemap::Vec2> points = way.points();
  const std::vector<Place> places = weigh(points, placed, also);
  Verdict verdict;
  const Place* chosen = best(way, points, places, min_evidence, rival_share);
  if (!chosen) return verdict;
  const std::size_t chosen_in_free = chosen->contradiction->in_free;
  // A rival counts when it explains about as much (or, with unknown space, a share of as much; or it was a
  // rival before) and is not more contradicted than the best.
  const double needed = std::min(chosen->score - min_evidence, rival_share * chosen->score);
  for (const Place& place : places)
  {
    if (&place == chosen || !apart(chosen->pose, place.pose) || (!place.kept && place.score <= needed) ||
        std::any_of(verdict.rivals.begin(), verdict.rivals.end(),
                    [&](const linemap::Pose2& r) { return !apart(r, place.pose); }))
      continue;
    const Contradiction& c = contradictionOf(way, points, place);
    if (c.seen_through > max_seen_through_ ||
        static_cast<double>(c.in_free) > static_cast<double>(chosen_in_free) + min_evidence)
      continue;
    verdict.rivals.push_back(place.pose);
  }
  verdict.place = chosen->pose;
  verdict.outcome = verdict.rivals.empty() ? Outcome::kPlaced : Outcome::kAmbiguous;
  return verdict;
}

double PlacementJudge::seenThroughLength(const Way& way, const linemap::Pose2& placed) const
{
  std::vector<FreeSpaceWitness> witnesses;
  for (const Sight& sight : way.sights())
  {
    const linemap::Pose2 laser = placed * sight.laser;
    for (const linemap::Segment2& s : sight.free)
    {
      FreeSpaceWitness w;
      if (makeWitness(laser.translation(), s.transformed(laser), margin_, w)) witnesses.push_back(w);
    }
  }
  // Per map segment, bins of about 0.1 m: seen through by some witness and in place by none.
  constexpr double bin = 0.1;
  constexpr std::size_t max_bins = 32;
  double length = 0.0;
  for (const linemap::Segment2& m : map_)
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

}  // namespace line_map_merging
