#include "line_map_merging/localization/fleet_placement.hpp"

#include <cmath>
#include <stdexcept>

#include "line_map_merging/localization/placement_judge.hpp"

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
  if (search.way.move(laser)) search.way.add(segmentSight(laser, segments, point_spacing_));

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
  const PlacementJudge::Verdict verdict = PlacementJudge(map_, params_, see_through_margin, max_seen_through)
                                              .judge(search.way, implied, minEvidencePoints());
  switch (verdict.outcome)
  {
    case PlacementJudge::Outcome::kSeenThrough:
      ++search.refused;
      search.confirmation.reset();
      search.localizer->startGlobalLocalization();
      return std::nullopt;
    case PlacementJudge::Outcome::kAmbiguous:
      ++search.ambiguous;
      search.confirmation.reset();
      return std::nullopt;
    case PlacementJudge::Outcome::kPlaced:
      break;
  }
  search.placed = verdict.place;
  search.localizer.reset();
  return search.placed;
}

bool FleetPlacement::ambiguous(std::size_t robot, const linemap::Pose2& placed,
                               const std::vector<linemap::Segment2>& map) const
{
  const auto it = searches_.find(robot);
  if (it == searches_.end()) return false;
  const PlacementJudge judge(map, params_, see_through_margin, max_seen_through);
  const PlacementJudge::Verdict verdict = judge.judge(it->second.way, placed, minEvidencePoints());
  return verdict.outcome != PlacementJudge::Outcome::kPlaced || judge.apart(placed, verdict.place);
}

double FleetPlacement::seenThroughLength(std::size_t robot, const linemap::Pose2& placed,
                                         const std::vector<linemap::Segment2>& map) const
{
  const auto it = searches_.find(robot);
  return it == searches_.end() ? 0.0
                               : PlacementJudge(map, params_, see_through_margin, max_seen_through)
                                     .seenThroughLength(it->second.way, placed);
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
