// Lines in registered points that their own scans' extractors left unexplained, gathered from
// several scans: a wall seen in pieces, or with too few points per scan (long range, coarse beams),
// still shows as a band of points once the scans are registered together; clutter seen from many
// sides does not line up. Shared by the sliding submap of the extractor and the map-level pass of
// the mapper. ROS-free.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "line_extraction/line_fit.hpp"
#include "line_extraction/types.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
/// A registered point its scan's extractor left unexplained.
struct ResidualPoint
{
  Vec2 p;              ///< in the fixed frame
  float sigma = 0.0f;  ///< its noise across a line [m]: the range's, and the registration's where it has one
  float gap = 0.0f;    ///< largest gap to a neighbour on one surface [m]
  std::uint32_t source = 0;  ///< id of its scan (a ResidualSource)
  /// Its beam's index in that scan (-1: unknown). Two returns of neighbouring beams on a line saw
  /// the wall between them.
  std::int32_t beam = -1;
  bool used = false;  ///< already part of a line
};

/// Every valid return of a scan, in increasing angle (laser frame).
struct ResidualReturns
{
  std::vector<double> angles, ranges;
  double max_range = 0.0;  ///< the largest of `ranges`

  /// From a scan's valid returns in beam order (either increasing or decreasing angle).
  static std::shared_ptr<const ResidualReturns> of(std::vector<double> angles, std::vector<double> ranges);
};

/// A scan the points came from: where the laser stood and every return it had, for the test that
/// a line is not seen through (shared: a scan is registered again and again).
struct ResidualSource
{
  std::uint32_t id = 0;
  linemap::Pose2 laser;  ///< in the fixed frame
  std::shared_ptr<const ResidualReturns> returns;
};

/// The tests a line must pass (keys of the "submap" and "map_level" blocks).
struct ResidualLineParams
{
  double band_sigmas = 3.0;  ///< a point lies on a line within band_sigmas * its sigma
  double seed_radius = 0.5;  ///< [m] around a seed point a line hypothesis is sought in
  /// Largest gap between neighbouring points of a line, at least [m]; the points' own gap may allow more.
  double max_gap = 0.3;
  int min_points = 10;
  int min_sources = 3;      ///< distinct scans among the points: a line one scan alone shows is that scan's
  double min_length = 0.2;  ///< [m]
  double max_rms_sigmas = 1.5;  ///< the fit's RMS residual, in the points' mean sigma
  /// Points beside the band (one to two bands off the line, over its interior), per point on it.
  double max_side_share = 0.3;
  /// Beams passing through the line's interior, per beam ending on it.
  double max_through_share = 0.1;
  /// Share of the line's length, in bins of fill_bin, that must hold a point of it lying within
  /// fill_bin of the line (0: no test): a wall is seen all along, a row of posts or a few far
  /// returns are not.
  double min_fill = 0.0;
  double fill_bin = 0.05;  ///< [m]
  /// Whether two such points of neighbouring beams of one scan also fill the bins between them when
  /// they lie farther apart than max_gap (where a scan's own extractor breaks a wall) and no farther
  /// than one surface could leave them (the sensor model's gap): a wall far away or at a grazing
  /// angle is sampled that coarsely by every scan, and seen between the returns.
  bool coarse_beam_fill = false;

  /// These tests with the keys `<prefix>band_sigmas` ... `<prefix>fill_bin` read over them, the
  /// count of sources under `<prefix><sources_key>` (a submap counts scans, the map keyframes).
  /// Throws linemap::ParameterError naming a bad key.
  ResidualLineParams readOver(const linemap::ParamSet& params, const std::string& prefix,
                              const std::string& sources_key) const;
};

struct ResidualLine
{
  Vec2 start, end;                     ///< in the fixed frame, the observers on the left
  double sigma = 0.0;                  ///< mean sigma of its points
  std::vector<std::uint32_t> members;  ///< indices into the points
};

class ResidualLineFinder
{
 public:
  explicit ResidualLineFinder(const ResidualLineParams& params) : params_(params) {}

