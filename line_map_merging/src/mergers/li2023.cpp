// Three-criteria line feature fusion (Li et al. 2023): R-tree candidate pairs, union-find clusters,
// total-least-squares fit per cluster, endpoint snapping.
#include "line_map_merging/mergers/li2023.hpp"

#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "line_extraction/line_fit.hpp"

namespace line_map_merging
{
namespace
{
namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;
using Point = bg::model::point<double, 2, bg::cs::cartesian>;
using Box = bg::model::box<Point>;
using Entry = std::pair<Box, std::size_t>;

constexpr double kPi = linemap::kPi;

struct UnionFind
{
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t i)
  {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  /// The root is always the smallest member.
  void unite(std::size_t a, std::size_t b)
  {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

Box circleBox(const Segment2& s)
{
  const Vec2 c = s.midpoint();
  const double r = 0.5 * s.length();
  return Box(Point(c.x() - r, c.y() - r), Point(c.x() + r, c.y() + r));
}

/// The TLS line through all endpoints of `members`, clipped to their extreme projections and
/// oriented like the first member. False when the endpoints do not define a line.
bool fitCluster(const std::vector<Segment2>& members, Segment2& out)
{
  line_extraction::LineSums sums;
  for (const Segment2& s : members)
  {
    sums.add(s.start);
    sums.add(s.end);
  }
  line_extraction::LineNormal line;
  if (!line_extraction::fitNormal(sums, line)) return false;
  // The criteria are undirected; the fused segment takes the direction of the length-weighted
  // majority of its members, so that it keeps the orientation convention (free side on the left).
  Vec2 dir(-line.ny, line.nx);
  double vote = 0.0;
  for (const Segment2& s : members) vote += dir.dot(s.end - s.start);
  if (vote < 0.0) dir = -dir;
  const Vec2 foot = line.radius * Vec2(line.nx, line.ny);
  double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
  for (const Segment2& s : members)
    for (const Vec2& p : {s.start, s.end})
    {
      const double t = dir.dot(p - foot);
      t_min = std::min(t_min, t);
      t_max = std::max(t_max, t);
    }
  out = Segment2(foot + t_min * dir, foot + t_max * dir);
  return isValidSegment(out);
}

/// Moves endpoints of different segments closer than `distance` to their mean. A group that holds
/// both ends of one segment is left alone (it would collapse the segment).
void snapEndpoints(std::vector<MapSegment>& map, double distance)
{
  if (!(distance > 0.0) || map.size() < 2) return;
  const std::size_t n = 2 * map.size();
  auto point = [&](std::size_t e) -> Vec2&
  { return e % 2 ? map[e / 2].segment.end : map[e / 2].segment.start; };
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return point(a).x() < point(b).x(); });
  UnionFind groups(n);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n && point(order[b]).x() - point(order[a]).x() <= distance; ++b)
    {
      const std::size_t i = order[a], j = order[b];
      if (i / 2 != j / 2 && (point(i) - point(j)).norm() <= distance) groups.unite(i, j);
    }
  std::vector<Vec2> sum(n, Vec2::Zero());
  std::vector<int> count(n, 0);
  std::vector<bool> collapses(n, false);
  for (std::size_t e = 0; e < n; ++e)
  {
    const std::size_t r = groups.find(e);
    sum[r] += point(e);
    ++count[r];
    if (e % 2 && groups.find(e - 1) == r) collapses[r] = true;
  }
  std::vector<Vec2> target(n);
  for (std::size_t e = 0; e < n; ++e)
  {
    const std::size_t r = groups.find(e);
    target[e] = (count[r] > 1 && !collapses[r]) ? Vec2(sum[r] / count[r]) : point(e);
  }
  for (std::size_t e = 0; e < n; ++e) point(e) = target[e];
}
}  // namespace

Li2023Params Li2023Params::fromParams(const linemap::ParamSet& params)
{
  return linemap::readValidated<Li2023Params>(params,
                                              {{"li2023/delta", &Li2023Params::delta},
                                               {"li2023/gamma", &Li2023Params::gamma},
                                               {"li2023/eta", &Li2023Params::eta},
                                               {"li2023/min_count", &Li2023Params::min_count},
                                               {"li2023/snap_distance", &Li2023Params::snap_distance}});
}

void Li2023Params::validate() const
{
  if (!(delta >= 0.0 && delta <= 0.5 * kPi))
    throw linemap::ParameterError("parameter 'li2023/delta': " + std::to_string(delta) +
                                  " is not in [0, pi/2] rad");
  if (!(gamma > 0.0 && gamma <= 1.0))
    throw linemap::ParameterError("parameter 'li2023/gamma': " + std::to_string(gamma) + " is not in (0, 1]");
  if (!(eta >= 0.0 && std::isfinite(eta)))
    throw linemap::ParameterError("parameter 'li2023/eta': " + std::to_string(eta) +
                                  " is not a finite distance >= 0 m");
  if (min_count < 1)
    throw linemap::ParameterError("parameter 'li2023/min_count': " + std::to_string(min_count) +
                                  " must be >= 1");
  if (!(snap_distance >= 0.0 && std::isfinite(snap_distance)))
    throw linemap::ParameterError("parameter 'li2023/snap_distance': " + std::to_string(snap_distance) +
                                  " is not a finite distance >= 0 m");
}

