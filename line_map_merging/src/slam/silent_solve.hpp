// One Ceres solve as the SLAM front and back end run it: on one thread (repeatable results) and silent.
#pragma once

#include <ceres/ceres.h>

namespace line_map_merging
{
/// Solves `problem` with `linear_solver` in at most `max_iterations`.
inline ceres::Solver::Summary solveSilently(ceres::Problem& problem, ceres::LinearSolverType linear_solver,
                                            int max_iterations)
{
  ceres::Solver::Options options;
  options.linear_solver_type = linear_solver;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary;
}
}  // namespace line_map_merging
