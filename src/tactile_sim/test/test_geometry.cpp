// 2D primitives against hand-computed cases.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_sim/geometry.hpp"

using tactile_sim::Vec2;
namespace geom = tactile_sim::geom;

TEST(Geometry, ClosestPointInteriorAndEndpoints) {
  const Vec2 a(0, 0), b(2, 0);
  double t = -1;
  EXPECT_TRUE(geom::closest_point_on_segment({0.5, 1.0}, a, b, &t).isApprox(Vec2(0.5, 0)));
  EXPECT_DOUBLE_EQ(t, 0.25);
  EXPECT_TRUE(geom::closest_point_on_segment({-1, 1}, a, b, &t).isApprox(Vec2(0, 0)));
  EXPECT_DOUBLE_EQ(t, 0.0);
  EXPECT_TRUE(geom::closest_point_on_segment({5, -3}, a, b, &t).isApprox(Vec2(2, 0)));
  EXPECT_DOUBLE_EQ(t, 1.0);
  // Zero-length segment returns its point.
  EXPECT_TRUE(geom::closest_point_on_segment({3, 4}, a, a, &t).isApprox(a));
}

TEST(Geometry, PointSegmentDistance) {
  // Diagonal segment (0,0)-(1,1); point (1,0) is at distance 1/sqrt(2).
  EXPECT_NEAR(geom::point_segment_distance({1, 0}, {0, 0}, {1, 1}), std::sqrt(0.5), 1e-15);
  // Beyond an end: distance to the endpoint (3-4-5 triangle).
  EXPECT_NEAR(geom::point_segment_distance({4, 5}, {0, 0}, {1, 1}), 5.0, 1e-15);
  EXPECT_NEAR(geom::point_segment_distance({0.5, 0.5}, {0, 0}, {1, 1}), 0.0, 1e-15);
}

TEST(Geometry, SegmentsCrossing) {
  // x from (0,0) to (2,2) and (0,2) to (2,0): cross at (1,1), t = u = 0.5.
  const auto x = geom::intersect_segments({0, 0}, {2, 2}, {0, 2}, {2, 0});
  ASSERT_TRUE(x.hit);
  EXPECT_FALSE(x.collinear);
  EXPECT_NEAR(x.t, 0.5, 1e-15);
  EXPECT_NEAR(x.u, 0.5, 1e-15);
  EXPECT_TRUE(x.point.isApprox(Vec2(1, 1)));
  // Unequal parameters: (0,0)-(4,0) against (1,-1)-(1,3): t = 0.25, u = 0.25.
  const auto y = geom::intersect_segments({0, 0}, {4, 0}, {1, -1}, {1, 3});
  ASSERT_TRUE(y.hit);
  EXPECT_NEAR(y.t, 0.25, 1e-15);
  EXPECT_NEAR(y.u, 0.25, 1e-15);
}

TEST(Geometry, SegmentsMiss) {
  // Lines cross at (3,0) but the first segment ends at x = 2.
  EXPECT_FALSE(geom::intersect_segments({0, 0}, {2, 0}, {3, -1}, {3, 1}).hit);
  // Parallel, 1 apart.
  EXPECT_FALSE(geom::intersect_segments({0, 0}, {2, 0}, {0, 1}, {2, 1}).hit);
  // Collinear but disjoint.
  EXPECT_FALSE(geom::intersect_segments({0, 0}, {1, 0}, {2, 0}, {3, 0}).hit);
}

TEST(Geometry, SegmentsEndpointTouching) {
  // T junction: the second segment ends on the first.
  const auto x = geom::intersect_segments({0, 0}, {2, 0}, {1, 1}, {1, 0});
  ASSERT_TRUE(x.hit);
  EXPECT_NEAR(x.t, 0.5, 1e-15);
  EXPECT_NEAR(x.u, 1.0, 1e-15);
  // Shared endpoint (polyline vertex).
  const auto y = geom::intersect_segments({0, 0}, {1, 0}, {1, 0}, {1, 1});
  ASSERT_TRUE(y.hit);
  EXPECT_NEAR(y.t, 1.0, 1e-15);
  EXPECT_NEAR(y.u, 0.0, 1e-15);
}

