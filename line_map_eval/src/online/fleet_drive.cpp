#include "line_map_eval/online/fleet_drive.hpp"

#include <stdexcept>

namespace line_map_eval
{
namespace
{
std::vector<linemap::Segment2> mapSegments(const line_map_merging::Merger& merger)
{
  std::vector<linemap::Segment2> out;
  for (const auto& s : merger.map()) out.push_back(s.segment);
  return out;
}
}  // namespace

FleetDrive driveFleet(line_map_merging::OnlineMapper& mapper, line_map_merging::FleetPlacement& placement,
                      const std::vector<FleetRobot>& robots)
{
  FleetDrive out;
  out.placed_at.assign(robots.size(), std::nullopt);
  out.placements.assign(robots.size(), std::nullopt);
  if (robots.empty()) return out;
  out.placed_at[0] = 0;
  out.placements[0] = Pose2();
  std::vector<std::size_t> next_scan(robots.size(), 0), next_trajectory(robots.size(), 0);
  std::uint64_t searched_revision = ~std::uint64_t{0};
  for (;;)
  {
    // The robot whose next scan is the oldest.
    std::optional<std::size_t> robot;
    for (std::size_t r = 0; r < robots.size(); ++r)
    {
      const Recording& rec = *robots[r].recording;
      if (next_scan[r] >= rec.scans.size()) continue;
      if (!robot || rec.scans[next_scan[r]].stamp < robots[*robot].recording->scans[next_scan[*robot]].stamp)
        robot = r;
    }
    if (!robot) break;
    const FleetRobot& f = robots[*robot];
    const std::size_t i = next_scan[*robot]++;
    const line_map_merging::StampedScan scan = [&]
    {
      line_map_merging::StampedScan s = stampedScan(*f.recording, f.schedule, f.segments, i);
      s.lane = *robot;
      return s;
    }();
    if (!out.placements[*robot])
    {
      if (mapper.revision() != searched_revision)
      {
        placement.setMap(mapSegments(mapper.merger()));
        searched_revision = mapper.revision();
      }
      if (const auto placed = placement.addScan(*robot, scan.stamp, scan.segments, scan.laser, scan.mount))
      {
        out.placements[*robot] = placed;
        out.placed_at[*robot] = i;
        mapper.placeLane(*robot, *placed);
      }
    }
    mapper.addScan(scan);
    auto& next = next_trajectory[*robot];
    for (; next < f.schedule.trajectories.size() && f.schedule.trajectories[next].stamp <= scan.stamp; ++next)
      mapper.addTrajectory(f.schedule.trajectories[next].poses, *robot);
  }
  return out;
}

}  // namespace line_map_eval
