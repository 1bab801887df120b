// The figure of a laser SLAM run (ROS-free), drawn by figures.hpp: where a run went wrong. The
// keyframes' scans at their optimised poses (light), the trajectory of every scan, each loop-closure
// attempt that got as far as a match as a line between its two keyframes (accepted and rejected
// apart) and, when relations were measured, those whose error exceeds a bound between their two
// scans' positions. `linemap_batch --slam` and `linemap_relations --slam` write it.
#pragma once

#include <string>
#include <vector>

#include "line_map_eval/batch/figures.hpp"
#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/datasets/relations.hpp"
#include "line_map_eval/datasets/slam_recording.hpp"

namespace line_map_eval
{
/// The layers of a SLAM run on `recording` (the scans it was run on). `residuals` (of the run's scan
/// poses; null: no relations) above `bad_relation` [m] in translation are marked.
MapFigure slamFigure(const Recording& recording, const SlamRecordingResult& slam,
                     const std::vector<RelationResidual>* residuals, const std::string& caption,
                     double bad_relation = 0.3);

/// slamFigure written to `path` (+ ".svg", ".png" by `formats`, as drawMap); the files written.
std::vector<std::string> drawSlamRun(const Recording& recording, const SlamRecordingResult& slam,
                                     const std::vector<RelationResidual>* residuals,
                                     const std::string& caption, const std::string& path,
                                     unsigned formats = kFigureSvg | kFigurePng);

}  // namespace line_map_eval
