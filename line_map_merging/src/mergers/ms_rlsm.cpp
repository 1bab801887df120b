// MS-RLSM (Sarkar, Pal & Sarkar 2014): angular mean shift, spatial clustering inside each angular
// cluster, length-weighted fusion of each spatial cluster.
#include "line_map_merging/mergers/ms_rlsm.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

namespace line_map_merging
{
namespace
{
constexpr double kPi = linemap::kPi;

/// Wraps to [0, pi).
double wrapHalfTurn(double a)
{
  a = std::fmod(a, kPi);
  if (a < 0.0) a += kPi;
  return a >= kPi ? 0.0 : a;
}

/// Signed difference a - b on the circle of period pi, in [-pi/2, pi/2).
double halfTurnDifference(double a, double b)
{
  return wrapHalfTurn(a - b + 0.5 * kPi) - 0.5 * kPi;
}

struct UnionFind
{
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i)
  {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b)
  {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};
}  // namespace

MsParams MsParams::fromParams(const linemap::ParamSet& params)
{
  return linemap::readValidated<MsParams>(params,
                                          {{"ms/angular_bandwidth", &MsParams::angular_bandwidth},
                                           {"ms/lateral_separation", &MsParams::lateral_separation},
                                           {"ms/longitudinal_overlap", &MsParams::longitudinal_overlap}});
}

void MsParams::validate() const
{
  if (!(angular_bandwidth > 0.0 && angular_bandwidth < 0.5 * kPi))
    throw linemap::ParameterError("parameter 'ms/angular_bandwidth': " + std::to_string(angular_bandwidth) +
                                  " is not in (0, pi/2) rad");
  if (!(lateral_separation >= 0.0 && std::isfinite(lateral_separation)))
    throw linemap::ParameterError("parameter 'ms/lateral_separation': " + std::to_string(lateral_separation) +
                                  " is not a finite distance >= 0 m");
  if (!std::isfinite(longitudinal_overlap))
    throw linemap::ParameterError(
        "parameter 'ms/longitudinal_overlap': " + std::to_string(longitudinal_overlap) + " is not finite");
}

double undirectedAngle(const Segment2& s)
{
  return wrapHalfTurn(std::atan2(s.end.y() - s.start.y(), s.end.x() - s.start.x()));
}

namespace
{
/// The mean-shift mode (flat kernel of half-width `bandwidth`, period pi) each sample converges to.
std::vector<double> meanShiftModes(const std::vector<double>& wrapped, const std::vector<double>& weights,
                                   double bandwidth)
{
  // Sorted samples repeated at -pi, 0, +pi so that every window [c - h, c + h] with c in [0, pi)
  // is one contiguous range; prefix sums give its weight and weighted angle sum in O(log n).
  const std::size_t n = wrapped.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return wrapped[a] < wrapped[b]; });
  std::vector<double> ext(3 * n), cum_w(3 * n + 1, 0.0), cum_wa(3 * n + 1, 0.0);
  for (std::size_t k = 0; k < 3 * n; ++k)
  {
    const std::size_t i = order[k % n];
    ext[k] = wrapped[i] + (static_cast<double>(k / n) - 1.0) * kPi;
    cum_w[k + 1] = cum_w[k] + weights[i];
    cum_wa[k + 1] = cum_wa[k] + weights[i] * ext[k];
  }

  auto shift = [&](double c)
  {
    const auto lo = std::lower_bound(ext.begin(), ext.end(), c - bandwidth) - ext.begin();
    const auto hi = std::upper_bound(ext.begin(), ext.end(), c + bandwidth) - ext.begin();
    const double w = cum_w[hi] - cum_w[lo];
    // The window around a window mean always holds a sample; w > 0 is a safeguard.
    return w > 0.0 ? wrapHalfTurn((cum_wa[hi] - cum_wa[lo]) / w) : c;
  };

  std::vector<double> mode(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    double c = wrapped[i];
    // A flat kernel reaches its fixed point in finitely many steps; the cap guards round-off cycles.
    for (int it = 0; it < 1000; ++it)
    {
      const double next = shift(c);
      const bool done = std::abs(halfTurnDifference(next, c)) < 1e-12;
      c = next;
      if (done) break;
    }
    mode[i] = c;
  }
  return mode;
}

