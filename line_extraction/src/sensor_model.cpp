// The range-noise and point-spacing model behind the adaptive thresholds.
#include "line_extraction/sensor_model.hpp"

#include <algorithm>
#include <string>

namespace line_extraction
{
SensorModel SensorModel::fromParams(const linemap::ParamSet& ps)
{
  SensorModel m;
  const std::string mode = ps.getString("thresholds", "adaptive");
  if (mode != "adaptive" && mode != "fixed")
    throw linemap::ParameterError("parameter 'thresholds' must be 'adaptive' or 'fixed', got '" + mode + "'");
  m.adaptive = mode == "adaptive";
  m.range_sigma = ps.getDouble("range_sigma", m.range_sigma);
  if (!(m.range_sigma > 0.0 && std::isfinite(m.range_sigma)))
    throw linemap::ParameterError("parameter 'range_sigma' must be a finite number > 0");
  m.range_sigma_per_m = ps.getDouble("range_sigma_per_m", m.range_sigma_per_m);
  if (!(m.range_sigma_per_m >= 0.0 && std::isfinite(m.range_sigma_per_m)))
    throw linemap::ParameterError("parameter 'range_sigma_per_m' must be a finite number >= 0");
  m.min_incidence = ps.getDouble("gap_incidence", m.min_incidence);
  if (!(m.min_incidence > 0.0 && m.min_incidence < linemap::kPi / 2.0))
    throw linemap::ParameterError("parameter 'gap_incidence' must be in (0, pi/2) rad");
  return m;
}

void SensorModel::annotate(PreparedScan& scan) const
{
  const std::size_t n = scan.size();
  scan.noise_scale.resize(n);
  scan.gap2.resize(n);
  if (!adaptive)
  {
    std::fill(scan.noise_scale.begin(), scan.noise_scale.end(), 1.0);
    std::fill(scan.gap2.begin(), scan.gap2.end(), 0.0);
    return;
  }
  // Neighbours are almost always one increment apart: keep the last sine ratio.
  double cached_dphi = -1.0, ratio = 0.0;
  const double inv_sigma0 = 1.0 / range_sigma;
  for (std::size_t i = 0; i < n; ++i)
  {
    scan.noise_scale[i] = sigma(scan.ranges[i]) * inv_sigma0;
    // Pair (i-1, i). None before the first point: a full-circle scan starts at its widest gap.
    if (i == 0)
    {
      scan.gap2[0] = 0.0;
      continue;
    }
    // Only neighbouring beams: beams without a return between two points are no evidence of a
    // surface there (a doorway, glass), so such a pair keeps the fixed gap.
    const double dphi = scan.angle_increment;
    if (scan.beam_index[i] - scan.beam_index[i - 1] != 1 || !(dphi < min_incidence))
    {
      scan.gap2[i] = 0.0;
      continue;
    }
    if (dphi != cached_dphi)
    {
      cached_dphi = dphi;
      ratio = std::sin(dphi) / std::sin(min_incidence - dphi);
    }
    const double r = std::min(scan.ranges[i], scan.ranges[i - 1]);
    const double gap = r * ratio + 3.0 * sigma(r);
    scan.gap2[i] = gap * gap;
  }
}

}  // namespace line_extraction
