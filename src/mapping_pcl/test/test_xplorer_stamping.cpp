// XPLORER slab stamping rules (001 Sec. IV-B, V-D) against hand geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "mapping_pcl/xplorer_stamping.hpp"

using namespace mapping_pcl;

namespace {
ContactSample sample(double t, Vec3 p, double yaw, Eigen::Vector2d f) {
  ContactSample s;
  s.t = t;
  s.position = p;
  s.yaw = yaw;
  s.height = p.z();
  s.force_body = f;
  return s;
}
}  // namespace

TEST(XplorerStamping, FaceSlabGeometryByHand) {
  PointMap map;
  XplorerContactMapper m(XplorerMapParams{}, map);
  // Level, facing +x, obstacle ahead: near face at 0.21 m, centre at 0.25 m.
  Box b = m.face_slab(sample(0, Vec3(1, 2, 0.7), 0.0, {-2, 0}), BodyDirection::kPlusX);
  EXPECT_NEAR(b.center.x(), 1.25, 1e-12);
  EXPECT_NEAR(b.center.y(), 2.0, 1e-12);
  EXPECT_NEAR(b.center.z(), 0.7, 1e-12);
  EXPECT_NEAR(std::cos(b.yaw), 0.0, 1e-12);  // box x (0.25 m) along world y
  // Yawed +90 deg: body +x is world +y.
  b = m.face_slab(sample(0, Vec3(0, 0, 0.7), M_PI / 2, {-2, 0}), BodyDirection::kPlusX);
  EXPECT_NEAR(b.center.x(), 0.0, 1e-12);
  EXPECT_NEAR(b.center.y(), 0.25, 1e-12);
  map.insert_box(b, 0.02);
  const MapMeasurement r = map.measure();
  EXPECT_NEAR(r.min.y(), 0.21, 1e-6);
  EXPECT_NEAR(r.max.y(), 0.29, 1e-6);
  EXPECT_NEAR(r.min.x(), -0.125, 1e-6);
}

TEST(XplorerStamping, ThresholdFlyingCheckAndRate) {
  PointMap map;
  XplorerContactMapper m(XplorerMapParams{}, map);
  EXPECT_EQ(m.update(sample(0.0, Vec3(0, 0, 0.7), 0, {-1.50, 0})), 0);  // below 1.51 N
  EXPECT_EQ(m.update(sample(0.01, Vec3(0, 0, 0.05), 0, {-2.0, 0})), 0);  // not flying
  EXPECT_EQ(m.stats().skipped_low_force, 1u);
  EXPECT_EQ(m.stats().skipped_not_flying, 1u);
  // 1 s of samples at 100 Hz with firm contact: 30 Hz stamping -> 25 slabs
  // (every 4th sample at 0.04 s spacing: the first sample >= 1/30 s after the last).
  int slabs = 0;
  for (int k = 0; k < 100; ++k) slabs += m.update(sample(1.0 + k * 0.01, Vec3(0, 0, 0.7), 0, {-2.0, 0}));
  EXPECT_EQ(slabs, 25);
  EXPECT_EQ(m.stats().corner_slabs, 0u);
  EXPECT_EQ(m.update(sample(3.0, Vec3(std::nan(""), 0, 0.7), 0, {-2.0, 0})), 0);
  EXPECT_EQ(m.stats().rejected_nonfinite, 1u);
}

