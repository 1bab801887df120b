// Ground-truth metrics of a line map over the seen parts of the true faces.
#include "line_map_eval/metrics/ground_truth_metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
using linemap::Segment2;
using linemap::Vec2;

namespace
{
/// Heading difference of two undirected lines, in [0, pi/2].
double undirectedAngle(const Segment2& a, const Segment2& b)
{
  const double d = std::abs(linemap::normalizeAngle(a.heading() - b.heading()));
  return std::min(d, linemap::kPi - d);
}

double headingDifference(const Segment2& a, const Segment2& b, bool directed)
{
  return directed ? std::abs(linemap::normalizeAngle(a.heading() - b.heading())) : undirectedAngle(a, b);
}

/// Whether map segment m lies along the face: headings within the angle, an overlap of positive
/// length along the face, and within association_distance of the face's line over that overlap.
/// (Not by the midpoint alone: a segment running on over two collinear faces belongs to both.)
/// The runs of a visible piece of scan `k` as intervals [from, to] along its face (metres from the
/// face's start, within the face); throws std::invalid_argument for a face the truth does not have.
std::vector<std::pair<double, double>> runIntervals(const GroundTruth& truth, std::size_t k,
                                                    const VisibleWall& v)
{
  if (v.wall >= truth.walls.size())
    throw std::invalid_argument("ground truth: scans[" + std::to_string(k) + "] sees wall " +
                                std::to_string(v.wall) + " of " + std::to_string(truth.walls.size()));
  const Segment2& face = truth.walls[v.wall];
  const double length = face.length();
  const Vec2 u = (face.end - face.start) / length;
  std::vector<std::pair<double, double>> out;
  for (const Segment2& run : v.runs.empty() ? std::vector<Segment2>{v.segment} : v.runs)
  {
    double a = std::clamp(u.dot(run.start - face.start), 0.0, length);
    double b = std::clamp(u.dot(run.end - face.start), 0.0, length);
    if (a > b) std::swap(a, b);
    out.emplace_back(a, b);
  }
  return out;
}

/// Per face of `truth`, the hits of all scans per bin of `bin` metres along it (each visible piece's
/// beams spread evenly over its runs).
std::vector<std::vector<double>> hitsPerBin(const GroundTruth& truth, double bin)
{
  std::vector<std::vector<double>> hits(truth.walls.size());
  for (std::size_t w = 0; w < truth.walls.size(); ++w)
    hits[w].assign(static_cast<std::size_t>(std::ceil(truth.walls[w].length() / bin)) + 1, 0.0);
  for (std::size_t k = 0; k < truth.scans.size(); ++k)
    for (const VisibleWall& v : truth.scans[k].visible)
    {
      const std::vector<std::pair<double, double>> runs = runIntervals(truth, k, v);
      double seen_length = 0.0;
      for (const auto& [a, b] : runs) seen_length += b - a;
      std::vector<double>& h = hits[v.wall];
      if (!(seen_length > 0.0))
      {
        h[static_cast<std::size_t>(runs.front().first / bin)] += static_cast<double>(v.beams);
        continue;
      }
      const double density = static_cast<double>(v.beams) / seen_length;
      for (const auto& [a, b] : runs)
        for (auto i = static_cast<std::size_t>(a / bin); i < h.size() && static_cast<double>(i) * bin < b;
             ++i)
        {
          const double overlap =
              std::min(b, (static_cast<double>(i) + 1.0) * bin) - std::max(a, static_cast<double>(i) * bin);
          if (overlap > 0.0) h[i] += density * overlap;
        }
    }
  return hits;
}

/// The stretches of a face (`length` m, hits per bin `h`) whose bins are hit and hold `min_hits` in the
/// window of min_length centred on them, kept when at least min_length long.
std::vector<std::pair<double, double>> denseStretches(const std::vector<double>& h, double bin, double length,
                                                      double min_length, double min_hits)
{
  std::vector<std::pair<double, double>> out;
  const auto half = static_cast<std::ptrdiff_t>(std::lround(0.5 * min_length / bin));
  const auto n = static_cast<std::ptrdiff_t>(h.size());
  std::vector<double> prefix(h.size() + 1, 0.0);
  for (std::size_t i = 0; i < h.size(); ++i) prefix[i + 1] = prefix[i] + h[i];
  std::ptrdiff_t start = -1;
  for (std::ptrdiff_t i = 0; i <= n; ++i)
  {
    bool dense = false;
    if (i < n)
    {
      const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, i - half), hi = std::min(n, i + half + 1);
      dense = h[static_cast<std::size_t>(i)] > 0.0 &&
              prefix[static_cast<std::size_t>(hi)] - prefix[static_cast<std::size_t>(lo)] >= min_hits;
    }
    if (dense && start < 0) start = i;
    if (!dense && start >= 0)
    {
      const double from = static_cast<double>(start) * bin,
                   to = std::min(length, static_cast<double>(i) * bin);
      if (to - from >= min_length) out.emplace_back(from, to);
      start = -1;
    }
  }
  return out;
}

