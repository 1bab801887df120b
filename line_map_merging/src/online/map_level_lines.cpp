// Lines in what the keyframes' scans returned and neither their own segments nor the map explain
// (see the header).
#include "line_map_merging/online/map_level_lines.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

#include "line_extraction/param_checks.hpp"

namespace line_map_merging
{
using line_extraction::ResidualLine;
using line_extraction::ResidualLineFinder;
using line_extraction::ResidualPoint;
using line_extraction::ResidualSource;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

MapLevelParams MapLevelParams::fromParams(const linemap::ParamSet& ps)
{
  using namespace line_extraction;
  MapLevelParams p;
  const std::string prefix = "map_level/";
  p.enabled = ps.getBool(prefix + "enabled", p.enabled);
  p.every_keyframes = intParamAtLeast(ps, prefix + "every_keyframes", p.every_keyframes, 0);
  linemap::ParamSet sensor;
  for (const char* key : {"range_sigma", "range_sigma_per_m", "gap_incidence"})
    if (ps.has(prefix + key)) sensor.set(key, ps.values().at(prefix + key));
  try
  {
    p.sensor = SensorModel::fromParams(sensor);
  }
  catch (const linemap::ParameterError& e)
  {
    throw linemap::ParameterError(std::string(e.what()) + " (under " + prefix + ")");
  }
  p.pose_sigma = nonNegativeParam(ps, prefix + "pose_sigma", p.pose_sigma);
  p.heading_sigma = nonNegativeParam(ps, prefix + "heading_sigma", p.heading_sigma);
  p.explained_sigmas = positiveParam(ps, prefix + "explained_sigmas", p.explained_sigmas);
  p.reseed_distance = nonNegativeParam(ps, prefix + "reseed_distance", p.reseed_distance);
  p.reseed_angle = nonNegativeParam(ps, prefix + "reseed_angle", p.reseed_angle);
  p.search_margin = positiveParam(ps, prefix + "search_margin", p.search_margin);
  p.map_distance = nonNegativeParam(ps, prefix + "map_distance", p.map_distance);
  p.lines = p.lines.readOver(ps, prefix, "min_keyframes");
  return p;
}

MapLevelLines::MapLevelLines(const MapLevelParams& params) : params_(params) {}

namespace
{
/// Whether the point p lies within `band` of the segment, its foot on it (or within `band` of its ends).
bool onSegment(const Vec2& p, const Segment2& s, double band)
{
  const Vec2 d = s.end - s.start;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return false;
  const double t = (p - s.start).dot(d) / len2;
  const double len = std::sqrt(len2);
  if (t * len < -band || (t - 1.0) * len > band) return false;
  return std::abs(d.x() * (p.y() - s.start.y()) - d.y() * (p.x() - s.start.x())) / len <= band;
}
}  // namespace

void MapLevelLines::addKeyframe(std::uint64_t index, const KeyframeScan& scan,
                                const std::vector<Segment2>& segments)
{
  auto stored = std::make_shared<Stored>();
  std::vector<double> angles, ranges;
  std::vector<int> beam;  // beam index of each valid return
  for (std::size_t i = 0; i < scan.ranges.size(); ++i)
  {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r <= scan.range_min || r >= scan.range_max) continue;
    angles.push_back(scan.angle_min + static_cast<double>(i) * scan.angle_increment);
    ranges.push_back(r);
    beam.push_back(static_cast<int>(i));
  }
  stored->beam_spacing = std::abs(scan.angle_increment);
  const line_extraction::SensorModel& sensor = params_.sensor;
  const std::size_t n = ranges.size();
  for (std::size_t k = 0; k < n; ++k)
  {
    const double r = ranges[k];
    const Vec2 p(r * std::cos(angles[k]), r * std::sin(angles[k]));
    const double band = params_.explained_sigmas * sensor.sigma(r);
    if (std::any_of(segments.begin(), segments.end(),
                    [&](const Segment2& s) { return onSegment(p, s, band); }))
      continue;
    // The widest gap to a neighbouring beam's return that one surface could leave (the sensor model's).
    double gap = 0.0;
    for (const std::size_t j : {k - 1, k + 1})
      if (j < n && std::abs(beam[j] - beam[k]) == 1)
        gap = std::max(gap, sensor.neighbourGap(std::min(r, ranges[j]), stored->beam_spacing));
    stored->residual_at.push_back(p);
    stored->residual_range.push_back(static_cast<float>(r));
    stored->residual_gap.push_back(static_cast<float>(gap));
    stored->residual_beam.push_back(beam[k]);
  }
  stored->returns = line_extraction::ResidualReturns::of(std::move(angles), std::move(ranges));
  scans_[index] = std::move(stored);
}