TEST(Geometry, SegmentsCollinearOverlap) {
  // p: (0,0)-(4,0); q: (3,0)-(1,0) overlaps on [1,3]; first common point along p is x = 1.
  const auto x = geom::intersect_segments({0, 0}, {4, 0}, {3, 0}, {1, 0});
  ASSERT_TRUE(x.hit);
  EXPECT_TRUE(x.collinear);
  EXPECT_NEAR(x.t, 0.25, 1e-15);
  EXPECT_NEAR(x.u, 1.0, 1e-15);
  EXPECT_TRUE(x.point.isApprox(Vec2(1, 0)));
  // Collinear touching at one end point only.
  const auto y = geom::intersect_segments({0, 0}, {1, 0}, {1, 0}, {2, 0});
  ASSERT_TRUE(y.hit);
  EXPECT_NEAR(y.t, 1.0, 1e-15);
}

TEST(Geometry, RaySegment) {
  const Vec2 o(0, 0), d(1, 0);
  // Wall at x = 2 from y = -1 to 1: hit at 2.
  auto r = geom::ray_segment(o, d, {2, -1}, {2, 1}, 5.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 2.0, 1e-14);
  // Out of range.
  EXPECT_FALSE(geom::ray_segment(o, d, {2, -1}, {2, 1}, 1.5).hit);
  // Behind the origin.
  EXPECT_FALSE(geom::ray_segment(o, d, {-2, -1}, {-2, 1}, 5.0).hit);
  // 45 deg ray hits the wall x = 1 at (1, 1), distance sqrt(2).
  r = geom::ray_segment(o, Vec2(1, 1).normalized(), {1, -5}, {1, 5}, 5.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, std::sqrt(2.0), 1e-14);
  // Ray along a collinear segment ahead: first point at 1.
  r = geom::ray_segment(o, d, {3, 0}, {1, 0}, 5.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 1.0, 1e-14);
}

TEST(Geometry, RayCircle) {
  // Circle at (3,0) radius 1: ray from origin along x enters at 2.
  auto r = geom::ray_circle({0, 0}, {1, 0}, {3, 0}, 1.0, 10.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 2.0, 1e-14);
  // Offset by 0.6 in y: chord entry at 3 - sqrt(1 - 0.36) = 2.2.
  r = geom::ray_circle({0, 0.6}, {1, 0}, {3, 0}, 1.0, 10.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 2.2, 1e-14);
  // Tangent at y = 1 touches at x = 3.
  r = geom::ray_circle({0, 1}, {1, 0}, {3, 0}, 1.0, 10.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 3.0, 1e-7);
  // Misses: passing above, pointing away, out of range.
  EXPECT_FALSE(geom::ray_circle({0, 1.01}, {1, 0}, {3, 0}, 1.0, 10.0).hit);
  EXPECT_FALSE(geom::ray_circle({0, 0}, {-1, 0}, {3, 0}, 1.0, 10.0).hit);
  EXPECT_FALSE(geom::ray_circle({0, 0}, {1, 0}, {3, 0}, 1.0, 1.9).hit);
  // Origin inside: hit at 0.
  r = geom::ray_circle({3.2, 0}, {1, 0}, {3, 0}, 1.0, 10.0);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.t, 0.0);
}

TEST(Geometry, SegmentCircle) {
  // Segment (0,0)-(4,0) against circle (3,0) r 1: enters at x = 2, t = 0.5.
  auto r = geom::segment_circle({0, 0}, {4, 0}, {3, 0}, 1.0);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.t, 0.5, 1e-14);
  EXPECT_TRUE(r.point.isApprox(Vec2(2, 0)));
  // Ends before the circle.
  EXPECT_FALSE(geom::segment_circle({0, 0}, {1.9, 0}, {3, 0}, 1.0).hit);
  // Starts inside.
  r = geom::segment_circle({3, 0.5}, {6, 0}, {3, 0}, 1.0);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.t, 0.0);
}