/// Sorts intervals and joins those that overlap or touch.
void mergeIntervals(std::vector<std::pair<double, double>>& parts)
{
  std::sort(parts.begin(), parts.end());
  std::size_t n = 0;
  for (const auto& p : parts)
    if (n > 0 && p.first <= parts[n - 1].second)
      parts[n - 1].second = std::max(parts[n - 1].second, p.second);
    else
      parts[n++] = p;
  parts.resize(n);
}

bool associated(const Segment2& m, const Segment2& face, const GroundTruthParams& params)
{
  if (headingDifference(m, face, params.directed) > params.association_angle) return false;
  const double length = face.length();
  const Vec2 u = (face.end - face.start) / length, n(-u.y(), u.x());
  const double a = u.dot(m.start - face.start), b = u.dot(m.end - face.start);
  const double lo = std::max(std::min(a, b), 0.0), hi = std::min(std::max(a, b), length);
  if (!(hi > lo)) return false;
  const double da = n.dot(m.start - face.start), db = n.dot(m.end - face.start);
  const auto offset = [&](double t) { return da + (db - da) * (t - a) / (b - a); };
  return std::abs(offset(lo)) <= params.association_distance &&
         std::abs(offset(hi)) <= params.association_distance;
}

void requirePositive(double v, const char* key)
{
  if (!(v > 0.0) || !std::isfinite(v))
    throw linemap::ParameterError(std::string("parameter '") + key + "' must be positive, got " +
                                  std::to_string(v));
}

void checkFinite(const std::vector<Segment2>& segments, const char* what)
{
  for (std::size_t i = 0; i < segments.size(); ++i)
    if (!segments[i].start.allFinite() || !segments[i].end.allFinite())
      throw std::invalid_argument(std::string("ground truth metrics: ") + what + " " + std::to_string(i) +
                                  " has non-finite coordinates");
}

/// A true corner and the face ends that meet there (end 0: a face's start, 1: its end).
struct Corner
{
  Vec2 point = Vec2::Zero();
  struct Meeting
  {
    std::size_t face_a, end_a, face_b, end_b;
  };
  std::vector<Meeting> meetings;
};

std::vector<Corner> cornersOf(const std::vector<Segment2>& walls, const GroundTruthParams& params)
{
  std::vector<Corner> corners;
  for (std::size_t i = 0; i < walls.size(); ++i)
    for (std::size_t j = i + 1; j < walls.size(); ++j)
    {
      if (undirectedAngle(walls[i], walls[j]) < params.corner_min_angle) continue;
      for (std::size_t ea = 0; ea < 2; ++ea)
        for (std::size_t eb = 0; eb < 2; ++eb)
        {
          const Vec2& a = ea == 0 ? walls[i].start : walls[i].end;
          const Vec2& b = eb == 0 ? walls[j].start : walls[j].end;
          if ((a - b).norm() > params.corner_tolerance) continue;
          const Vec2 c = 0.5 * (a + b);
          auto known =
              std::find_if(corners.begin(), corners.end(),
                           [&](const Corner& k) { return (k.point - c).norm() <= params.corner_tolerance; });
          if (known == corners.end()) known = corners.insert(corners.end(), Corner{c, {}});
          known->meetings.push_back({i, ea, j, eb});
        }
    }
  return corners;
}
/// Throws std::invalid_argument (ParameterError for the parameters) naming what does not fit.
void checkInputs(const std::vector<Segment2>& walls, const SeenParts& seen, const std::vector<Segment2>& map,
                 const GroundTruthParams& params, const std::vector<double>& slack)
{
  params.validate();
  checkFinite(walls, "face");
  checkFinite(map, "map segment");
  if (seen.size() != walls.size())
    throw std::invalid_argument("ground truth metrics: seen parts for " + std::to_string(seen.size()) +
                                " faces, but there are " + std::to_string(walls.size()));
  if (!slack.empty() && slack.size() != walls.size())
    throw std::invalid_argument("ground truth metrics: slack for " + std::to_string(slack.size()) +
                                " faces, but there are " + std::to_string(walls.size()));
}

