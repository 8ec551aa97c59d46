#include "tactile_sim/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace tactile_sim::geom {

Vec2 closest_point_on_segment(const Vec2& p, const Vec2& a, const Vec2& b, double* t_out) {
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  double t = 0.0;
  if (len2 > 0.0) t = std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
  if (t_out) *t_out = t;
  return a + t * d;
}

double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  return (p - closest_point_on_segment(p, a, b)).norm();
}

SegmentIntersection intersect_segments(const Vec2& p0, const Vec2& p1, const Vec2& q0,
                                       const Vec2& q1, double eps) {
  SegmentIntersection out;
  const Vec2 r = p1 - p0;
  const Vec2 s = q1 - q0;
  const double rr = r.squaredNorm();
  const double ss = s.squaredNorm();
  const Vec2 qp = q0 - p0;
  const double denom = cross(r, s);
  const double scale = std::sqrt(rr * ss);
  // Degenerate (point) segments: reduce to point-on-segment tests.
  if (rr <= eps * eps || ss <= eps * eps) {
    if (rr <= eps * eps && ss <= eps * eps) {
      if (qp.norm() <= eps) out = {true, false, 0.0, 0.0, p0};
      return out;
    }
    if (rr <= eps * eps) {
      double u = 0.0;
      const Vec2 c = closest_point_on_segment(p0, q0, q1, &u);
      if ((c - p0).norm() <= eps) out = {true, false, 0.0, u, p0};
      return out;
    }
    double t = 0.0;
    const Vec2 c = closest_point_on_segment(q0, p0, p1, &t);
    if ((c - q0).norm() <= eps) out = {true, false, t, 0.0, q0};
    return out;
  }
  if (std::abs(denom) > 1e-12 * scale) {
    // Proper crossing: p0 + t r = q0 + u s.
    const double t = cross(qp, s) / denom;
    const double u = cross(qp, r) / denom;
    const double tt = eps / std::sqrt(rr), tu = eps / std::sqrt(ss);
    if (t < -tt || t > 1.0 + tt || u < -tu || u > 1.0 + tu) return out;
    out.hit = true;
    out.t = std::clamp(t, 0.0, 1.0);
    out.u = std::clamp(u, 0.0, 1.0);
    out.point = p0 + out.t * r;
    return out;
  }
  // Parallel: collinear only if q0 lies on the line of p (distance <= eps).
  if (std::abs(cross(qp, r)) / std::sqrt(rr) > eps) return out;
  // Project q onto p's parameter and intersect the intervals.
  const double tq0 = qp.dot(r) / rr;
  const double tq1 = (q1 - p0).dot(r) / rr;
  const double lo = std::max(0.0, std::min(tq0, tq1));
  const double hi = std::min(1.0, std::max(tq0, tq1));
  const double tol = eps / std::sqrt(rr);
  if (lo > hi + tol) return out;
  out.hit = true;
  out.collinear = true;
  out.t = std::clamp(lo, 0.0, 1.0);
  out.point = p0 + out.t * r;
  out.u = std::clamp((out.point - q0).dot(s) / ss, 0.0, 1.0);
  return out;
}

RayHit ray_segment(const Vec2& origin, const Vec2& dir, const Vec2& a, const Vec2& b,
                   double max_range) {
  const SegmentIntersection x = intersect_segments(origin, origin + max_range * dir, a, b);
  RayHit out;
  if (!x.hit) return out;
  out.hit = true;
  out.t = x.t * max_range;
  out.point = x.point;
  return out;
}

RayHit ray_circle(const Vec2& origin, const Vec2& dir, const Vec2& center, double radius,
                  double max_range) {
  RayHit out;
  const Vec2 m = origin - center;
  const double c = m.squaredNorm() - radius * radius;
  if (c <= 0.0) {  // origin inside or on the circle
    out.hit = true;
    out.t = 0.0;
    out.point = origin;
    return out;
  }
  const double b = m.dot(dir);
  if (b > 0.0) return out;  // pointing away from an outside origin
  const double disc = b * b - c;
  if (disc < 0.0) return out;
  const double s = -b - std::sqrt(disc);
  if (s < 0.0 || s > max_range) return out;
  out.hit = true;
  out.t = s;
  out.point = origin + s * dir;
  return out;
}

RayHit segment_circle(const Vec2& a, const Vec2& b, const Vec2& center, double radius) {
  const Vec2 d = b - a;
  const double len = d.norm();
  if (len <= 0.0) {
    RayHit out;
    if ((a - center).squaredNorm() <= radius * radius) out = {true, 0.0, a};
    return out;
  }
  RayHit r = ray_circle(a, d / len, center, radius, len);
  if (r.hit) r.t /= len;
  return r;
}

}  // namespace tactile_sim::geom