  /// Indexes the points and the sources (sorted by id). Both are kept by reference until the next
  /// call; grow() sets the points' `used` flags.
  void index(std::vector<ResidualPoint>& points, const std::vector<ResidualSource>& sources);

  /// A line grown from an unused seed point, its points marked used; false when none passes.
  bool grow(std::size_t seed, ResidualLine& line);

  const ResidualLineParams& params() const { return params_; }

 private:
  /// A point on a line hypothesis and its position along it.
  struct Candidate
  {
    std::uint32_t index;
    double along;
  };

  static bool alongThenIndex(const Candidate& a, const Candidate& b);
  /// Sorts by position along the line, ties by index.
  static void sortAlong(std::vector<Candidate>& band, std::vector<Candidate>& scratch);
  const ResidualSource* sourceById(std::uint32_t id) const;
  /// A stretch [t0, t1] of a line: the cells of forEachNear's call over it.
  struct Stretch
  {
    double t0, t1;
  };
  /// A point as the grid holds it, in cell order: what the band tests read, side by side.
  struct CellPoint
  {
    Vec2 p;
    double band;  ///< band_sigmas times its sigma [m]
    std::uint32_t source;
    bool used;  ///< as the point's own flag
  };
  /// Calls f(index, cell point) for every point whose grid cell may hold points within `half_width` of the
  /// line through `origin` along `dir` between `t0` and `t1` (each point once; the caller tests exactly).
  /// With `visited`, only the cells a call over that shorter stretch (same line and width) did not visit.
  template <class F>
  void forEachNear(const Vec2& origin, const Vec2& dir, double t0, double t1, double half_width, F&& f,
                   const Stretch* visited = nullptr) const;
  bool seedLine(std::size_t seed, LineNormal& best) const;
  bool growRun(std::size_t seed, LineNormal& fit_line, std::vector<Candidate>& run) const;
  /// The run through the seed of the band along `fit_line`, searched over a `stretch` either side of the seed
  /// that doubles until the run ends inside it (`stretch` is left at that); false when the seed is not in it.
  bool runAlong(std::size_t seed, const LineNormal& fit_line, double& stretch,
                std::vector<Candidate>& run) const;
  /// [m] the widest gap any two neighbouring points of a line may leave.
  double bridge() const;
  /// The band's candidates (sorted along the line) that the seed reaches without a gap wider than the
  /// points allow; false when the seed is not in the band.
  bool runThrough(std::size_t seed, const std::vector<Candidate>& band, std::vector<Candidate>& run) const;
  bool acceptRun(const std::vector<Candidate>& run, const LineNormal& fit_line, ResidualLine& line) const;
  /// A run that fails the fill test cut to its piece around the seed between the empty stretches (no point
  /// within fill_bin of the line over more than max_gap) nearest to it, and `fit_line` refitted to it; false
  /// when the run passed the fill test, is curved, has no such stretch, or the seed lies in one.
  bool keepSeedPiece(std::size_t seed, LineNormal& fit_line, std::vector<Candidate>& run) const;
  /// The share of the line's bins [t0, t1] that its points fill (see ResidualLineParams::min_fill).
  double filledShare(const std::vector<Candidate>& run, const LineNormal& line, double t0, double t1) const;
  bool curved(const std::vector<Candidate>& run, const LineNormal& line, double t0, double t1,
              double sigma) const;
  bool seenThrough(const Vec2& a, const Vec2& b, double band) const;

  ResidualLineParams params_;
  std::vector<ResidualPoint>* points_ = nullptr;
  const std::vector<ResidualSource>* sources_ = nullptr;
  double max_sigma_ = 0.0, max_gap_ = 0.0;  ///< over all points
  // Hash grid over the points, cell = seed_radius: keys sorted, with the point of each.
  std::vector<std::uint32_t> cell_order_;
  std::vector<CellPoint> cell_points_;        ///< the points of cell_order_, in its order
  std::vector<std::uint32_t> cell_position_;  ///< each point's place in cell_order_
  /// Per occupied cell, its points' range in cell_order_.
  std::unordered_map<std::int64_t, std::pair<std::uint32_t, std::uint32_t>> cells_;
};

}  // namespace line_extraction
