#include "line_map_eval/batch/slam_figure.hpp"

#include "line_map_eval/metrics/lookup_table.hpp"

namespace line_map_eval
{
MapFigure slamFigure(const Recording& recording, const SlamRecordingResult& slam,
                     const std::vector<RelationResidual>* residuals, const std::string& caption,
                     double bad_relation)
{
  MapFigure f;
  f.caption = caption;
  f.show_slam = true;
  f.scan_points = registeredScanPoints(recording, slam.keyframes);
  f.trajectory.reserve(slam.scan_poses.size());
  for (const Pose2& p : slam.scan_poses) f.trajectory.push_back(p.translation());
  for (const auto& c : slam.closures)
  {
    if (c.from >= slam.keyframes.size() || c.to >= slam.keyframes.size()) continue;
    const linemap::Segment2 line(slam.keyframes[c.from].pose.translation(),
                                 slam.keyframes[c.to].pose.translation());
    (c.outcome == line_map_merging::ClosureOutcome::kAccepted ? f.accepted_closures : f.rejected_closures)
        .push_back(line);
  }
  if (residuals)
  {
    f.show_relations = true;
    f.bad_relation = bad_relation;
    for (const RelationResidual& r : *residuals)
      if (r.translation > bad_relation)
        f.bad_relations.emplace_back(r.first.translation(), r.second.translation());
  }
  return f;
}

std::vector<std::string> drawSlamRun(const Recording& recording, const SlamRecordingResult& slam,
                                     const std::vector<RelationResidual>* residuals,
                                     const std::string& caption, const std::string& path, unsigned formats)
{
  return drawMap(slamFigure(recording, slam, residuals, caption), path, formats);
}

}  // namespace line_map_eval
