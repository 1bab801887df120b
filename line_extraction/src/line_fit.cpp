// Total-least-squares line fitting from running sums, and its covariance.
//
// Fit: with the centred second moments Sxx, Syy, Sxy of the points, the sum of
// squared distances to the line with normal angle a is
//   J(a) = (Sxx + Syy)/2 + (Sxx - Syy)/2 cos 2a + Sxy sin 2a,
// which is smallest for (cos 2a, sin 2a) proportional to (Syy - Sxx, -2 Sxy), i.e.
// a = atan2(-2 Sxy, Syy - Sxx) / 2, with minimum ((Sxx + Syy) - h)/2, h = |(Syy - Sxx, -2 Sxy)|;
// n(a) is the eigenvector of the scatter matrix for its smaller eigenvalue (fitNormal).
// The line passes through the centroid: radius = mean . n(a), flipped to be >= 0.
//
// Covariance: let each point carry isotropic noise of standard deviation s, so its
// offset across the line is e_i ~ N(0, s^2). With n = (cos a, sin a), u = dn/da =
// (-sin a, cos a) and t_i = p_i . u (position along the line), a perturbed line
// (r + dr, a + da) leaves the residual e_i + da t_i - dr for point i. Least squares
// on these residuals gives
//   da = -sum (t_i - tm) e_i / St,   dr = mean(e) + tm da,   St = sum (t_i - tm)^2,
// and since sum (t_i - tm) = 0, mean(e) and da are uncorrelated, hence
//   var(a) = s^2 / St,  var(r) = s^2 / n + tm^2 var(a),  cov(r, a) = tm var(a).
// St is the scatter along the line: (Sxx + Syy + h) / 2.
#include "line_extraction/line_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace line_extraction
{
namespace
{
struct Moments
{
  double mx, my, cxx, cyy, cxy;
};

Moments centred(const LineSums& s)
{
  Moments m;
  m.mx = s.sx / s.n;
  m.my = s.sy / s.n;
  // Clamp tiny negative values produced by cancellation.
  m.cxx = std::max(0.0, s.sxx - s.sx * m.mx);
  m.cyy = std::max(0.0, s.syy - s.sy * m.my);
  m.cxy = s.sxy - s.sx * m.my;
  return m;
}

Vec2 project(const Vec2& p, double nx, double ny, double radius)
{
  const double d = p.x() * nx + p.y() * ny - radius;
  return {p.x() - d * nx, p.y() - d * ny};
}

// h = |(cxx - cyy, 2 cxy)|: the difference of the scatter matrix's two eigenvalues.
double scatterSpread(const Moments& m)
{
  const double dxy = m.cxx - m.cyy;
  return std::sqrt(dxy * dxy + 4.0 * m.cxy * m.cxy);
}

// The total-least-squares normal of centred moments `m`, whose h = |(cxx - cyy, 2 cxy)| is given;
// false for coincident points.
bool normalOf(const Moments& m, double h, LineNormal& out)
{
  const double cxx = m.cxx, cyy = m.cyy, cxy = m.cxy, mx = m.mx, my = m.my;
  const double dxy = cxx - cyy;
  if (!(cxx + cyy + h > 0.0)) return false;
  // The normal is the eigenvector of the scatter matrix for its smaller eigenvalue
  // lmin = (cxx + cyy - h)/2, taken from the row of (S - lmin I) with the larger
  // diagonal entry for accuracy: one square root and no trigonometry.
  double vx, vy;
  if (dxy >= 0.0)
  {
    vx = cxy;
    vy = -0.5 * (dxy + h);  // lmin - cxx
  }
  else
  {
    vx = 0.5 * (dxy - h);  // lmin - cyy
    vy = cxy;
  }
  const double norm2 = vx * vx + vy * vy;
  if (norm2 > 0.0)
  {
    const double inv = 1.0 / std::sqrt(norm2);
    vx *= inv;
    vy *= inv;
  }
  else
  {
    vx = 1.0;  // isotropic scatter: no preferred direction
    vy = 0.0;
  }
  double r = mx * vx + my * vy;
  if (r < 0.0)
  {
    r = -r;
    vx = -vx;
    vy = -vy;
  }
  out.nx = vx;
  out.ny = vy;
  out.radius = r;
  return true;
}

}  // namespace

LineFit fitLine(const LineSums& sums, double range_sigma)
{
  LineFit fit;
  // The normal and radius from the same moments and h as fitNormal (an eigenvector, no
  // trigonometry); the angle from the normal is then the only transcendental call.
  if (sums.n < 2.0) return fit;
  const Moments m = centred(sums);
  const double h = scatterSpread(m);
  LineNormal line;
  if (!normalOf(m, h, line)) return fit;  // coincident points: no direction
  const double trace = m.cxx + m.cyy;
  const double along = 0.5 * (trace + h);  // scatter along the line, > 0 here

  const double c = line.nx, s = line.ny;
  fit.angle = std::atan2(s, c);
  fit.radius = line.radius;
  fit.normal = Vec2(c, s);
  fit.sum_squared_residuals = std::max(0.0, 0.5 * (trace - h));

  const double var_noise = range_sigma * range_sigma;
  const double var_angle = var_noise / along;
  const double t_mean = -m.mx * s + m.my * c;
  fit.covariance(0, 0) = var_noise / sums.n + t_mean * t_mean * var_angle;
  fit.covariance(0, 1) = fit.covariance(1, 0) = t_mean * var_angle;
  fit.covariance(1, 1) = var_angle;
  fit.valid = true;
  return fit;
}

bool fitNormal(const LineSums& sums, LineNormal& out)
{
  if (sums.n < 2.0) return false;
  const Moments m = centred(sums);
  return normalOf(m, scatterSpread(m), out);
}

LineSums sumRange(const PreparedScan& scan, int begin, int end)
{
  LineSums s;
  for (int i = begin; i < end; ++i) s.add(scan.points[i]);
  return s;
}

void appendSegment(const PreparedScan& scan, const LineFit& fit, const int* members, int count,
                   ExtractionResult& out)
{
  if (count <= 0) return;
  const double c = fit.normal.x(), s = fit.normal.y();
  Segment seg;
  seg.start = project(scan.points[members[0]], c, s, fit.radius);
  seg.end = project(scan.points[members[count - 1]], c, s, fit.radius);
  seg.angle = fit.angle;
  seg.radius = fit.radius;
  const double scale = membersNoiseScale(scan, members[0], members[count - 1]);
  seg.covariance = fit.covariance * (scale * scale);
  seg.num_points = count;
  seg.index_begin = static_cast<int>(out.point_indices.size());
  out.point_indices.insert(out.point_indices.end(), members, members + count);
  seg.index_end = static_cast<int>(out.point_indices.size());
  out.segments.push_back(seg);
}

void appendSegment(const PreparedScan& scan, const LineFit& fit, PointRange members, ExtractionResult& out)
{
  if (members.size() <= 0) return;
  const double c = fit.normal.x(), s = fit.normal.y();
  Segment seg;
  seg.start = project(scan.points[members.begin], c, s, fit.radius);
  seg.end = project(scan.points[members.end - 1], c, s, fit.radius);
  seg.angle = fit.angle;
  seg.radius = fit.radius;
  const double scale = membersNoiseScale(scan, members.begin, members.end - 1);
  seg.covariance = fit.covariance * (scale * scale);
  seg.num_points = members.size();
  seg.index_begin = static_cast<int>(out.point_indices.size());
  out.point_indices.resize(out.point_indices.size() + members.size());
  std::iota(out.point_indices.begin() + seg.index_begin, out.point_indices.end(), members.begin);
  seg.index_end = static_cast<int>(out.point_indices.size());
  out.segments.push_back(seg);
}

void PrefixSums::build(const PreparedScan& scan, PointRange range)
{
  offset_ = range.begin;
  // Grow only: shrinking and regrowing would zero-fill the tail on every call.
  const std::size_t needed = static_cast<std::size_t>(std::max(range.size(), 0)) + 1;
  if (cum_.size() < needed) cum_.resize(needed);
  LineSums acc;
  cum_[0] = acc;
  for (int i = range.begin; i < range.end; ++i)
  {
    acc.add(scan.points[i]);
    cum_[i - range.begin + 1] = acc;
  }
}

void resolveOverlaps(const PreparedScan& scan, std::vector<PointRange>& segments, const PrefixSums* prefix)
{
  auto sumRange = [&](const PreparedScan& sc, int b, int e)
  { return prefix ? prefix->sums(b, e) : line_extraction::sumRange(sc, b, e); };
  const std::size_t n = segments.size();
  for (std::size_t k = 0; k + 1 < n; ++k)
  {
    PointRange& a = segments[k];
    PointRange& b = segments[k + 1];
    if (a.size() <= 0 || b.size() <= 0 || b.begin > a.end) continue;
    int cb = std::max(b.begin, a.begin), ce = std::min(a.end, b.end);
    if (cb == ce)
    {
      // Touching segments: the last point of one and the first of the other are
      // contested, when both keep enough points to define their lines.
      if (a.size() < 4 || b.size() < 4) continue;
      --cb;
      ++ce;
    }
    // Lines from the uncontested parts (or the whole segment when too little is left).
    LineNormal left, right;
    const bool left_ok = cb - a.begin >= 2 ? fitNormal(sumRange(scan, a.begin, cb), left)
                                           : fitNormal(sumRange(scan, a.begin, a.end), left);
    const bool right_ok = b.end - ce >= 2 ? fitNormal(sumRange(scan, ce, b.end), right)
                                          : fitNormal(sumRange(scan, b.begin, b.end), right);
    int split = ce;
    if (left_ok && right_ok)
    {
      for (int i = cb; i < ce; ++i)
      {
        // A point of the overlap goes to the nearer line. A point that only one segment owns
        // (touching segments) leaves it only when clearly (0.1 mm, above float range rounding)
        // nearer the other line: on a tie (collinear neighbours, e.g. one wall split at a gap)
        // it must not move across the gap.
        constexpr double kMargin = 1e-4;
        const double dr = right.distance(scan.points[i]), dl = left.distance(scan.points[i]);
        const bool to_b = i < b.begin ? dr < dl - kMargin : i >= a.end ? dl >= dr - kMargin : dr < dl;
        if (to_b)
        {
          split = i;
          break;
        }
      }
    }
    else if (!left_ok)
    {
      split = cb;
    }
    a.end = split;
    b.begin = split;
    if (a.size() < 2) a.end = a.begin;
    if (b.size() < 2) b.begin = b.end;
  }
}

}  // namespace line_extraction
