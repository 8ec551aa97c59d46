// 2D geometry primitives of the arena (top view, world x-y plane): segments,
// rays and circles. Pure functions, no allocation; every "t" is a parameter
// along the first argument, every ray distance is in metres along a unit
// direction.
#pragma once

#include "tactile_sim/types.hpp"

namespace tactile_sim::geom {

/// Directed segment a -> b.
struct Segment {
  Vec2 a = Vec2::Zero();
  Vec2 b = Vec2::Zero();
};

/// 2D cross product (z of the 3D cross product).
inline double cross(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }

/// Closest point to p on segment [a, b]; `t_out` (optional) receives its
/// parameter in [0, 1]. A zero-length segment returns a.
Vec2 closest_point_on_segment(const Vec2& p, const Vec2& a, const Vec2& b, double* t_out = nullptr);

/// Euclidean distance from p to segment [a, b].
double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b);

/// Result of a segment-segment intersection.
struct SegmentIntersection {
  bool hit = false;
  bool collinear = false;  ///< overlapping collinear segments (t, u: first common point along p)
  double t = 0.0;          ///< parameter along p0 -> p1, in [0, 1]
  double u = 0.0;          ///< parameter along q0 -> q1, in [0, 1]
  Vec2 point = Vec2::Zero();
};

/// Intersection of segments [p0, p1] and [q0, q1] (endpoints included).
/// Parallel disjoint segments miss; collinear overlapping segments hit at the
/// first common point along p (smallest t). `eps` is a length tolerance [m].
SegmentIntersection intersect_segments(const Vec2& p0, const Vec2& p1, const Vec2& q0,
                                       const Vec2& q1, double eps = 1e-12);

/// Result of a ray (or segment) query.
struct RayHit {
  bool hit = false;
  double t = 0.0;            ///< distance along the unit direction [m] (or parameter, see function)
  Vec2 point = Vec2::Zero();
};

/// First intersection of the ray origin + s * dir (dir unit, s in [0, max_range])
/// with segment [a, b]. A ray running along a collinear segment hits at its
/// first point (s = 0 if the origin lies on it).
RayHit ray_segment(const Vec2& origin, const Vec2& dir, const Vec2& a, const Vec2& b,
                   double max_range);

/// First intersection of the ray with the circle (centre, radius), s in
/// [0, max_range]. An origin inside or on the circle hits at s = 0.
RayHit ray_circle(const Vec2& origin, const Vec2& dir, const Vec2& center, double radius,
                  double max_range);

/// First intersection of segment [a, b] with the circle; t is the parameter
/// along a -> b in [0, 1] (0 if a is inside or on the circle).
RayHit segment_circle(const Vec2& a, const Vec2& b, const Vec2& center, double radius);

}  // namespace tactile_sim::geom
