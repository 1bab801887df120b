// Collinear merge: consecutive segments whose lines agree within the chi-square gate
// (Mahalanobis distance with the summed covariances) become one segment refitted
// from the union of their points, using the running sums so each point is added once.
#include "line_extraction/collinear_merge.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace line_extraction
{
double lineMahalanobis(const Segment& a, const Segment& b)
{
  const Eigen::Matrix2d s = a.covariance + b.covariance;
  const double det = s.determinant();
  const Eigen::Vector2d d1(a.radius - b.radius, linemap::normalizeAngle(a.angle - b.angle));
  const Eigen::Vector2d d2(a.radius + b.radius, linemap::normalizeAngle(a.angle - b.angle - linemap::kPi));
  if (!(det > 0.0))
  {
    // Without uncertainty only identical lines are the same line.
    return (d1.squaredNorm() == 0.0 || d2.squaredNorm() == 0.0) ? 0.0
                                                                : std::numeric_limits<double>::infinity();
  }
  const Eigen::Matrix2d inv = s.inverse();
  return std::min(d1.dot(inv * d1), d2.dot(inv * d2));
}

bool CollinearMerger::mergeable(const PreparedScan& scan, int a_last, int b_first, const Segment& a,
                                const Segment& b) const
{
  // Far from the sensor, two pieces of one wall whose facing points are neighbouring beams can be
  // farther apart than max_gap.
  const double fixed2 = params_.max_gap * params_.max_gap;
  const double allowed2 = b_first == a_last + 1 ? scan.maxGap2(b_first, fixed2) : fixed2;
  if ((b.start - a.end).squaredNorm() > allowed2) return false;
  return lineMahalanobis(a, b) < params_.gate;
}

void CollinearMerger::absorb(const PreparedScan& scan, const ExtractionResult& in, const Segment& seg,
                             ExtractionResult& out)
{
  for (int k = seg.index_begin; k < seg.index_end; ++k)
  {
    const int idx = in.point_indices[k];
    if (member_[idx]) continue;
    member_[idx] = 1;
    sums_.add(scan.points[idx]);
    out.point_indices.push_back(idx);
  }
}

void CollinearMerger::refit(const PreparedScan& scan, ExtractionResult& out)
{
  Segment& seg = out.segments.back();
  seg.index_end = static_cast<int>(out.point_indices.size());
  seg.num_points = seg.index_end - seg.index_begin;
  const LineFit fit = fitLine(sums_, params_.range_sigma);
  if (!fit.valid) return;
  seg.angle = fit.angle;
  seg.radius = fit.radius;
  const double scale =
      membersNoiseScale(scan, out.point_indices[seg.index_begin], out.point_indices[seg.index_end - 1]);
  seg.covariance = fit.covariance * (scale * scale);
  const Vec2& n = fit.normal;
  const Vec2& first = scan.points[out.point_indices[seg.index_begin]];
  const Vec2& last = scan.points[out.point_indices[seg.index_end - 1]];
  seg.start = first - (first.dot(n) - fit.radius) * n;
  seg.end = last - (last.dot(n) - fit.radius) * n;
}

void CollinearMerger::track(const PreparedScan& scan, const ExtractionResult& out)
{
  if (tracked_) return;
  const Segment& seg = out.segments.back();
  sums_.clear();
  for (int k = seg.index_begin; k < seg.index_end; ++k)
  {
    const int idx = out.point_indices[k];
    member_[idx] = 1;
    sums_.add(scan.points[idx]);
  }
  tracked_ = true;
}

void CollinearMerger::untrack(const ExtractionResult& out)
{
  if (!tracked_) return;
  const Segment& seg = out.segments.back();
  for (int k = seg.index_begin; k < seg.index_end; ++k) member_[out.point_indices[k]] = 0;
  tracked_ = false;
}

void CollinearMerger::merge(const PreparedScan& scan, const ExtractionResult& in, ExtractionResult& out,
                            bool wrap)
{
  if (member_.size() < scan.size()) member_.resize(scan.size(), 0);
  const std::size_t first_out = out.segments.size();
  tracked_ = false;
  for (const Segment& seg : in.segments)
  {
    if (out.segments.size() > first_out &&
        mergeable(scan, out.point_indices[out.segments.back().index_end - 1],
                  in.point_indices[seg.index_begin], out.segments.back(), seg))
    {
      // Sums and marks are built only for segments that do merge.
      track(scan, out);
      absorb(scan, in, seg, out);
      refit(scan, out);
      continue;
    }
    untrack(out);
    Segment copy = seg;
    copy.index_begin = static_cast<int>(out.point_indices.size());
    out.point_indices.insert(out.point_indices.end(), in.point_indices.begin() + seg.index_begin,
                             in.point_indices.begin() + seg.index_end);
    copy.index_end = static_cast<int>(out.point_indices.size());
    out.segments.push_back(copy);
  }

  // Around a full circle the last segment may continue the first one.
  if (wrap && out.segments.size() >= first_out + 2 &&
      mergeable(scan, out.point_indices[out.segments.back().index_end - 1],
                out.point_indices[out.segments[first_out].index_begin], out.segments.back(),
                out.segments[first_out]))
  {
    // The last segment's points are at the tail of out.point_indices; appending
    // the first's points there gives the union in scan order.
    track(scan, out);
    const Segment first = out.segments[first_out];
    for (int k = first.index_begin; k < first.index_end; ++k)
    {
      const int idx = out.point_indices[k];
      if (member_[idx]) continue;
      member_[idx] = 1;
      sums_.add(scan.points[idx]);
      out.point_indices.push_back(idx);
    }
    refit(scan, out);
    untrack(out);  // the marks cover the merged point list
    out.segments[first_out] = out.segments.back();
    out.segments.pop_back();
  }
  // Leave the marks clear for the next call.
  if (out.segments.size() > first_out) untrack(out);
}

}  // namespace line_extraction
