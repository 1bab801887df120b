// How far apart the points of one surface can lie and how noisy they are, from the scan's beam
// geometry and a range-noise model (ROS-free). Every distance threshold of the extractors is a
// constant set for short range; with the adaptive model it grows with the range, so one set of
// defaults serves fine and coarse beams, near and far walls.
#pragma once

#include <cmath>

#include "line_extraction/types.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
/// Keys "thresholds", "range_sigma", "range_sigma_per_m", "gap_incidence".
struct SensorModel
{
  /// false: the papers' fixed thresholds (every scale 1, no range-dependent gap).
  bool adaptive = true;
  double range_sigma = 0.01;         ///< sigma_0: range noise at zero range [m]
  double range_sigma_per_m = 0.001;  ///< growth of the range noise [m per m of range]
  /// Smallest angle between a beam and a surface whose neighbouring points may be joined across a
  /// gap wider than the fixed one [rad]: below it a surface's returns are unreliable (mixed
  /// pixels, grazing noise), and a wider gap would join things that are no surface.
  double min_incidence = 30.0 * linemap::kPi / 180.0;

  /// Throws linemap::ParameterError naming a bad key.
  static SensorModel fromParams(const linemap::ParamSet& params);

  /// sigma(r) = sigma_0 + range_sigma_per_m * r.
  double sigma(double range) const { return range_sigma + range_sigma_per_m * range; }
  /// sigma(r) / sigma_0: a tolerance chosen for the base noise holds at range r when multiplied by
  /// this (1 when not adaptive).
  double noiseScale(double range) const { return adaptive ? sigma(range) / range_sigma : 1.0; }
  /// Farthest apart two neighbouring points of one surface can be, the nearer at `range` and the
  /// beams `dphi` apart: the surface inclined down to min_incidence against the beam puts the
  /// other point r sin(dphi) / sin(min_incidence - dphi) away (law of sines), plus 3 sigma of
  /// noise. 0 when the beams are too far apart for any surface the model accepts, or not adaptive.
  double neighbourGap(double range, double dphi) const
  {
    if (!adaptive || !(dphi < min_incidence)) return 0.0;
    return range * std::sin(dphi) / std::sin(min_incidence - dphi) + 3.0 * sigma(range);
  }

  /// Fills scan.noise_scale and scan.gap2 from the points' ranges and beam angles.
  void annotate(PreparedScan& scan) const;
};

}  // namespace line_extraction