namespace
{
/// Grows the box lo-hi to hold p.
void growBox(const Vec2& p, Vec2& lo, Vec2& hi)
{
  lo = lo.cwiseMin(p);
  hi = hi.cwiseMax(p);
}

bool inBox(const Vec2& p, const Vec2& lo, const Vec2& hi)
{
  return p.x() >= lo.x() && p.y() >= lo.y() && p.x() <= hi.x() && p.y() <= hi.y();
}

double distanceToBox(const Vec2& p, const Vec2& lo, const Vec2& hi)
{
  return (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
}
}  // namespace

/// The map's faces near the searched box in a grid of cells, each listing the segments within reach
/// of it: whether a registered return lies on a mapped face is asked for every return.
class MapLevelLines::FacesNear
{
 public:
  FacesNear(const std::vector<MapSegment>& map, const Vec2& lo, const Vec2& hi, double reach) : map_(map)
  {
    for (std::size_t i = 0; i < map.size(); ++i)
    {
      const Segment2& s = map[i].segment;
      const Vec2 s_lo = s.start.cwiseMin(s.end) - Vec2::Constant(reach);
      const Vec2 s_hi = s.start.cwiseMax(s.end) + Vec2::Constant(reach);
      if (s_lo.x() > hi.x() || s_lo.y() > hi.y() || s_hi.x() < lo.x() || s_hi.y() < lo.y()) continue;
      for (std::int64_t ix = indexOf(std::max(s_lo.x(), lo.x())); ix <= indexOf(std::min(s_hi.x(), hi.x()));
           ++ix)
        for (std::int64_t iy = indexOf(std::max(s_lo.y(), lo.y())); iy <= indexOf(std::min(s_hi.y(), hi.y()));
             ++iy)
        {
          const Vec2 centre((static_cast<double>(ix) + 0.5) * kCell, (static_cast<double>(iy) + 0.5) * kCell);
          if (linemap::distanceToSegment(centre, s.start, s.end) <= reach + kCell * 0.7072)
            cells_[key(ix, iy)].push_back(static_cast<std::uint32_t>(i));
        }
    }
  }

  /// Whether p lies within `band` of a mapped face turned to the laser at `laser` (the other face of
  /// a thin wall is not this one); band at most the reach given.
  bool explain(const Vec2& p, const Vec2& laser, double band) const
  {
    const auto near = cells_.find(key(indexOf(p.x()), indexOf(p.y())));
    if (near == cells_.end()) return false;
    return std::any_of(near->second.begin(), near->second.end(),
                       [&](std::uint32_t i)
                       {
                         const Segment2& m = map_[i].segment;
                         const Vec2 d = m.end - m.start, to_laser = laser - m.start;
                         return d.x() * to_laser.y() - d.y() * to_laser.x() > 0.0 && onSegment(p, m, band);
                       });
  }

 private:
  static constexpr double kCell = 2.0;  ///< [m]
  static std::int64_t indexOf(double v) { return static_cast<std::int64_t>(std::floor(v / kCell)); }
  static std::int64_t key(std::int64_t ix, std::int64_t iy) { return (ix << 32) ^ (iy & 0xffffffffLL); }