double lensArea(double r1, double r2, double d)
{
  if (!(r1 >= 0.0 && r2 >= 0.0 && d >= 0.0))
    throw std::invalid_argument("lensArea: radii and distance must be >= 0");
  if (d >= r1 + r2) return 0.0;
  const double r = std::min(r1, r2);
  if (d <= std::abs(r1 - r2)) return kPi * r * r;
  // Two circular segments, one cut from each disc by the common chord.
  const double c1 = std::clamp((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1), -1.0, 1.0);
  const double c2 = std::clamp((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2), -1.0, 1.0);
  const double k = (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2);
  return r1 * r1 * std::acos(c1) + r2 * r2 * std::acos(c2) - 0.5 * std::sqrt(std::max(0.0, k));
}

double includedAngle(const Segment2& a, const Segment2& b)
{
  // (A, B) of A x + B y + C = 0 is the segment's normal (dy, -dx).
  const double a1 = a.end.y() - a.start.y(), b1 = a.start.x() - a.end.x();
  const double a2 = b.end.y() - b.start.y(), b2 = b.start.x() - b.end.x();
  const double norm = std::hypot(a1, b1) * std::hypot(a2, b2);
  if (!(norm > 0.0)) return 0.5 * kPi;
  return std::acos(std::min(1.0, std::abs(a1 * a2 + b1 * b2) / norm));
}

double circleOverlapRatio(const Segment2& a, const Segment2& b)
{
  const double ra = 0.5 * a.length(), rb = 0.5 * b.length();
  const double r = std::min(ra, rb);
  if (!(r > 0.0)) return 0.0;
  return std::min(1.0, lensArea(ra, rb, (a.midpoint() - b.midpoint()).norm()) / (kPi * r * r));
}

double midpointDistance(const Segment2& a, const Segment2& b)
{
  return std::max(linemap::distanceToSegment(a.midpoint(), b.start, b.end),
                  linemap::distanceToSegment(b.midpoint(), a.start, a.end));
}

Li2023::Li2023(const Li2023Params& params) : params_(params)
{
  params_.validate();
}

bool Li2023::close(const Segment2& a, const Segment2& b) const
{
  // Cheapest test first.
  return includedAngle(a, b) <= params_.delta && midpointDistance(a, b) <= params_.eta &&
         circleOverlapRatio(a, b) >= params_.gamma;
}

std::vector<MapSegment> Li2023::compute() const
{
  std::vector<Segment2> segments;
  std::vector<std::size_t> keyframe_of;
  const auto& keyframes = stored();
  for (std::size_t k = 0; k < keyframes.size(); ++k)
    for (const Segment2& s : keyframes[k].segments)
    {
      segments.push_back(s.transformed(keyframes[k].pose));
      keyframe_of.push_back(k);
    }
  const std::size_t n = segments.size();

  // Overlapping feature circles (gamma > 0) have intersecting bounding boxes.
  std::vector<Entry> entries;
  entries.reserve(n);
  for (std::size_t i = 0; i < n; ++i) entries.emplace_back(circleBox(segments[i]), i);
  const bgi::rtree<Entry, bgi::rstar<16>> index(entries.begin(), entries.end());

  UnionFind clusters(n);
  std::vector<Entry> hits;
  for (std::size_t i = 0; i < n; ++i)
  {
    hits.clear();
    index.query(bgi::intersects(entries[i].first), std::back_inserter(hits));
    for (const Entry& e : hits)
    {
      const std::size_t j = e.second;
      if (j <= i || keyframe_of[j] == keyframe_of[i]) continue;
      if (clusters.find(i) == clusters.find(j)) continue;
      if (close(segments[i], segments[j])) clusters.unite(i, j);
    }
  }

  // Roots are the smallest members: index order numbers the clusters by their first segment.
  std::vector<std::vector<Segment2>> members;
  std::vector<long> cluster_of(n, -1);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t root = clusters.find(i);
    if (cluster_of[root] < 0)
    {
      cluster_of[root] = static_cast<long>(members.size());
      members.emplace_back();
    }
    members[cluster_of[root]].push_back(segments[i]);
  }
  std::vector<MapSegment> out;
  for (const auto& m : members)
  {
    Segment2 fitted;
    if (static_cast<int>(m.size()) < params_.min_count || !fitCluster(m, fitted)) continue;
    out.push_back({out.size(), fitted, static_cast<std::uint32_t>(m.size())});
  }
  snapEndpoints(out, params_.snap_distance);
  return out;
}

}  // namespace line_map_merging
