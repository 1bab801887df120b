// Metrics of a line map against the true lines of a simulated world (ROS-free): per face
// coverage and endpoint error, and the vertex accuracy at the true corners -- all over what the
// robot SAW. A map can only hold what its scans showed: the parts of a wall never in sight, the
// back of a cabinet, the far end of an outer wall glimpsed through a door, are no map error.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "line_map_eval/simulation/ground_truth.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// Keys "eval/gt_..." (see config/line_map_eval.yaml).
struct GroundTruthParams
{
  double coverage_tolerance = 0.05;                      ///< a face sample is covered within this [m]
  double sample_spacing = 0.01;                          ///< distance between face samples [m]
  double association_angle = 10.0 * linemap::kPi / 180;  ///< map segment vs face [rad]
  double association_distance = 0.2;                     ///< map segment to the face's line [m]
  /// Compare directed headings (segments and faces share the free-side-left orientation), so a
  /// segment on one face of a wall never counts for the other face 10 cm away.
  bool directed = true;
  /// A visible piece is a sight of its face when at least this long [m] and hit by at least
  /// min_seen_beams beams: the default extractor's minimums (srg/min_length, srg/min_points), as in
  /// the extraction benchmark; a shorter or sparser glimpse gives no segment to map.
  double min_seen_length = 0.6;
  std::size_t min_seen_beams = 10;
  double corner_tolerance = 0.01;                       ///< face endpoints this close meet [m]
  double corner_min_angle = 20.0 * linemap::kPi / 180;  ///< faces meeting straighter are no corner [rad]
  double vertex_radius = 0.3;                           ///< map endpoints within this of a corner [m]
  /// Under a registration error (GroundTruth::registration_*), a face's coverage tolerance and
  /// association distance grow by this many stds of the error expected at its mean sighting range.
  double registration_sigmas = 2.0;
  /// A face part is also seen when all scans together hit it with min_seen_beams beams per
  /// min_seen_length (accumulatedSeenParts): a wall seen from afar by a few beams per scan, as the map
  /// as a whole sees it.
  bool accumulate_sightings = true;

  static GroundTruthParams fromParams(const linemap::ParamSet& params);
  void validate() const;
};

/// Per face, the parts of it the scans saw: sorted, disjoint [from, to] intervals in metres from
/// the face's start.
using SeenParts = std::vector<std::vector<std::pair<double, double>>>;

/// The union, per face of `truth.walls`, of the visible pieces of every scan whose sight (sights():
/// the piece alone, or the run of consecutive faces of a curve it is part of) is at least
/// `min_piece_length` long and hit by at least `min_piece_beams` beams in total.
SeenParts seenParts(const GroundTruth& truth, double min_piece_length, std::size_t min_piece_beams = 0);

/// Per face, the parts whose hits over all scans (each visible piece's beams spread evenly over its
/// runs) reach min_beams within every window of min_length about them, in stretches at least
/// min_length long; resolved to `bin` metres. Sorted, disjoint, like seenParts.
SeenParts accumulatedSeenParts(const GroundTruth& truth, double min_length, std::size_t min_beams,
                               double bin = 0.05);

/// The union of two sets of seen parts of the same faces.
SeenParts unionOfSeenParts(const SeenParts& a, const SeenParts& b);

struct WallScore
{
  std::size_t face = 0;       ///< index into the faces
  linemap::Segment2 segment;  ///< the face, its free side on the left
  double length = 0.0;        ///< of the face [m]
  double seen_length = 0.0;   ///< of its seen parts [m]
  /// Fraction of the samples of the seen parts within coverage_tolerance of an associated segment.
  double coverage = 0.0;
  /// Largest distance from a seen and mapped face endpoint to the nearest endpoint of an
  /// associated map segment [m]; 0 when there is none, +infinity when no segment is associated.
  double endpoint_error = 0.0;
  std::size_t seen_endpoints = 0;    ///< 0, 1 or 2
  std::size_t mapped_endpoints = 0;  ///< of those, the ends an associated segment reaches
  std::size_t associated = 0;        ///< map segments associated with the face
};

struct CornerScore
{
  linemap::Vec2 corner = linemap::Vec2::Zero();
  double vertex_error = 0.0;  ///< sum of distances from the corner to the map endpoints near it [m]
  std::size_t endpoints = 0;  ///< endpoints within vertex_radius of segments associated with its faces
};

