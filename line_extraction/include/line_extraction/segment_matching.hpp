// Matching extracted lines to true lines, and the detection statistics of the
// extraction benchmark (TruePos, FalsePos, spread of the line errors).
#pragma once

#include <cstddef>
#include <vector>

#include "linemap/geometry.hpp"

namespace line_extraction
{
struct MatchingOptions
{
  double sigma_radius = 0.03;  ///< [m]
  double sigma_angle = 0.03;   ///< [rad]
  /// Gate on the squared Mahalanobis distance of (radius, angle) with the
  /// diagonal covariance above: 2.77 is the 75 % quantile of chi-square(2).
  double gate = 2.77;
};

struct LineMatch
{
  int extracted = 0;          ///< index into the extracted lines
  int truth = 0;              ///< index into the true lines
  double radius_error = 0.0;  ///< extracted - true [m]
  double angle_error = 0.0;   ///< extracted - true, wrapped to (-pi, pi] [rad]
  double distance2 = 0.0;     ///< squared Mahalanobis distance
};

/// Squared Mahalanobis distance between two lines in Hessian form, with the
/// errors of the closer of the two equivalent parametrisations ((r, a) and
/// (-r, a + pi) matter when both lines pass near the origin).
LineMatch compareLines(const linemap::HessianLine& extracted, const linemap::HessianLine& truth,
                       const MatchingOptions& options);

/// One-to-one matches within the gate, chosen greedily by increasing distance
/// (ties by extracted, then true index); sorted by distance.
std::vector<LineMatch> matchLines(const std::vector<linemap::HessianLine>& extracted,
                                  const std::vector<linemap::HessianLine>& truth,
                                  const MatchingOptions& options = MatchingOptions());

/// A line with the extent of the segment on it.
struct LinePiece
{
  linemap::HessianLine line;
  linemap::Segment2 extent;
};

/// One-to-one matches of segments within the gate on their lines, as matchLines,
/// except that a pair whose segments overlap (along the true piece) is preferred
/// to a pair whose segments do not: a wall with a door has two collinear true
/// pieces with the same (radius, angle), and an extracted segment is credited to
/// the piece it lies on rather than to the first of the two. Overlap does not
/// change which pairs pass the gate.
std::vector<LineMatch> matchSegments(const std::vector<LinePiece>& extracted,
                                     const std::vector<LinePiece>& truth,
                                     const MatchingOptions& options = MatchingOptions());

/// Length of the overlap of segment a with segment b, measured along b (0 when
/// their projections onto b's direction are disjoint, or b has no length).
double overlapAlong(const linemap::Segment2& a, const linemap::Segment2& b);

/// The line of a map-frame wall piece as a laser at `laser_pose` (map frame) sees it.
linemap::HessianLine lineInLaserFrame(const linemap::Pose2& laser_pose, const linemap::Segment2& piece);

/// A map-frame wall piece in the frame of a laser at `laser_pose` (map frame).
linemap::Segment2 pieceInLaserFrame(const linemap::Pose2& laser_pose, const linemap::Segment2& piece);

/// Which true wall pieces an extractor is required to find: those hit by at least
/// min_beams beams and at least min_length long (the strictest output minimum of
/// the extractors, srg's 10 points and 0.6 m, so that every extractor is judged alike).
struct TruthRule
{
  std::size_t min_beams = 10;
  double min_length = 0.6;  ///< [m]
  bool counts(std::size_t beams, double length) const { return beams >= min_beams && length >= min_length; }
};

/// Detection statistics accumulated over many scans.
/// TruePos = matched counted true lines / counted true lines; FalsePos =
/// (extracted - matched) / extracted. A true line that is not counted (e.g.
/// seen by too few beams) may absorb an extracted line without being required.
class MatchStatistics
{
 public:
  /// Adds one scan: `counted[t]` says whether true line t is required (empty = all are).
  void add(std::size_t extracted_count, std::size_t truth_count, const std::vector<LineMatch>& matches,
           const std::vector<bool>& counted = {});

  std::size_t extracted() const { return extracted_; }
  std::size_t counted() const { return counted_; }
  std::size_t truePositives() const { return true_positives_; }
  std::size_t matched() const { return matched_; }
  /// 0 when nothing was counted / extracted.
  double truePositiveRate() const;
  double falsePositiveRate() const;
  /// Sample standard deviations of the radius [m] and angle [rad] errors over all matches (0 below 2
  /// matches).
  double radiusErrorStd() const;
  double angleErrorStd() const;

 private:
  std::size_t extracted_ = 0, counted_ = 0, true_positives_ = 0, matched_ = 0;
  double sum_r_ = 0.0, sum_r2_ = 0.0, sum_a_ = 0.0, sum_a2_ = 0.0;
};

}  // namespace line_extraction
