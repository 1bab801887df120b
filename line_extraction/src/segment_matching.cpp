// Ground-truth matching of extracted lines (chi-square gate, greedy one-to-one).
#include "line_extraction/segment_matching.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace line_extraction
{
LineMatch compareLines(const linemap::HessianLine& extracted, const linemap::HessianLine& truth,
                       const MatchingOptions& options)
{
  auto make = [&](double dr, double da)
  {
    LineMatch m;
    m.radius_error = dr;
    m.angle_error = linemap::normalizeAngle(da);
    const double zr = dr / options.sigma_radius, za = m.angle_error / options.sigma_angle;
    m.distance2 = zr * zr + za * za;
    return m;
  };
  const LineMatch same = make(extracted.radius - truth.radius, extracted.angle - truth.angle);
  const LineMatch flipped =
      make(-extracted.radius - truth.radius, extracted.angle + linemap::kPi - truth.angle);
  return flipped.distance2 < same.distance2 ? flipped : same;
}

namespace
{
// Greedy one-to-one matching of the gated pairs: pairs of a better rank first (0
// before 1), then by distance, then by index. rank(e, t) gives the rank of a pair.
template <typename Rank>
std::vector<LineMatch> greedyMatches(const std::vector<linemap::HessianLine>& extracted,
                                     const std::vector<linemap::HessianLine>& truth,
                                     const MatchingOptions& options, Rank rank)
{
  std::vector<std::pair<int, LineMatch>> candidates;
  for (std::size_t e = 0; e < extracted.size(); ++e)
  {
    for (std::size_t t = 0; t < truth.size(); ++t)
    {
      LineMatch m = compareLines(extracted[e], truth[t], options);
      if (m.distance2 > options.gate) continue;
      m.extracted = static_cast<int>(e);
      m.truth = static_cast<int>(t);
      candidates.emplace_back(rank(e, t), m);
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const std::pair<int, LineMatch>& a, const std::pair<int, LineMatch>& b)
            {
              return std::tie(a.first, a.second.distance2, a.second.extracted, a.second.truth) <
                     std::tie(b.first, b.second.distance2, b.second.extracted, b.second.truth);
            });
  std::vector<char> used_e(extracted.size(), 0), used_t(truth.size(), 0);
  std::vector<LineMatch> matches;
  for (const auto& c : candidates)
  {
    const LineMatch& m = c.second;
    if (used_e[m.extracted] || used_t[m.truth]) continue;
    used_e[m.extracted] = used_t[m.truth] = 1;
    matches.push_back(m);
  }
  // Reported by distance, whatever the rank that chose them.
  std::stable_sort(matches.begin(), matches.end(),
                   [](const LineMatch& a, const LineMatch& b) { return a.distance2 < b.distance2; });
  return matches;
}

std::vector<linemap::HessianLine> linesOf(const std::vector<LinePiece>& pieces)
{
  std::vector<linemap::HessianLine> lines;
  lines.reserve(pieces.size());
  for (const LinePiece& p : pieces) lines.push_back(p.line);
  return lines;
}
}  // namespace

std::vector<LineMatch> matchLines(const std::vector<linemap::HessianLine>& extracted,
                                  const std::vector<linemap::HessianLine>& truth,
                                  const MatchingOptions& options)
{
  return greedyMatches(extracted, truth, options, [](std::size_t, std::size_t) { return 0; });
}

double overlapAlong(const linemap::Segment2& a, const linemap::Segment2& b)
{
  const linemap::Vec2 d = b.end - b.start;
  const double length = d.norm();
  if (!(length > 0.0)) return 0.0;
  const linemap::Vec2 u = d / length;
  const double s0 = (a.start - b.start).dot(u), s1 = (a.end - b.start).dot(u);
  return std::max(0.0, std::min(std::max(s0, s1), length) - std::max(std::min(s0, s1), 0.0));
}

std::vector<LineMatch> matchSegments(const std::vector<LinePiece>& extracted,
                                     const std::vector<LinePiece>& truth, const MatchingOptions& options)
{
  return greedyMatches(linesOf(extracted), linesOf(truth), options,
                       [&](std::size_t e, std::size_t t)
                       { return overlapAlong(extracted[e].extent, truth[t].extent) > 0.0 ? 0 : 1; });
}

linemap::HessianLine lineInLaserFrame(const linemap::Pose2& laser_pose, const linemap::Segment2& piece)
{
  const linemap::Segment2 local = pieceInLaserFrame(laser_pose, piece);
  return linemap::hessianFromPoints(local.start, local.end);
}

linemap::Segment2 pieceInLaserFrame(const linemap::Pose2& laser_pose, const linemap::Segment2& piece)
{
  return piece.transformed(laser_pose.inverse());
}

void MatchStatistics::add(std::size_t extracted_count, std::size_t truth_count,
                          const std::vector<LineMatch>& matches, const std::vector<bool>& counted)
{
  auto is_counted = [&](std::size_t t) { return counted.empty() || counted[t]; };
  extracted_ += extracted_count;
  for (std::size_t t = 0; t < truth_count; ++t) counted_ += is_counted(t);
  for (const LineMatch& m : matches)
  {
    ++matched_;
    true_positives_ += is_counted(static_cast<std::size_t>(m.truth));
    sum_r_ += m.radius_error;
    sum_r2_ += m.radius_error * m.radius_error;
    sum_a_ += m.angle_error;
    sum_a2_ += m.angle_error * m.angle_error;
  }
}

double MatchStatistics::truePositiveRate() const
{
  return counted_ == 0 ? 0.0 : static_cast<double>(true_positives_) / counted_;
}

double MatchStatistics::falsePositiveRate() const
{
  return extracted_ == 0 ? 0.0 : static_cast<double>(extracted_ - matched_) / extracted_;
}

namespace
{
double sampleStd(double sum, double sum2, std::size_t n)
{
  if (n < 2) return 0.0;
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, (sum2 - n * mean * mean) / (n - 1)));
}
}  // namespace

double MatchStatistics::radiusErrorStd() const
{
  return sampleStd(sum_r_, sum_r2_, matched_);
}
double MatchStatistics::angleErrorStd() const
{
  return sampleStd(sum_a_, sum_a2_, matched_);
}

}  // namespace line_extraction
