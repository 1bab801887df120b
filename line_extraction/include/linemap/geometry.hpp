// Shared 2D geometry of the linemap suite (ROS-free). Every package uses these
// types so that poses, segments and angle conventions are defined once.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace linemap
{
using Vec2 = Eigen::Vector2d;

constexpr double kPi = 3.14159265358979323846;

/// Wraps an angle to (-pi, pi].
inline double normalizeAngle(double a)
{
  // Most angles are in range already; std::remainder is slow (it switches the rounding mode) and
  // returns them unchanged, so skipping it changes no bit.
  if (a > -kPi && a <= kPi) return a;
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

/// Rigid 2D transform / pose (x, y, theta). `a * b` composes a after b:
/// if a = T_world_robot and b = T_robot_laser then a * b = T_world_laser.
struct Pose2
{
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  Pose2() = default;
  Pose2(double x_, double y_, double theta_) : x(x_), y(y_), theta(theta_) {}

  Vec2 translation() const { return {x, y}; }

  Vec2 apply(const Vec2& p) const
  {
    double c = 1.0, s = 0.0;
    cosSin(c, s);
    return {c * p.x() - s * p.y() + x, s * p.x() + c * p.y() + y};
  }

  Pose2 operator*(const Pose2& b) const
  {
    const Vec2 t = apply(b.translation());
    return {t.x(), t.y(), normalizeAngle(theta + b.theta)};
  }

  Pose2 inverse() const
  {
    double c = 1.0, s = 0.0;
    cosSin(c, s);
    return {-(c * x + s * y), s * x - c * y, normalizeAngle(-theta)};
  }

 private:
  /// cos and sin of theta. A mount or a start pose is often unrotated: for +0 they are exactly 1 and
  /// +0, which is what std::cos and std::sin return, at no cost (they save and restore the rounding mode).
  void cosSin(double& c, double& s) const
  {
    if (theta == 0.0 && !std::signbit(theta)) return;
    c = std::cos(theta);
    s = std::sin(theta);
  }
};

/// The z component of a x b: positive when b lies counter-clockwise of a.
inline double cross(const Vec2& a, const Vec2& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// Linear interpolation of translation and shortest-arc interpolation of heading, t in [0, 1].
inline Pose2 interpolate(const Pose2& a, const Pose2& b, double t)
{
  return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y),
          normalizeAngle(a.theta + t * normalizeAngle(b.theta - a.theta))};
}

/// The rigid transform that best maps the first point of each pair onto the second (least squares, as the
/// absolute trajectory error is measured); identity for fewer than two pairs. In 2D the rotation is closed
/// form: the angle of the summed cross and dot products of the centred pairs; the translation then maps the
/// one centroid onto the other.
inline Pose2 bestRigidFit(const std::vector<std::pair<Vec2, Vec2>>& pairs)
{
  if (pairs.size() < 2) return Pose2();
  Vec2 from_mean = Vec2::Zero(), to_mean = Vec2::Zero();
  for (const auto& [from, to] : pairs)
  {
    from_mean += from;
    to_mean += to;
  }
  from_mean /= static_cast<double>(pairs.size());
  to_mean /= static_cast<double>(pairs.size());
  double cross = 0.0, dot = 0.0;
  for (const auto& [from, to] : pairs)
  {
    const Vec2 a = from - from_mean, b = to - to_mean;
    cross += a.x() * b.y() - a.y() * b.x();
    dot += a.dot(b);
  }
  const double theta = std::atan2(cross, dot);
  const double c = std::cos(theta), s = std::sin(theta);
  const Vec2 rotated(c * from_mean.x() - s * from_mean.y(), s * from_mean.x() + c * from_mean.y());
  return Pose2(to_mean.x() - rotated.x(), to_mean.y() - rotated.y(), theta);
}

/// A directed segment; its heading points from start to end.
struct Segment2
{
  Vec2 start = Vec2::Zero();
  Vec2 end = Vec2::Zero();

  Segment2() = default;
  Segment2(const Vec2& s, const Vec2& e) : start(s), end(e) {}

  double length() const { return (end - start).norm(); }
  Vec2 midpoint() const { return 0.5 * (start + end); }
  /// Heading in (-pi, pi].
  double heading() const { return normalizeAngle(std::atan2(end.y() - start.y(), end.x() - start.x())); }
  Segment2 transformed(const Pose2& p) const { return {p.apply(start), p.apply(end)}; }
};

/// Distance from p to the infinite line through a and b (|p - a| when a == b).
inline double distanceToLine(const Vec2& p, const Vec2& a, const Vec2& b)
{
  const Vec2 d = b - a;
  const double n = d.norm();
  if (n <= 0.0) return (p - a).norm();
  return std::abs(d.x() * (p.y() - a.y()) - d.y() * (p.x() - a.x())) / n;
}

/// Distance from p to the closed segment [a, b].
inline double distanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b)
{
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return (p - a).norm();
  const double t = std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
  return (p - (a + t * d)).norm();
}

/// Hessian normal form x*cos(angle) + y*sin(angle) = radius (radius >= 0) of the
/// line through a and b.
struct HessianLine
{
  double angle = 0.0;
  double radius = 0.0;
};

inline HessianLine hessianFromPoints(const Vec2& a, const Vec2& b)
{
  const Vec2 d = b - a;
  double angle = std::atan2(d.x(), -d.y());  // normal = direction rotated by -90 degrees
  double radius = a.x() * std::cos(angle) + a.y() * std::sin(angle);
  if (radius < 0.0)
  {
    radius = -radius;
    angle += kPi;
  }
  return {normalizeAngle(angle), radius};
}

}  // namespace linemap
