#include "line_map_eval/metrics/map_quality.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
QualityParams QualityParams::fromParams(const linemap::ParamSet& params)
{
  return linemap::readValidated<QualityParams>(
      params, {{"eval/directed", &QualityParams::directed},
               {"eval/direction_bins", &QualityParams::direction_bins},
               {"eval/redundancy_penalty", &QualityParams::redundancy_penalty}});
}

void QualityParams::validate() const
{
  if (direction_bins < 1 || direction_bins > 360)
    throw linemap::ParameterError("parameter 'eval/direction_bins' must be in [1, 360], got " +
                                  std::to_string(direction_bins));
  if (!(redundancy_penalty >= 0.0) || !std::isfinite(redundancy_penalty))
    throw linemap::ParameterError("parameter 'eval/redundancy_penalty' must be >= 0, got " +
                                  std::to_string(redundancy_penalty));
}

int directionBin(double heading, int bins, bool directed)
{
  // Shift by half a bin so that bin 0 is centred on 0: axis-aligned walls (the common case
  // indoors) sit in the middle of a bin, and a wall at +0.1 deg and its copy at -0.1 deg share it.
  const double period = directed ? 2.0 * linemap::kPi : linemap::kPi;
  const double width = period / bins;
  double h = std::fmod(heading + 0.5 * width, period);
  if (h < 0.0) h += period;
  const int b = static_cast<int>(h / width);
  return std::clamp(b, 0, bins - 1);  // h may round up to the period
}

QualityResult computeMapQuality(const LookupTable& table, const std::vector<linemap::Segment2>& map,
                                const QualityParams& params)
{
  params.validate();
  // One key per pixel: (cell, bin) packed into 64 bits, with its L. Sorting groups the
  // pixels of a pair; the first of a group is non-redundant, the rest redundant.
  struct Pixel
  {
    std::uint64_t key;
    float value;
  };
  std::vector<Pixel> pixels;
  const double res = table.resolution();
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    const linemap::Segment2& s = map[i];
    if (!s.start.allFinite() || !s.end.allFinite())
      throw std::invalid_argument("map quality: map segment " + std::to_string(i) +
                                  " has non-finite coordinates");
    const double limit = 6e7 * res;  // cell coordinates must fit into the 27-bit key fields below
    if (s.start.cwiseAbs().maxCoeff() > limit || s.end.cwiseAbs().maxCoeff() > limit)
      throw std::invalid_argument("map quality: map segment " + std::to_string(i) +
                                  " lies more than 6e7 cells from the origin");
    const std::uint64_t bin =
        static_cast<std::uint64_t>(directionBin(s.heading(), params.direction_bins, params.directed));
    const Cell a = table.cellOf(s.start), b = table.cellOf(s.end);
    forEachBresenhamCell(
        a.x, a.y, b.x, b.y,
        [&](int x, int y)
        {
          // 27 bits per biased coordinate (+-6.7e7 cells), 9 low bits for the bin: 63 bits.
          const std::uint64_t ux = static_cast<std::uint64_t>(static_cast<std::int64_t>(x) + (1LL << 26));
          const std::uint64_t uy = static_cast<std::uint64_t>(static_cast<std::int64_t>(y) + (1LL << 26));
          pixels.push_back({(((ux << 27) | uy) << 9) | bin, table.at({x, y})});
        });
  }
  QualityResult r;
  r.pixel_count = pixels.size();
  if (pixels.empty()) return r;
  std::sort(pixels.begin(), pixels.end(), [](const Pixel& p, const Pixel& q) { return p.key < q.key; });
  for (std::size_t i = 0; i < pixels.size(); ++i)
  {
    if (i > 0 && pixels[i].key == pixels[i - 1].key)
    {
      ++r.redundant_pixels;
      r.redundant_sum += pixels[i].value;
    }
    else
      r.nonredundant_sum += pixels[i].value;
  }
  r.quality = 100.0 * (r.nonredundant_sum - params.redundancy_penalty * r.redundant_sum) /
              static_cast<double>(r.pixel_count);
  return r;
}

}  // namespace line_map_eval