/// joint[face][end]: where consecutive chords of a curve meet, which is no end of a wall.
std::vector<std::array<bool, 2>> curveJoints(const std::vector<Segment2>& walls,
                                             const std::vector<std::vector<std::size_t>>& curves,
                                             double corner_tolerance)
{
  std::vector<std::array<bool, 2>> joint(walls.size(), {false, false});
  for (const auto& curve : curves)
    for (std::size_t k = 0; k < curve.size(); ++k)
    {
      if (curve[k] >= walls.size())
        throw std::invalid_argument("ground truth metrics: a curve lists face " + std::to_string(curve[k]) +
                                    " of " + std::to_string(walls.size()));
      const std::size_t a = curve[k], b = curve[(k + 1) % curve.size()];
      if (a == b || b >= walls.size()) continue;  // one face; b out of range is reported at its turn
      for (std::size_t ea = 0; ea < 2; ++ea)
        for (std::size_t eb = 0; eb < 2; ++eb)
          if (((ea ? walls[a].end : walls[a].start) - (eb ? walls[b].end : walls[b].start)).norm() <=
              corner_tolerance)
            joint[a][ea] = joint[b][eb] = true;
    }
  return joint;
}

/// The face's seen length, and the share of samples `spacing` apart over its seen parts that lie within
/// `tolerance` of a segment associated with it.
void scoreCoverage(const Segment2& wall, const std::vector<std::pair<double, double>>& seen,
                   const std::vector<Segment2>& map, const std::vector<std::size_t>& assoc, double tolerance,
                   double spacing, WallScore& score)
{
  std::size_t samples = 0, covered = 0;
  const Vec2 u = (wall.end - wall.start) / wall.length();
  for (const auto& [from, to] : seen)
  {
    score.seen_length += to - from;
    const std::size_t steps = static_cast<std::size_t>(std::ceil((to - from) / spacing));
    for (std::size_t k = 0; k <= steps; ++k)
    {
      const double t =
          steps == 0 ? from : from + (to - from) * static_cast<double>(k) / static_cast<double>(steps);
      const Vec2 p = wall.start + t * u;
      ++samples;
      for (const std::size_t m : assoc)
        if (linemap::distanceToSegment(p, map[m].start, map[m].end) <= tolerance)
        {
          ++covered;
          break;
        }
    }
  }
  score.coverage = static_cast<double>(covered) / static_cast<double>(samples);
}

struct EndpointTally
{
  double sum = 0.0;
  std::size_t count = 0;
};

/// Per seen end of the face that an associated segment reaches within `vertex_radius`: the distance to
/// the nearest endpoint of those segments (the others count as unmapped ends).
void scoreEnds(const Segment2& wall, const std::array<bool, 2>& seen_end, const std::vector<Segment2>& map,
               const std::vector<std::size_t>& assoc, double vertex_radius, WallScore& score,
               GroundTruthResult& r, EndpointTally& tally)
{
  for (std::size_t e = 0; e < 2; ++e)
  {
    if (!seen_end[e]) continue;
    const Vec2& end = e == 0 ? wall.start : wall.end;
    double nearest = std::numeric_limits<double>::infinity(), reach = nearest;
    for (const std::size_t m : assoc)
    {
      nearest = std::min({nearest, (map[m].start - end).norm(), (map[m].end - end).norm()});
      reach = std::min(reach, linemap::distanceToSegment(end, map[m].start, map[m].end));
    }
    if (reach > vertex_radius)
    {
      ++r.unmapped_ends;
      continue;
    }
    ++score.mapped_endpoints;
    score.endpoint_error = std::max(score.endpoint_error, nearest);
    r.max_endpoint_error = std::max(r.max_endpoint_error, nearest);
    tally.sum += nearest;
    ++tally.count;
  }
}

