// Structure coverage (ROS-free): how much of the straight structure in the registered scans the map
// covers, independent of any extractor. Point coverage counts clutter as misses and q is a precision;
// this asks which walls the map left out, and how many metres of them.
//
// A scan point lies on straight structure when a thin straight band through it is well supported:
//  - the cloud is reduced to voxels (`voxel` m) holding their points' count, mean and scatter, so that
//    the hundreds of scans seeing one wall cost one voxel per few centimetres of it;
//  - around the point's voxel, the voxels whose means lie within `radius` form the neighbourhood; their
//    points' principal axis gives a first direction, and a line through the voxel's mean with it;
//  - the band: the neighbourhood voxels whose means lie within g = band_sigmas * sigma of the line; the
//    line is refitted to the band's points (mean and principal axis) and the band taken again, until it
//    settles: a mean shift onto the densest line nearby, so the two faces of a wall 10 cm thick are two
//    lines, and at an L corner the band settles on one arm;
//  - the voxel is straight structure when the band's points scatter about the line by an RMS of at most
//    max_rms_sigmas * sigma (a uniformly filled band passes up to a full width of sqrt(12) times that;
//    a filled blob, whose band is filled across its 2g, has g / sqrt(3) and fails), its voxel means
//    spread along the line over at least `min_length` and fill at least `min_fill` of that extent (in
//    bins of one voxel: a row of chair legs does not), and it holds at least `min_share` of the
//    neighbourhood's voxels (a band through scattered clutter holds few of them);
//  - a point of such a voxel is on structure when it lies within g of the line (so a segment on the
//    line, covering within the point-coverage radius, g at the defaults, covers it).
// The smeared scale: a wall whose registered points smear across by tens of centimetres (the keyframes
// that saw it disagree) or that far scans sample sparsely fails the fine band, and is still a wall. Every
// voxel also gets the same band test at a larger scale (smear_radius, smear_band), with two changes: the
// RMS is taken over the 80 % of the band's points nearest its line (a wall with objects beside it is
// thin at its core, clutter filling the band is not), and the fill is judged against the bins its n
// points would fill spread evenly at random, B (1 - exp(-n / B)) of B (a sparse wall fills about that
// many, a row of posts seen by many scans piles its points into few). A band whose points fall into two
// lines with a gap between (the faces of a partition) is no smear. A point is structure on either
// scale; on a smeared line it is covered when a map segment passes within the band's own width
// (sqrt(3) x its RMS, at most smear_band, at least the point-coverage radius) of its foot on that line.
// Coverage is by length (StructureCoverage::fraction): a wall seen from afar by few points weighs
// what a wall beside the path does, as in the ground truth's seen-face coverage.
// Consequences at the defaults (sigma 5 cm: g 5 cm, RMS 2.5 cm; radius 0.5 m; min_length 0.4 m):
// straight pieces from 0.4 m long are structure up to their free ends; an L corner is structure up to
// its vertex (a point near the vertex lies within g of either arm's line); a uniformly filled band is
// structure up to 8.7 cm thick; a curved wall of radius rho holds a band chord of 2 sqrt(2 rho g - g^2),
// so rho below about min_length^2 / (8 g) = 0.4 m (a pillar) is not structure, a gently curved wall is.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "line_map_eval/metrics/length_coverage.hpp"
#include "line_map_eval/metrics/point_coverage.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_eval
{
/// Keys "eval/structure_*" (config/line_map_eval.yaml explains each default).
struct StructureParams
{
  double radius = 0.5;          ///< [m] neighbourhood of a voxel
  double min_length = 0.4;      ///< [m] the band's extent along its line
  double band_sigmas = 1.0;     ///< band half-width g, in lookup-table sigmas
  double max_rms_sigmas = 0.5;  ///< largest RMS scatter about the line, in sigmas
  double min_share = 0.3;       ///< smallest share of the neighbourhood's voxels in the band
  double min_fill = 0.5;        ///< smallest share of the band's extent its voxels fill (voxel bins)
  double voxel = 0.05;          ///< [m] voxel size of the reduced cloud
  double length_cell = 0.1;     ///< [m] cell size of the unmapped length
  /// The smeared scale, for voxels the fine test refuses (0 smear_band: off).
  double smear_band = 0.25;       ///< [m] band half-width
  double smear_radius = 2.0;      ///< [m] neighbourhood
  double smear_max_rms = 0.08;    ///< [m] largest RMS scatter about the line
  double smear_min_share = 0.4;   ///< smallest share of the neighbourhood's voxels in the band
  double smear_min_length = 1.5;  ///< [m] the band's extent along its line
  /// Smallest share of the bins along the band's extent it fills, of those its points would fill
  /// spread evenly at random.
  double smear_min_fill = 0.6;
  double smear_fill_bin = 0.05;  ///< [m] bins of that fill
  int smear_min_points = 10;     ///< points in the band

  static StructureParams fromParams(const linemap::ParamSet& params);
  /// Throws linemap::ParameterError naming the key.
  void validate() const;
};

/// The runs of structureLength over a set of feet, kept so that the length of any subset costs one
/// pass over the feet.
struct StructureRuns
{
  std::vector<std::uint32_t> run_of;        ///< per foot: its run
  std::vector<double> width;                ///< per run: [m] of line per column, cell / cos(delta)
  std::vector<std::uint32_t> before_start;  ///< per run r: before[before_start[r], before_start[r + 1])
  std::vector<std::uint32_t> before;        ///< are the runs of the column before touching it across
  /// structureLength of the feet, with `uncovered` (per foot, or empty: all).
  double length(const std::vector<std::uint8_t>& uncovered = {}) const;
};

/// Sorts feet into the runs of structureLength (below); throws like it.
StructureRuns structureRuns(const std::vector<linemap::Vec2>& feet, const std::vector<double>& headings,
                            double cell);

/// The straight-structure points of a cloud; depends on the cloud alone, so it is computed once per
/// lookup table and reused for every map scored against it.
struct StructurePoints
{
  std::size_t points = 0;            ///< points classified
  std::vector<std::size_t> indices;  ///< ascending indices of the points on straight structure
  std::vector<linemap::Vec2> feet;   ///< per structure point: its foot on the local line
  std::vector<double> headings;      ///< per structure point: the local line's heading in [0, pi)
  /// Per structure point: 1 when on fine structure (feet and headings are then the fine line's), 0 on
  /// smeared structure alone.
  std::vector<std::uint8_t> fine;
  /// Per structure point: its foot on its voxel's smeared line, and the distance [m] from that foot
  /// within which a map segment covers it (the band's own width); 0 without a smeared line.
  std::vector<linemap::Vec2> smeared_feet;
  std::vector<float> reach;
  StructureRuns runs;   ///< of the feet, with the cell size eval/structure_length_cell
  double length = 0.0;  ///< [m] structureLength of all of them
};

/// Classifies `points` (see the file comment); `sigma` is the lookup table's. Parallel over voxels.
/// Throws std::invalid_argument naming the point for a non-finite point, linemap::ParameterError for
/// bad parameters or a non-positive sigma.
StructurePoints classifyStructure(const std::vector<linemap::Vec2>& points, double sigma,
                                  const StructureParams& params);

/// Length [m] of straight structure from points on it. Each point's foot (on its local line, so the width
/// of a registered wall is no length) goes into a grid turned to the nearest of 8 headings (0, 22.5, ...
/// 157.5 deg) of its line: columns `cell` wide along that heading, rows cell / 4 across. In a column,
/// adjacent occupied rows are one run, one line (its feet scatter by millimetres; the two faces of a
/// wall, 10 cm apart, are two runs). A line of length L at an angle delta (<= 11.25 deg) to its grid's
/// heading crosses L cos(delta) / cell columns, so each run adds cell / cos(delta), delta being the
/// mean over the run's feet (doubled angles); but a piece touches one column more than that on
/// average (its two end columns hold a part each), so the first run of each chain of runs (in
/// consecutive columns, touching across) adds nothing. With `uncovered` (per foot), only runs whose feet are
/// mostly uncovered count: the unmapped length, not inflated by a mapped wall's outlying points.
/// `headings` (in [0, pi)) parallel to `feet`. Throws std::invalid_argument for mismatched sizes,
/// non-finite values or a non-positive cell.
double structureLength(const std::vector<linemap::Vec2>& feet, const std::vector<double>& headings,
                       double cell, const std::vector<std::uint8_t>& uncovered = {});

struct StructureCoverage
{
  std::size_t points = 0;              ///< scan points on straight structure
  std::size_t covered = 0;             ///< of which within the point-coverage radius of a map segment
  std::vector<std::size_t> uncovered;  ///< scan-point indices of the others, ascending (for figures)
  double length = 0.0;                 ///< [m] of all straight structure (structureLength)
  double unmapped_length = 0.0;        ///< [m] structureLength of the runs of mostly uncovered points
  /// The share of the straight structure's length the map covers, 1 - unmapped_length / length, in
  /// [0, 1]; 0 without structure. By length, as the ground truth scores the faces the robot saw: a
  /// wall seen from afar by sparse points weighs what a wall beside the path does.
  double fraction() const { return length > 0.0 ? std::max(0.0, 1.0 - unmapped_length / length) : 0.0; }
  /// covered / points in [0, 1]; 0 without structure points.
  double pointFraction() const
  {
    return points ? static_cast<double>(covered) / static_cast<double>(points) : 0.0;
  }
};

/// The structure points' coverage: a fine one is covered when the point coverage of the same cloud
/// (computed with `radius`) covers it; any one on a smeared line also when a segment of `map` passes
/// within its reach (at least `radius`) of its foot on that line. Throws std::invalid_argument when the two
/// were computed for clouds of different sizes.
StructureCoverage computeStructureCoverage(const StructurePoints& structure, const PointCoverage& coverage,
                                           const std::vector<linemap::Segment2>& map, double radius);

}  // namespace line_map_eval