TEST(XplorerStamping, CornerSlabWhenTheMoveDirectionChanges) {
  PointMap map;
  XplorerContactMapper m(XplorerMapParams{}, map);
  // Obstacle ahead (+x world), moving -y (right-hand).
  EXPECT_EQ(m.update(sample(0.0, Vec3(0, 0, 0.7), 0.0, {-2, 0})), 1);
  // Turned right by 90 deg round a convex corner: body +x at yaw -90 deg is
  // world -y; lambda = body -y = world -x: the move direction changed.
  const ContactSample s = sample(1.0, Vec3(0, -1, 0.7), -M_PI / 2, {-2, 0});
  EXPECT_EQ(m.update(s), 2);
  EXPECT_EQ(m.stats().corner_slabs, 1u);
  const Box c = m.corner_slab(s, Eigen::Vector2d(1, 0), Eigen::Vector2d(0, -1));
  EXPECT_NEAR(c.center.x(), 0.417 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(c.center.y(), -1.0 - 0.417 * std::sqrt(0.5), 1e-12);
}

TEST(XplorerStamping, IdealBoxTraversalMapsTheBoxFootprint) {
  // An ideal traversal of a 1.22 m x 1.0 m box (x in [0, 1.22], y in [0, 1]):
  // centre 0.21 m from each face, facing it, slabs covering each face, 50 Hz.
  PointMap map;
  XplorerContactMapper m(XplorerMapParams{}, map);
  const double L = 1.22, W = 1.0, d = 0.21, h = 0.125;
  double t = 0.0;
  auto face = [&](Eigen::Vector2d a, Eigen::Vector2d b, double yaw) {
    const int n = 100;
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector2d p = a + (b - a) * k / n;
      m.update(sample(t, Vec3(p.x(), p.y(), 0.7), yaw, {-2, 0}));
      t += 0.02;
    }
  };
  // Right-hand traversal (lambda = C_n turned by -90 deg), clockwise seen from above.
  face({-d, W - h}, {-d, h}, 0.0);                 // west face, facing +x, moving -y
  face({h, -d}, {L - h, -d}, M_PI / 2);            // south face, facing +y, moving +x
  face({L + d, h}, {L + d, W - h}, M_PI);          // east face, facing -x, moving +y
  face({L - h, W + d}, {h, W + d}, -M_PI / 2);     // north face, facing -y, moving -x
  // Three corners; each diagonal slab lies inside the box (0.417 m along the
  // bisector of the two contact directions from a point 0.21 m off the new face).
  EXPECT_EQ(m.stats().corner_slabs, 3u);
  map.voxel_filter(0.01);
  const MapMeasurement r = map.measure();
  EXPECT_NEAR(r.length, L, 0.011);
  EXPECT_NEAR(r.width, W, 0.011);
  EXPECT_NEAR(r.obb_area / (L * W), 1.0, 0.02);
  EXPECT_NEAR(r.height, 0.5, 0.011);
}

// The CAD outline with the arms as they are (edge_from_arms). Undeflected,
// along +b1: arms 0 and 1 reach (0.05 + 0.15) cos 45 deg = 0.141421 m, plus
// the 0.07 m guard: 0.211421 m. Arm 0 (at -45 deg) folded back by -0.05 rad:
// its motor at 0.05 (cos, sin)(-45 deg) + 0.15 (cos, sin)(-45 deg - 2.865 deg)
// has x = 0.035355 + 0.15 cos(0.835398) = 0.035355 + 0.100633 = 0.135988; arm
// 1 folded by +0.05 rad likewise: the reach drops to 0.205988 m.
TEST(XplorerStamping, OutlineReachFromTheArmAnglesByHand) {
  const XplorerMapParams p;
  EXPECT_NEAR(outline_reach(p, {1, 0}, {0, 0, 0, 0}), 0.211421, 1e-6);
  EXPECT_NEAR(outline_reach(p, {0, -1}, {0, 0, 0, 0}), 0.211421, 1e-6);
  EXPECT_NEAR(outline_reach(p, {1, 0}, {-0.05, 0.05, 0, 0}), 0.205988, 1e-6);
  // Only arm 0 folded: arm 1 still reaches 0.211421 m.
  EXPECT_NEAR(outline_reach(p, {1, 0}, {-0.05, 0, 0, 0}), 0.211421, 1e-6);

  // The stamped slab's near face follows the outline when arm angles come
  // with the sample, the fixed 0.21 m when they do not (or are NaN).
  PointMap map;
  XplorerContactMapper m(p, map);
  ContactSample s = sample(0, Vec3(0, 0, 0.7), 0.0, {-2, 0});
  s.arm_angles = std::array<double, 4>{-0.05, 0.05, 0, 0};
  ASSERT_EQ(m.update(s), 1);
  m.flush();  // slabs are held back corner_release_s before entering the map
  EXPECT_NEAR(map.measure().min.x(), 0.205988, 1e-6);
  EXPECT_EQ(m.stats().offset_from_arms, 1u);
  PointMap map2;
  XplorerContactMapper m2(p, map2);
  s.arm_angles = std::array<double, 4>{std::nan(""), 0.05, 0, 0};
  ASSERT_EQ(m2.update(s), 1);
  m2.flush();
  EXPECT_NEAR(map2.measure().min.x(), 0.21, 1e-6);
  EXPECT_EQ(m2.stats().offset_from_arms, 0u);
  XplorerMapParams off;
  off.edge_from_arms = false;
  PointMap map3;
  XplorerContactMapper m3(off, map3);
  s.arm_angles = std::array<double, 4>{-0.05, 0.05, 0, 0};
  ASSERT_EQ(m3.update(s), 1);
  m3.flush();
  EXPECT_NEAR(map3.measure().min.x(), 0.21, 1e-6);
  off.arm_length = 0.0;
  EXPECT_THROW(off.validate(), std::invalid_argument);
}