/// The corners both of whose meeting ends were seen: the map endpoints near each, of the segments
/// associated with its faces.
void scoreCorners(const std::vector<Segment2>& walls, const std::vector<std::array<bool, 2>>& seen_end,
                  const std::vector<std::vector<std::size_t>>& assoc, const std::vector<Segment2>& map,
                  const GroundTruthParams& params, GroundTruthResult& r)
{
  double vertex_sum = 0.0;
  std::size_t corners_with_endpoints = 0;
  std::vector<std::size_t> faces;
  for (const Corner& c : cornersOf(walls, params))
  {
    faces.clear();
    for (const Corner::Meeting& m : c.meetings)
      if (seen_end[m.face_a][m.end_a] && seen_end[m.face_b][m.end_b])
        for (const std::size_t f : {m.face_a, m.face_b})
          if (std::find(faces.begin(), faces.end(), f) == faces.end()) faces.push_back(f);
    if (faces.empty()) continue;  // not seen
    CornerScore cs;
    cs.corner = c.point;
    // Each map endpoint once, however many of the corner's faces its segment is associated with.
    std::vector<std::size_t> segments;
    for (const std::size_t f : faces) segments.insert(segments.end(), assoc[f].begin(), assoc[f].end());
    std::sort(segments.begin(), segments.end());
    segments.erase(std::unique(segments.begin(), segments.end()), segments.end());
    for (const std::size_t m : segments)
      for (const Vec2& e : {map[m].start, map[m].end})
      {
        const double d = (e - c.point).norm();
        if (d > params.vertex_radius) continue;
        cs.vertex_error += d;
        ++cs.endpoints;
      }
    if (cs.endpoints == 0)
      ++r.missed_corners;
    else
    {
      vertex_sum += cs.vertex_error;
      ++corners_with_endpoints;
    }
    r.corners.push_back(cs);
  }
  if (corners_with_endpoints > 0)
    r.mean_vertex_error = vertex_sum / static_cast<double>(corners_with_endpoints);
}

}  // namespace

GroundTruthParams GroundTruthParams::fromParams(const linemap::ParamSet& params)
{
  constexpr double deg = linemap::kPi / 180.0;
  GroundTruthParams p;
  p.coverage_tolerance = params.getDouble("eval/gt_coverage_tolerance", p.coverage_tolerance);
  p.registration_sigmas = params.getDouble("eval/gt_registration_sigmas", p.registration_sigmas);
  p.accumulate_sightings = params.getBool("eval/gt_accumulate_sightings", p.accumulate_sightings);
  p.sample_spacing = params.getDouble("eval/gt_sample_spacing", p.sample_spacing);
  p.association_angle = deg * params.getDouble("eval/gt_association_angle_deg", p.association_angle / deg);
  p.association_distance = params.getDouble("eval/gt_association_distance", p.association_distance);
  p.directed = params.getBool("eval/gt_directed", p.directed);
  p.min_seen_length = params.getDouble("eval/gt_min_seen_length", p.min_seen_length);
  const int beams = params.getInt("eval/gt_min_seen_beams", static_cast<int>(p.min_seen_beams));
  if (beams < 0) throw linemap::ParameterError("parameter 'eval/gt_min_seen_beams' must be >= 0");
  p.min_seen_beams = static_cast<std::size_t>(beams);
  p.corner_tolerance = params.getDouble("eval/gt_corner_tolerance", p.corner_tolerance);
  p.corner_min_angle = deg * params.getDouble("eval/gt_corner_min_angle_deg", p.corner_min_angle / deg);
  p.vertex_radius = params.getDouble("eval/gt_vertex_radius", p.vertex_radius);
  p.validate();
  return p;
}

