// Ground truth of a simulated recording (ROS-free): the true lines (the faces of the walls)
// and, per scan, the true laser pose and the face pieces the scan sees. Stored next to the bag
// as OUT.truth.yaml (format linemap_truth/2) for the map metrics.
//
// linemap_truth/2 (since walls have thickness): `walls` lists the true FACES, each directed with
// free space on its left (the project's segment orientation), and `solids` the world's walls
// (centre line and thickness) they come from; `visible[].wall` indexes `walls`. In
// linemap_truth/1 `walls` were the world's thin, undirected walls; such files are refused.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "line_map_eval/simulation/wall_faces.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
inline constexpr const char* kTruthFormat = "linemap_truth/2";

/// The part of face `wall` between the extreme beam hits of one scan, map frame,
/// directed like the face.
struct VisibleWall
{
  std::size_t wall = 0;
  linemap::Segment2 segment;
  std::size_t beams = 0;  ///< beams whose true ray ends on this face
  /// The pieces of `segment` hit by runs of consecutive beams, along the face, when there is more
  /// than one: between two runs the face hides behind something nearer (a pillar) and is not seen
  /// by this scan. Empty: `segment` is one run.
  std::vector<linemap::Segment2> runs;

  bool operator==(const VisibleWall& o) const
  {
    const auto same = [](const linemap::Segment2& a, const linemap::Segment2& b)
    { return a.start == b.start && a.end == b.end; };
    return wall == o.wall && same(segment, o.segment) && beams == o.beams &&
           std::equal(runs.begin(), runs.end(), o.runs.begin(), o.runs.end(), same);
  }
};

struct TruthScan
{
  double stamp = 0.0;
  linemap::Pose2 pose;  ///< TRUE pose of the laser in the map frame
  std::vector<VisibleWall> visible;
};

struct TruthLaser
{
  std::size_t beams = 0;
  double angle_min = 0.0, angle_increment = 0.0;
  double range_min = 0.0, range_max = 0.0;
  double sigma = 0.0, spurious = 0.0;
  double sigma_slope = 0.0;  ///< range noise std sigma + sigma_slope r (key absent: 0)
};

struct GroundTruth
{
  std::string world;
  TruthLaser laser;
  linemap::Pose2 base_to_laser;
  std::size_t min_beams = 1;  ///< hits a face needs to be listed as visible
  std::vector<Wall> solids;   ///< the world's walls (centre lines and thicknesses)
  /// The true lines: the faces of `solids` (wallFaces()), free side on the left.
  std::vector<linemap::Segment2> walls;
  /// The faces of each curved surface (a side of an arc: curveFaces()), in order along it. A curve
  /// is seen as a whole: a scan sights its consecutive visible faces together, as an extractor fits
  /// lines across the chords of a curve (key `curves`, absent: none).
  std::vector<std::vector<std::size_t>> curves;
  std::vector<TruthScan> scans;
  /// Stds of the error of the registered keyframe poses the map is built on (world key
  /// `registration`; key `registration` here, absent: 0): a wall seen from range r is expected that
  /// far off in the map, sqrt(position^2 + (heading r)^2), and is scored with that much slack.
  double registration_position = 0.0;  ///< [m]
  double registration_heading = 0.0;   ///< [rad]
};

/// The wall pieces one scan sees: `hit_wall[i]` is the wall (face) beam i's noiseless ray ends
/// on (-1: none or beyond range) and `hit_range[i]` its true range; beam i points at
/// laser_pose.theta + angle_min + i * angle_increment. A wall hit by >= min_beams beams is
/// listed with the span between its extreme hit points and, when beams of nearer walls interrupt
/// it, the runs of consecutive beams that hit it; sorted by wall index. A face of one of
/// `curves` counts with its sight (sights()): its pieces are listed when together hit by >= min_beams.
std::vector<VisibleWall> visibleWallPieces(const std::vector<linemap::Segment2>& walls,
                                           const linemap::Pose2& laser_pose, double angle_min,
                                           double angle_increment, const std::vector<int>& hit_wall,
                                           const std::vector<double>& hit_range, std::size_t min_beams,
                                           const std::vector<std::vector<std::size_t>>& curves = {});

/// The sights of one scan's visible pieces: indices into `visible`, one group per piece of a
/// straight face, and one per run of consecutive faces of a curve that are all visible in the scan
/// and share their ends (the last and first faces of a closed curve too), in order of their first
/// piece. `walls` are the faces `visible` and `curves` index; throws std::invalid_argument for a
/// curve listing a face beyond them.
std::vector<std::vector<std::size_t>> sights(const std::vector<linemap::Segment2>& walls,
                                             const std::vector<VisibleWall>& visible,
                                             const std::vector<std::vector<std::size_t>>& curves);

/// OUT.bag -> OUT.truth.yaml (any other name gets ".truth.yaml" appended).
std::string truthPathForBag(const std::string& bag_path);

/// Writes the file with every double in its shortest exact form (a read gives the same values).
/// Throws std::runtime_error naming the file on failure.
void writeGroundTruth(const GroundTruth& truth, const std::string& path);

/// Reads a linemap_truth/2 file; throws std::runtime_error naming the file and key on bad input.
GroundTruth readGroundTruth(const std::string& path);

}  // namespace line_map_eval
