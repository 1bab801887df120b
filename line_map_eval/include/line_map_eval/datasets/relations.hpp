// The relations metric of Kümmerle et al., "On measuring the accuracy of SLAM algorithms"
// (Autonomous Robots 2009), ROS-free: for every reference relation (t1, t2, delta*) the estimated
// relative pose delta = x(t1)^-1 * x(t2) is compared with it, error = delta*^-1 * delta; reported
// are the mean and standard deviation of |translation(error)| and |rotation(error)| (absolute
// values, as the paper's tables and later work report them).
// Relation files: one relation per line, `t1 t2 dx dy dz roll pitch yaw` (metres, radians), the
// timestamps equal to FLASER timestamps of the raw log; only dx, dy, yaw are used.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_map_eval
{
struct Relation
{
  double t1 = 0.0, t2 = 0.0;
  linemap::Pose2 delta;  ///< pose(t1)^-1 * pose(t2)
};

/// Reads a relations file; throws std::runtime_error naming the file and line on a malformed line.
std::vector<Relation> readRelations(const std::string& path);

struct RelationsError
{
  std::size_t relations = 0;                             ///< in the file
  std::size_t used = 0;                                  ///< both timestamps found in the trajectory
  double translation_mean = 0.0, translation_std = 0.0;  ///< [m]
  double rotation_mean = 0.0, rotation_std = 0.0;        ///< [rad]
  double translation_max = 0.0, rotation_max = 0.0;
};

/// One relation measured on a trajectory.
struct RelationResidual
{
  std::size_t relation = 0;                  ///< index into the relations
  linemap::Pose2 first, second;              ///< the trajectory's poses at t1 and t2
  double translation = 0.0, rotation = 0.0;  ///< |translation|, |rotation| of delta*^-1 * delta [m, rad]
};

/// Every relation both of whose timestamps are in `poses` (as relationsError takes them), in order.
std::vector<RelationResidual> relationResiduals(const std::vector<Relation>& relations,
                                                const std::vector<std::pair<double, linemap::Pose2>>& poses,
                                                double tolerance = 1e-4);

/// The metric of `poses` (timestamp, pose), any order; a relation timestamp takes the pose whose
/// timestamp is nearest to it within `tolerance` [s], else the relation is not used.
RelationsError relationsError(const std::vector<Relation>& relations,
                              const std::vector<std::pair<double, linemap::Pose2>>& poses,
                              double tolerance = 1e-4);

}  // namespace line_map_eval