void GroundTruthParams::validate() const
{
  requirePositive(coverage_tolerance, "eval/gt_coverage_tolerance");
  if (!(registration_sigmas >= 0.0) || !std::isfinite(registration_sigmas))
    throw linemap::ParameterError("parameter 'eval/gt_registration_sigmas' must be >= 0, got " +
                                  std::to_string(registration_sigmas));
  requirePositive(sample_spacing, "eval/gt_sample_spacing");
  requirePositive(association_distance, "eval/gt_association_distance");
  requirePositive(corner_tolerance, "eval/gt_corner_tolerance");
  requirePositive(vertex_radius, "eval/gt_vertex_radius");
  const double max_angle = directed ? linemap::kPi : 0.5 * linemap::kPi;
  if (!(association_angle >= 0.0) || association_angle > max_angle)
    throw linemap::ParameterError(std::string("parameter 'eval/gt_association_angle_deg' must be in [0, ") +
                                  (directed ? "180" : "90") + "]");
  if (!(corner_min_angle >= 0.0) || corner_min_angle > 0.5 * linemap::kPi)
    throw linemap::ParameterError("parameter 'eval/gt_corner_min_angle_deg' must be in [0, 90]");
  if (!(min_seen_length >= 0.0) || !std::isfinite(min_seen_length))
    throw linemap::ParameterError("parameter 'eval/gt_min_seen_length' must be >= 0, got " +
                                  std::to_string(min_seen_length));
}

SeenParts seenParts(const GroundTruth& truth, double min_piece_length, std::size_t min_piece_beams)
{
  SeenParts seen(truth.walls.size());
  // Per visible piece, the intervals along its face that runs of consecutive beams hit.
  std::vector<std::vector<std::pair<double, double>>> intervals;
  for (std::size_t k = 0; k < truth.scans.size(); ++k)
  {
    const auto& visible = truth.scans[k].visible;
    intervals.assign(visible.size(), {});
    for (std::size_t i = 0; i < visible.size(); ++i)
    {
      intervals[i] = runIntervals(truth, k, visible[i]);
    }
    // A sight (a piece, or the pieces of a curve seen together) is long and dense enough as a whole;
    // its length is what its runs saw, not the parts hidden between them.
    for (const auto& sight : sights(truth.walls, visible, truth.curves))
    {
      double length = 0.0;
      std::size_t beams = 0;
      for (const std::size_t i : sight)
      {
        for (const auto& [from, to] : intervals[i]) length += to - from;
        beams += visible[i].beams;
      }
      if (length < min_piece_length || beams < min_piece_beams) continue;
      for (const std::size_t i : sight)
        for (const auto& interval : intervals[i])
          if (interval.second > interval.first) seen[visible[i].wall].push_back(interval);
    }
  }
  for (auto& parts : seen) mergeIntervals(parts);
  return seen;
}

SeenParts accumulatedSeenParts(const GroundTruth& truth, double min_length, std::size_t min_beams, double bin)
{
  if (!(bin > 0.0) || !(min_length >= 0.0))
    throw std::invalid_argument("accumulated seen parts: the bin must be positive, the length >= 0");
  const std::vector<std::vector<double>> hits = hitsPerBin(truth, bin);
  SeenParts seen(truth.walls.size());
  for (std::size_t w = 0; w < truth.walls.size(); ++w)
    seen[w] =
        denseStretches(hits[w], bin, truth.walls[w].length(), min_length, static_cast<double>(min_beams));
  return seen;
}

SeenParts unionOfSeenParts(const SeenParts& a, const SeenParts& b)
{
  if (a.size() != b.size())
    throw std::invalid_argument("seen parts: " + std::to_string(a.size()) + " faces and " +
                                std::to_string(b.size()));
  SeenParts out = a;
  for (std::size_t w = 0; w < out.size(); ++w)
  {
    out[w].insert(out[w].end(), b[w].begin(), b[w].end());
    mergeIntervals(out[w]);
  }
  return out;
}

std::vector<Vec2> findCorners(const std::vector<Segment2>& walls, const GroundTruthParams& params)
{
  std::vector<Vec2> out;
  for (const Corner& c : cornersOf(walls, params)) out.push_back(c.point);
  return out;
}