struct GroundTruthResult
{
  std::vector<WallScore> walls;      ///< the seen faces
  std::vector<CornerScore> corners;  ///< the seen corners
  double coverage = 0.0;             ///< seen-length-weighted mean face coverage in [0, 1]
  double max_endpoint_error = 0.0;   ///< over the seen and mapped face endpoints [m]
  double mean_endpoint_error = 0.0;  ///< same, mean [m]
  std::size_t unmapped_ends = 0;     ///< seen face endpoints no associated segment reaches
  std::size_t undetected_walls = 0;  ///< seen faces without any associated map segment
  std::size_t unseen_walls = 0;      ///< faces no scan saw (not scored)
  double mean_vertex_error = 0.0;    ///< mean over the corners with endpoints of their vertex_error [m]
  std::size_t missed_corners = 0;    ///< seen corners without any map endpoint within vertex_radius
};

/// Scores `map` against the faces `walls`, over their seen parts `seen` (one entry per face; a
/// face without seen parts is not scored). A map segment is associated with a face when their
/// heading difference (directed, or undirected with directed = false) is at most
/// association_angle, it overlaps the face along the face's direction, and over that overlap it
/// stays within association_distance of the face's line (so a segment running on over two
/// collinear faces, e.g. across a 10 cm partition, belongs to both).
/// Coverage samples each seen interval every <= sample_spacing (both ends included) and counts
/// the samples within coverage_tolerance of an associated segment, so a perpendicular face's
/// segment ending at a corner does not count as covering it. A face endpoint is seen when a seen
/// interval reaches within coverage_tolerance of it, and mapped when an associated segment passes
/// within vertex_radius of it; its error is then the distance to the nearest endpoint of an
/// associated segment (a segment that runs on past the end, across a partition, shows here). An
/// end the map does not reach is an unmapped end (and shows in the coverage), not an endpoint
/// error of metres. A corner is a point where the endpoints of two faces lie
/// within corner_tolerance and their undirected headings differ by at least corner_min_angle
/// (collinear continuations are not corners); its position is the mean of those endpoints, and
/// corners closer than corner_tolerance are one. It is seen when the ends of two of its faces
/// that meet there are both seen. Vertex accuracy (the three-criteria paper's measure): per seen
/// corner, the sum of the distances from the corner to every endpoint within vertex_radius of a
/// map segment associated with one of its faces (a segment on the other side of a 10 cm wall is
/// not a vertex of this corner). Throws std::invalid_argument naming the face or segment for
/// non-finite coordinates or a zero-length face, or when `seen` does not have one entry per face.
/// Where consecutive faces of one of `curves` meet is a joint of chords, not the end of a wall: such
/// ends are never seen, mapped or scored, so the endpoint figures keep to the true wall ends.
/// `slack` (per face, or empty) is added to a face's coverage tolerance and association distance.
GroundTruthResult evaluateAgainstGroundTruth(const std::vector<linemap::Segment2>& walls,
                                             const SeenParts& seen, const std::vector<linemap::Segment2>& map,
                                             const GroundTruthParams& params,
                                             const std::vector<std::vector<std::size_t>>& curves = {},
                                             const std::vector<double>& slack = {});

/// Per face of `truth`, registration_sigmas times the std of the registration error at the mean
/// range of the scans that saw it (all 0 without a registration error).
std::vector<double> registrationSlack(const GroundTruth& truth, double registration_sigmas);

/// The parts of `truth`'s faces that count as seen: seenParts with min_seen_length and min_seen_beams, and
/// with accumulate_sightings their union with accumulatedSeenParts.
SeenParts seenPartsOf(const GroundTruth& truth, const GroundTruthParams& params);

/// Against a simulation's ground truth: its faces over their parts seen in sights (seenParts with
/// min_seen_length and min_seen_beams), its curves' joints excluded, with its registrationSlack.
GroundTruthResult evaluateAgainstGroundTruth(const GroundTruth& truth,
                                             const std::vector<linemap::Segment2>& map,
                                             const GroundTruthParams& params);

/// Every face seen in full (hand-made cases).
GroundTruthResult evaluateAgainstGroundTruth(const std::vector<linemap::Segment2>& walls,
                                             const std::vector<linemap::Segment2>& map,
                                             const GroundTruthParams& params);

/// The corners of a set of faces as defined above.
std::vector<linemap::Vec2> findCorners(const std::vector<linemap::Segment2>& walls,
                                       const GroundTruthParams& params);

}  // namespace line_map_eval