/// A label per sample: consecutive sorted modes closer than bandwidth / 2 (across the wrap too) are one
/// group; labels in order of first sample. `count` receives the number of groups.
std::vector<int> groupModes(const std::vector<double>& mode, double bandwidth, int& count)
{
  const std::size_t n = mode.size();
  std::vector<std::size_t> by_mode(n);
  std::iota(by_mode.begin(), by_mode.end(), 0);
  std::sort(by_mode.begin(), by_mode.end(), [&](std::size_t a, std::size_t b) { return mode[a] < mode[b]; });
  UnionFind groups(n);
  const double tol = 0.5 * bandwidth;
  for (std::size_t k = 1; k < n; ++k)
    if (mode[by_mode[k]] - mode[by_mode[k - 1]] <= tol)
      groups.unite(static_cast<int>(by_mode[k]), static_cast<int>(by_mode[k - 1]));
  if (n > 1 && mode[by_mode.front()] + kPi - mode[by_mode.back()] <= tol)
    groups.unite(static_cast<int>(by_mode.front()), static_cast<int>(by_mode.back()));

  std::vector<int> label(n, -1), label_of_root(n, -1);
  count = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    int& l = label_of_root[groups.find(static_cast<int>(i))];
    if (l < 0) l = count++;
    label[i] = l;
  }
  return label;
}
}  // namespace

std::vector<int> angularClusters(const std::vector<double>& angles, const std::vector<double>& weights,
                                 double bandwidth, std::vector<double>* modes)
{
  if (angles.size() != weights.size())
    throw std::invalid_argument("angularClusters: " + std::to_string(angles.size()) + " angles but " +
                                std::to_string(weights.size()) + " weights");
  if (!(bandwidth > 0.0 && bandwidth < 0.5 * kPi))
    throw std::invalid_argument("angularClusters: bandwidth " + std::to_string(bandwidth) +
                                " is not in (0, pi/2)");
  const std::size_t n = angles.size();
  if (modes) modes->clear();
  if (n == 0) return {};
  std::vector<double> wrapped(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!std::isfinite(angles[i]) || !(weights[i] > 0.0) || !std::isfinite(weights[i]))
      throw std::invalid_argument("angularClusters: sample " + std::to_string(i) +
                                  " has a non-finite angle or a weight that is not > 0");
    wrapped[i] = wrapHalfTurn(angles[i]);
  }
  int next = 0;
  const std::vector<int> label = groupModes(meanShiftModes(wrapped, weights, bandwidth), bandwidth, next);
  if (modes)
  {
    // Cluster direction: weighted mean of the members' angles, doubled to remove the period pi.
    std::vector<double> cx(next, 0.0), cy(next, 0.0);
    for (std::size_t i = 0; i < n; ++i)
    {
      cx[label[i]] += weights[i] * std::cos(2.0 * wrapped[i]);
      cy[label[i]] += weights[i] * std::sin(2.0 * wrapped[i]);
    }
    for (int l = 0; l < next; ++l) modes->push_back(wrapHalfTurn(0.5 * std::atan2(cy[l], cx[l])));
  }
  return label;
}

MsRlsm::MsRlsm(const MsParams& params) : params_(params)
{
  params_.validate();
}

