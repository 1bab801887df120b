// Scan validation and conversion to Cartesian points. The trigonometry of the beams
// is computed once per scan geometry, which never changes for a given laser.
#include "line_extraction/preprocess.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace line_extraction
{
void validateScan(const ScanInput& scan)
{
  if (!std::isfinite(scan.angle_increment) || scan.angle_increment <= 0.0)
    throw ScanError("scan field 'angle_increment' must be finite and > 0, got " +
                    std::to_string(scan.angle_increment));
  if (!std::isfinite(scan.angle_min))
    throw ScanError("scan field 'angle_min' must be finite, got " + std::to_string(scan.angle_min));
  if (std::isnan(scan.range_min) || std::isnan(scan.range_max) || scan.range_min > scan.range_max)
    throw ScanError("scan fields 'range_min' (" + std::to_string(scan.range_min) + ") and 'range_max' (" +
                    std::to_string(scan.range_max) + "): range_min must not exceed range_max");
  if (scan.count > 0 && scan.ranges == nullptr) throw ScanError("scan field 'ranges' is missing");
  // A huge increment can overflow the later beam angles (cos(inf) = NaN points).
  if (scan.count > 0 &&
      !std::isfinite(scan.angle_min + static_cast<double>(scan.count - 1) * scan.angle_increment))
    throw ScanError("scan fields 'angle_min' and 'angle_increment': the last beam angle is not finite");
  if (scan.intensity_count > 0 && scan.intensity_count != scan.count)
    throw ScanError("scan field 'intensities' has " + std::to_string(scan.intensity_count) +
                    " values but 'ranges' has " + std::to_string(scan.count));
}

Preprocessor::Preprocessor(double max_usable_range) : max_usable_range_(max_usable_range)
{
  if (!(max_usable_range > 0.0))
    throw std::invalid_argument("max usable range must be > 0, got " + std::to_string(max_usable_range));
}

void Preprocessor::updateBeams(const ScanInput& scan)
{
  if (scan.angle_min == cached_angle_min_ && scan.angle_increment == cached_increment_ &&
      scan.count == cached_count_)
    return;
  cos_.resize(scan.count);
  sin_.resize(scan.count);
  for (std::size_t i = 0; i < scan.count; ++i)
  {
    const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    cos_[i] = std::cos(a);
    sin_[i] = std::sin(a);
  }
  cached_angle_min_ = scan.angle_min;
  cached_increment_ = scan.angle_increment;
  cached_count_ = scan.count;
}

void Preprocessor::prepare(const ScanInput& scan, PreparedScan& out)
{
  out.clear();
  validateScan(scan);
  out.angle_increment = scan.angle_increment;
  // A full turn of beams (the last beam one increment or less short of the first).
  out.full_circle = scan.count > 2 && static_cast<double>(scan.count) * scan.angle_increment >=
                                          2.0 * linemap::kPi - 0.5 * scan.angle_increment;
  if (scan.count == 0) return;
  updateBeams(scan);
  const double lo = std::max(scan.range_min, 0.0);
  const double hi = std::min(scan.range_max, max_usable_range_);
  // Sized for every beam, written through pointers, then cut to the valid count
  // (resizing keeps the capacity, so a warmed-up scan does not allocate).
  out.points.resize(scan.count);
  out.ranges.resize(scan.count);
  out.angles.resize(scan.count);
  out.beam_index.resize(scan.count);
  Vec2* points = out.points.data();
  double* ranges = out.ranges.data();
  double* angles = out.angles.data();
  int* beams = out.beam_index.data();
  std::size_t n = 0;
  for (std::size_t i = 0; i < scan.count; ++i)
  {
    const double r = scan.ranges[i];
    // NaN fails every comparison, +inf fails r < hi, -inf fails r >= lo.
    if (!(r >= lo && r < hi && r > 0.0)) continue;
    points[n] = Vec2(r * cos_[i], r * sin_[i]);
    ranges[n] = r;
    angles[n] = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    beams[n] = static_cast<int>(i);
    ++n;
  }
  out.points.resize(n);
  out.ranges.resize(n);
  out.angles.resize(n);
  out.beam_index.resize(n);
  if (out.full_circle) startAtWidestGap(out);
}

void startAtWidestGap(PreparedScan& scan)
{
  const std::size_t n = scan.size();
  if (n < 3) return;
  std::size_t start = 0;
  double widest = (scan.points[0] - scan.points[n - 1]).squaredNorm();
  for (std::size_t i = 1; i < n; ++i)
  {
    const double d = (scan.points[i] - scan.points[i - 1]).squaredNorm();
    if (d > widest)
    {
      widest = d;
      start = i;
    }
  }
  if (start == 0) return;
  // Points moved behind the old last point continue its angles past +2 pi.
  for (std::size_t i = 0; i < start; ++i) scan.angles[i] += 2.0 * linemap::kPi;
  std::rotate(scan.points.begin(), scan.points.begin() + start, scan.points.end());
  std::rotate(scan.ranges.begin(), scan.ranges.begin() + start, scan.ranges.end());
  std::rotate(scan.angles.begin(), scan.angles.begin() + start, scan.angles.end());
  std::rotate(scan.beam_index.begin(), scan.beam_index.begin() + start, scan.beam_index.end());
}

}  // namespace line_extraction
