// Scoring a map of a changed building: the true faces cut into removed, added and unchanged pieces.
#include "line_map_eval/metrics/change_coverage.hpp"

#include <algorithm>
#include <utility>

namespace line_map_eval
{
namespace
{
using linemap::Segment2;
using linemap::Vec2;
using Intervals = std::vector<std::pair<double, double>>;

/// Sorted, disjoint union of `in`.
Intervals unite(Intervals in)
{
  std::sort(in.begin(), in.end());
  Intervals out;
  for (const auto& i : in)
  {
    if (!out.empty() && i.first <= out.back().second)
      out.back().second = std::max(out.back().second, i.second);
    else
      out.push_back(i);
  }
  return out;
}

Intervals intersect(const Intervals& a, const Intervals& b)
{
  Intervals out;
  for (const auto& x : a)
    for (const auto& y : b)
    {
      const double from = std::max(x.first, y.first), to = std::min(x.second, y.second);
      if (to > from) out.emplace_back(from, to);
    }
  return unite(out);
}

Intervals subtract(const Intervals& a, const Intervals& b)
{
  Intervals out;
  for (auto [from, to] : a)
  {
    for (const auto& y : b)
    {
      if (y.second <= from || y.first >= to) continue;
      if (y.first > from) out.emplace_back(from, y.first);
      from = std::max(from, y.second);
      if (from >= to) break;
    }
    if (to > from) out.emplace_back(from, to);
  }
  return out;
}

/// Where along `face` (metres from its start) a face of `others` runs the same way on its line.
Intervals overlaidBy(const Segment2& face, const std::vector<Segment2>& others, double tolerance)
{
  const double length = face.length();
  const Vec2 u = (face.end - face.start) / length, n(-u.y(), u.x());
  Intervals out;
  for (const Segment2& o : others)
  {
    const Vec2 a = o.start - face.start, b = o.end - face.start;
    if (std::abs(n.dot(a)) > tolerance || std::abs(n.dot(b)) > tolerance || u.dot(b - a) <= 0.0) continue;
    const double from = std::max(0.0, u.dot(a)), to = std::min(length, u.dot(b));
    if (to > from) out.emplace_back(from, to);
  }
  return unite(out);
}

void addPieces(const Segment2& face, const Intervals& parts, double min_length, std::vector<Segment2>& out)
{
  const Vec2 u = (face.end - face.start) / face.length();
  for (const auto& [from, to] : parts)
    if (to - from >= min_length) out.push_back({face.start + from * u, face.start + to * u});
}

double percentCovered(const std::vector<Segment2>& pieces, const std::vector<Segment2>& map,
                      const GroundTruthParams& params)
{
  if (pieces.empty()) return 0.0;
  return 100.0 * evaluateAgainstGroundTruth(pieces, map, params).coverage;
}

double totalLength(const std::vector<Segment2>& pieces)
{
  double sum = 0.0;
  for (const Segment2& s : pieces) sum += s.length();
  return sum;
}

}  // namespace

ChangePieces changePieces(const GroundTruth& before, const GroundTruth& after,
                          const GroundTruthParams& params, double tolerance, double min_length)
{
  const SeenParts seen_before = seenPartsOf(before, params), seen_after = seenPartsOf(after, params);
  ChangePieces pieces;
  for (std::size_t f = 0; f < before.walls.size(); ++f)
  {
    const Intervals kept = overlaidBy(before.walls[f], after.walls, tolerance);
    addPieces(before.walls[f], subtract(seen_before[f], kept), min_length, pieces.removed);
  }
  for (std::size_t f = 0; f < after.walls.size(); ++f)
  {
    const Intervals kept = overlaidBy(after.walls[f], before.walls, tolerance);
    addPieces(after.walls[f], subtract(seen_after[f], kept), min_length, pieces.added);
    addPieces(after.walls[f], intersect(seen_after[f], kept), min_length, pieces.unchanged);
  }
  return pieces;
}

ChangeScores scoreChanges(const ChangePieces& pieces, const std::vector<Segment2>& map,
                          const GroundTruthParams& params)
{
  ChangeScores s;
  s.removed_length = totalLength(pieces.removed);
  s.added_length = totalLength(pieces.added);
  s.unchanged_length = totalLength(pieces.unchanged);
  s.removed_retired = pieces.removed.empty() ? 100.0 : 100.0 - percentCovered(pieces.removed, map, params);
  s.added_coverage = percentCovered(pieces.added, map, params);
  s.unchanged_coverage = percentCovered(pieces.unchanged, map, params);
  return s;
}

}  // namespace line_map_eval