  const std::vector<MapSegment>& map_;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells_;
};

MapLevelLines::SeedArea MapLevelLines::seedArea(const std::vector<KeyframeInfo>& keyframes)
{
  SeedArea area;
  area.lo = Vec2::Constant(INFINITY);
  area.hi = Vec2::Constant(-INFINITY);
  for (const KeyframeInfo& k : keyframes)
  {
    const auto it = scans_.find(k.index);
    if (it == scans_.end()) continue;
    const auto before = searched_.find(k.index);
    // A back end nudges every pose a little with each trajectory: only a keyframe that moved by
    // more than reseed_distance / reseed_angle since it last seeded (a loop closed) seeds again.
    const bool moved =
        before == searched_.end() ||
        (before->second.translation() - k.pose.translation()).norm() > params_.reseed_distance ||
        std::abs(linemap::normalizeAngle(before->second.theta - k.pose.theta)) > params_.reseed_angle;
    area.known.push_back({&k, it->second.get(), moved});
    if (!moved) continue;
    searched_[k.index] = k.pose;
    for (const Vec2& local : it->second->residual_at) growBox(k.pose.apply(local), area.lo, area.hi);
  }
  if (area.lo.x() <= area.hi.x())
  {
    area.lo -= Vec2::Constant(params_.search_margin);
    area.hi += Vec2::Constant(params_.search_margin);
  }
  return area;
}

MapLevelLines::Registered MapLevelLines::registerResiduals(const SeedArea& area, const FacesNear& faces) const
{
  Registered reg;
  for (const Known& known : area.known)
  {
    const KeyframeInfo& k = *known.keyframe;
    const Stored& st = *known.stored;
    if (distanceToBox(k.pose.translation(), area.lo, area.hi) > st.returns->max_range) continue;
    const auto src_id = static_cast<std::uint32_t>(reg.sources.size());
    reg.sources.push_back({src_id, k.pose, st.returns});
    reg.stored_of.push_back(&st);
    reg.keyframe_of.push_back(k.index);
    reg.seeds.push_back(known.seeds ? 1 : 0);
    for (std::size_t j = 0; j < st.residual_at.size(); ++j)
    {
      const double r = st.residual_range[j];
      ResidualPoint w;
      w.p = k.pose.apply(st.residual_at[j]);
      if (!inBox(w.p, area.lo, area.hi)) continue;
      const double across =
          params_.pose_sigma * params_.pose_sigma + (r * params_.heading_sigma) * (r * params_.heading_sigma);
      const double sigma = std::sqrt(params_.sensor.sigma(r) * params_.sensor.sigma(r) + across);
      // Explained by the map: the wall is mapped already.
      if (faces.explain(w.p, k.pose.translation(),
                        std::max(params_.explained_sigmas * sigma, params_.map_distance)))
        continue;
      w.sigma = static_cast<float>(sigma);
      w.gap = st.residual_gap[j];
      w.beam = st.residual_beam[j];
      w.source = src_id;
      reg.points.push_back(w);
      reg.point_range.push_back(r);
    }
  }
  return reg;
}

void MapLevelLines::addParts(const ResidualLine& line, const Registered& reg,
                             std::vector<KeyframeOriginals>& out,
                             std::map<std::uint64_t, std::size_t>& out_slot)
{
  // Each keyframe's part: the span of its points along the line, widened by half a beam's footprint
  // at each end (one return stands for that much wall), within the line.
  const Vec2 dir = (line.end - line.start).normalized();
  const double length = (line.end - line.start).norm();
  std::map<std::uint32_t, std::pair<double, double>> span;
  for (const std::uint32_t m : line.members)
  {
    const double t = (reg.points[m].p - line.start).dot(dir);
    const std::uint32_t id = reg.points[m].source;
    const double half = 0.5 * reg.point_range[m] * reg.stored_of[id]->beam_spacing;
    auto [it, fresh] = span.emplace(id, std::make_pair(t - half, t + half));
    if (!fresh)
    {
      it->second.first = std::min(it->second.first, t - half);
      it->second.second = std::max(it->second.second, t + half);
    }
  }
  for (const auto& [id, range] : span)
  {
    const double t0 = std::max(0.0, range.first), t1 = std::min(length, range.second);
    if (!(t1 > t0)) continue;
    const Pose2 to_laser = reg.sources[id].laser.inverse();
    const Segment2 part(to_laser.apply(line.start + dir * t0), to_laser.apply(line.start + dir * t1));
    auto [slot, fresh] = out_slot.emplace(reg.keyframe_of[id], out.size());
    if (fresh) out.push_back({reg.keyframe_of[id], {}});
    out[slot->second].segments.push_back(part);
  }
}

std::vector<KeyframeOriginals> MapLevelLines::extract(const std::vector<KeyframeInfo>& keyframes,
                                                      const std::vector<MapSegment>& map,
                                                      std::vector<Segment2>* lines)
{
  // Lines through the seeding keyframes' points are sought among the points within search_margin of
  // them, and judged seen through by the keyframes within range.
  const SeedArea area = seedArea(keyframes);
  if (!(area.lo.x() <= area.hi.x())) return {};
  // A point's sigma beyond 0.5 m would be no wall's.
  const FacesNear faces(map, area.lo, area.hi,
                        std::max(params_.explained_sigmas * 0.5, params_.map_distance));
  Registered reg = registerResiduals(area, faces);

  ResidualLineFinder finder(params_.lines);
  finder.index(reg.points, reg.sources);
  std::vector<KeyframeOriginals> out;
  std::map<std::uint64_t, std::size_t> out_slot;
  for (std::size_t seed = 0; seed < reg.points.size(); ++seed)
  {
    ResidualLine line;
    if (!reg.seeds[reg.points[seed].source] || !finder.grow(seed, line)) continue;
    if (lines) lines->emplace_back(line.start, line.end);
    addParts(line, reg, out, out_slot);
  }
  return out;
}

}  // namespace line_map_merging
