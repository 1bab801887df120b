// Scan validation and polar -> Cartesian conversion with cached beam directions.
#pragma once

#include <limits>
#include <stdexcept>
#include <vector>

#include "line_extraction/types.hpp"

namespace line_extraction
{
/// A scan whose geometry cannot be used; what() names the offending field.
struct ScanError : std::invalid_argument
{
  using std::invalid_argument::invalid_argument;
};

/// Throws ScanError naming the field when the scan geometry is unusable
/// (non-positive or non-finite angle_increment, non-finite angle_min, missing
/// ranges, range_min > range_max, intensities of another length than ranges).
void validateScan(const ScanInput& scan);

/// For a full-circle scan: rotates the points so that the first one follows the
/// widest gap between neighbours (the wrap-around pair included). No wall then
/// straddles the ends of the point list unless the scan has no gap wider than its
/// walls' point spacing. Angles of the points moved to the back get +2 pi, so they
/// keep increasing.
void startAtWidestGap(PreparedScan& scan);

class Preprocessor
{
 public:
  /// Readings at or beyond `max_usable_range` [m] are dropped as well.
  explicit Preprocessor(double max_usable_range = std::numeric_limits<double>::infinity());

  /// Validates the scan and fills `out` with its usable points (finite, inside
  /// [range_min, range_max), below the usable range, > 0), in beam order; a
  /// full-circle scan starts at its widest gap (startAtWidestGap).
  void prepare(const ScanInput& scan, PreparedScan& out);

  double maxUsableRange() const { return max_usable_range_; }

 private:
  void updateBeams(const ScanInput& scan);

  double max_usable_range_;
  // Beam directions for the last scan geometry seen.
  double cached_angle_min_ = std::numeric_limits<double>::quiet_NaN();
  double cached_increment_ = std::numeric_limits<double>::quiet_NaN();
  std::size_t cached_count_ = 0;
  std::vector<double> cos_, sin_;
};

}  // namespace line_extraction