namespace
{
/// The segments of one angular cluster oriented along its direction, with their position across it
/// (rho) and their extent along it (t0 < t1).
struct Oriented
{
  std::vector<Segment2> segments;
  std::vector<bool> reversed;
  std::vector<double> rho, t0, t1;
};

/// Orients every segment along its cluster direction so that the fusion's heading mean does not
/// cancel a segment against its reverse.
Oriented orient(std::vector<Segment2> segments, const std::vector<std::vector<std::size_t>>& members,
                const std::vector<double>& modes)
{
  const std::size_t n = segments.size();
  Oriented o{std::move(segments), std::vector<bool>(n, false), std::vector<double>(n), std::vector<double>(n),
             std::vector<double>(n)};
  for (std::size_t c = 0; c < modes.size(); ++c)
  {
    const Vec2 u(std::cos(modes[c]), std::sin(modes[c]));
    const Vec2 normal(-u.y(), u.x());
    for (std::size_t i : members[c])
    {
      Segment2& s = o.segments[i];
      if ((s.end - s.start).dot(u) < 0.0)
      {
        std::swap(s.start, s.end);
        o.reversed[i] = true;
      }
      o.rho[i] = normal.dot(s.midpoint());
      o.t0[i] = u.dot(s.start);
      o.t1[i] = u.dot(s.end);
    }
  }
  return o;
}

/// Within each angular cluster, segments at most `lateral` apart across and overlapping by at least
/// `longitudinal` along are one group (transitively).
UnionFind spatialGroups(std::vector<std::vector<std::size_t>> members, const Oriented& o, double lateral,
                        double longitudinal)
{
  UnionFind spatial(o.segments.size());
  for (auto& m : members)
  {
    std::sort(m.begin(), m.end(), [&](std::size_t a, std::size_t b) { return o.rho[a] < o.rho[b]; });
    for (std::size_t a = 0; a < m.size(); ++a)
      for (std::size_t b = a + 1; b < m.size() && o.rho[m[b]] - o.rho[m[a]] <= lateral; ++b)
      {
        const std::size_t i = m[a], j = m[b];
        if (std::min(o.t1[i], o.t1[j]) - std::max(o.t0[i], o.t0[j]) >= longitudinal)
          spatial.unite(static_cast<int>(i), static_cast<int>(j));
      }
  }
  return spatial;
}

/// One map segment per group, fused from its members (weighted by length).
std::vector<MapSegment> fuseGroups(UnionFind& spatial, const Oriented& o, const std::vector<double>& lengths)
{
  // Union-find roots are the smallest member index, so iterating in index order numbers the
  // clusters by their first segment.
  const std::size_t n = o.segments.size();
  std::vector<std::vector<WeightedSegment>> clusters;
  std::vector<double> direction_vote;  // length of members kept as they came minus of those reversed
  std::vector<int> cluster_of(n, -1);
  for (std::size_t i = 0; i < n; ++i)
  {
    const int root = spatial.find(static_cast<int>(i));
    if (cluster_of[root] < 0)
    {
      cluster_of[root] = static_cast<int>(clusters.size());
      clusters.emplace_back();
      direction_vote.push_back(0.0);
    }
    clusters[cluster_of[root]].push_back({o.segments[i], lengths[i]});
    direction_vote[cluster_of[root]] += o.reversed[i] ? -lengths[i] : lengths[i];
  }
  std::vector<MapSegment> out;
  out.reserve(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c)
  {
    // The clustering is undirected, but the output keeps the orientation convention (free side on
    // the left) of the length-weighted majority of its members.
    Segment2 fused = fuse(clusters[c]);
    if (direction_vote[c] < 0.0) std::swap(fused.start, fused.end);
    out.push_back({out.size(), fused, static_cast<std::uint32_t>(clusters[c].size())});
  }
  return out;
}
}  // namespace

std::vector<MapSegment> MsRlsm::compute() const
{
  std::vector<Segment2> segments;
  for (const Keyframe& k : stored())
    for (const Segment2& s : k.segments) segments.push_back(s.transformed(k.pose));
  const std::size_t n = segments.size();
  std::vector<double> angles(n), lengths(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    angles[i] = undirectedAngle(segments[i]);
    lengths[i] = segments[i].length();
  }
  std::vector<double> modes;
  const std::vector<int> angular = angularClusters(angles, lengths, params_.angular_bandwidth, &modes);
  std::vector<std::vector<std::size_t>> members(modes.size());
  for (std::size_t i = 0; i < n; ++i) members[angular[i]].push_back(i);
  const Oriented oriented = orient(std::move(segments), members, modes);
  UnionFind spatial =
      spatialGroups(std::move(members), oriented, params_.lateral_separation, params_.longitudinal_overlap);
  return fuseGroups(spatial, oriented, lengths);
}

}  // namespace line_map_merging