GroundTruthResult evaluateAgainstGroundTruth(const std::vector<Segment2>& walls, const SeenParts& seen,
                                             const std::vector<Segment2>& map,
                                             const GroundTruthParams& params,
                                             const std::vector<std::vector<std::size_t>>& curves,
                                             const std::vector<double>& slack)
{
  checkInputs(walls, seen, map, params, slack);
  GroundTruthResult r;
  double covered_length = 0.0, seen_total = 0.0;
  EndpointTally endpoints;
  std::vector<std::vector<std::size_t>> assoc(walls.size());
  // seen_end[face][0 / 1]: the face's start / end was seen.
  std::vector<std::array<bool, 2>> seen_end(walls.size(), {false, false});
  const std::vector<std::array<bool, 2>> joint = curveJoints(walls, curves, params.corner_tolerance);
  for (std::size_t w = 0; w < walls.size(); ++w)
  {
    const Segment2& wall = walls[w];
    const double length = wall.length();
    if (!(length > 0.0))
      throw std::invalid_argument("ground truth metrics: face " + std::to_string(w) + " has zero length");
    if (seen[w].empty())
    {
      ++r.unseen_walls;
      continue;
    }
    WallScore score;
    score.face = w;
    score.segment = wall;
    score.length = length;
    GroundTruthParams face_params = params;
    if (!slack.empty())
    {
      face_params.coverage_tolerance += slack[w];
      face_params.association_distance += slack[w];
    }
    for (std::size_t m = 0; m < map.size(); ++m)
      if (associated(map[m], wall, face_params)) assoc[w].push_back(m);
    score.associated = assoc[w].size();
    scoreCoverage(wall, seen[w], map, assoc[w], face_params.coverage_tolerance, params.sample_spacing, score);

    seen_end[w] = {!joint[w][0] && seen[w].front().first <= params.coverage_tolerance,
                   !joint[w][1] && seen[w].back().second >= length - params.coverage_tolerance};
    score.seen_endpoints = std::size_t(seen_end[w][0]) + std::size_t(seen_end[w][1]);
    if (assoc[w].empty())
    {
      score.endpoint_error = std::numeric_limits<double>::infinity();
      ++r.undetected_walls;
    }
    else
      scoreEnds(wall, seen_end[w], map, assoc[w], params.vertex_radius, score, r, endpoints);
    covered_length += score.coverage * score.seen_length;
    seen_total += score.seen_length;
    r.walls.push_back(score);
  }
  if (seen_total > 0.0) r.coverage = covered_length / seen_total;
  if (endpoints.count > 0) r.mean_endpoint_error = endpoints.sum / static_cast<double>(endpoints.count);
  scoreCorners(walls, seen_end, assoc, map, params, r);
  return r;
}

SeenParts seenPartsOf(const GroundTruth& truth, const GroundTruthParams& params)
{
  SeenParts seen = seenParts(truth, params.min_seen_length, params.min_seen_beams);
  if (params.accumulate_sightings)
    seen = unionOfSeenParts(seen, accumulatedSeenParts(truth, params.min_seen_length, params.min_seen_beams));
  return seen;
}

GroundTruthResult evaluateAgainstGroundTruth(const GroundTruth& truth, const std::vector<Segment2>& map,
                                             const GroundTruthParams& params)
{
  params.validate();
  return evaluateAgainstGroundTruth(truth.walls, seenPartsOf(truth, params), map, params, truth.curves,
                                    registrationSlack(truth, params.registration_sigmas));
}

std::vector<double> registrationSlack(const GroundTruth& truth, double registration_sigmas)
{
  std::vector<double> slack(truth.walls.size(), 0.0);
  if (truth.registration_position == 0.0 && truth.registration_heading == 0.0) return slack;
  std::vector<double> range_sum(truth.walls.size(), 0.0);
  std::vector<std::size_t> sightings(truth.walls.size(), 0);
  for (const TruthScan& scan : truth.scans)
    for (const VisibleWall& v : scan.visible)
    {
      if (v.wall >= slack.size()) continue;
      range_sum[v.wall] += (0.5 * (v.segment.start + v.segment.end) - scan.pose.translation()).norm();
      ++sightings[v.wall];
    }
  for (std::size_t w = 0; w < slack.size(); ++w)
  {
    const double range = sightings[w] ? range_sum[w] / static_cast<double>(sightings[w]) : 0.0;
    slack[w] =
        registration_sigmas * std::hypot(truth.registration_position, truth.registration_heading * range);
  }
  return slack;
}

GroundTruthResult evaluateAgainstGroundTruth(const std::vector<Segment2>& walls,
                                             const std::vector<Segment2>& map,
                                             const GroundTruthParams& params)
{
  SeenParts all(walls.size());
  for (std::size_t w = 0; w < walls.size(); ++w) all[w].emplace_back(0.0, walls[w].length());
  return evaluateAgainstGroundTruth(walls, all, map, params);
}

}  // namespace line_map_eval
