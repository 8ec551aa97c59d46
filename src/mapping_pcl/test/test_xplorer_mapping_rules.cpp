// The issue-17 stamping rules of the XPLORER mapper (README "Procedural
// objects"), each against a hand-made case: mapping initiated at delta_map and
// held down to delta_map_hold, slabs held back and dropped at a corner
// release, and the two-arm (square) contact check.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "mapping_pcl/xplorer_map_logic.hpp"
#include "mapping_pcl/xplorer_stamping.hpp"
#include "tactile_common/time.hpp"

using namespace mapping_pcl;

namespace {
ContactSample sample(double t, double x, double fx, std::array<double, 4> arms = {-0.05, 0.05, 0.0, 0.0}) {
  ContactSample s;
  s.t = t;
  s.position = Vec3(x, 0.0, 0.7);
  s.height = 0.7;
  s.force_body = Eigen::Vector2d(fx, 0.0);  // pushed back: obstacle ahead (+x)
  s.arm_angles = arms;
  return s;
}
}  // namespace

// 001 Sec. IV-B: "obstacle map generation initializes when |b_delta_f| >=
// delta_map". The traversal then holds ~1.25-1.4 N (below 1.51 N): with
// delta_map_hold = 0.5 N the map goes on; below 0.5 N it stops and needs
// 1.51 N again.
TEST(XplorerMappingRules, InitiatedAtDeltaMapAndHeldDownToTheHoldForce) {
  XplorerMapParams p;
  p.delta_map_hold = 0.5;
  PointMap map;
  XplorerContactMapper m(p, map);
  EXPECT_EQ(m.update(sample(0.0, 0.0, -1.3)), 0);  // 1.3 N: not initiated yet
  EXPECT_FALSE(m.initiated());
  EXPECT_EQ(m.update(sample(0.1, 0.0, -1.6)), 1);  // >= 1.51 N: initiated, stamps
  EXPECT_EQ(m.update(sample(0.2, 0.0, -1.3)), 1);  // held at 1.3 N (the old gate: 0)
  EXPECT_EQ(m.update(sample(0.3, 0.0, -0.6)), 1);  // still >= 0.5 N
  EXPECT_EQ(m.update(sample(0.4, 0.0, -0.4)), 0);  // released
  EXPECT_EQ(m.update(sample(0.5, 0.0, -1.3)), 0);  // 1.3 N does not re-initiate
  EXPECT_EQ(m.stats().initiations, 1u);
  EXPECT_EQ(m.stats().releases, 1u);
  // observe_force (ticks the node logic does not stamp) sets the latch as well.
  m.observe_force({-1.55, 0.0});
  EXPECT_TRUE(m.initiated());
  EXPECT_EQ(m.update(sample(0.6, 0.0, -1.3)), 1);
  // delta_map_hold = delta_map is the per-sample gate of 001 (before issue 17).
  PointMap map2;
  XplorerMapParams per_sample;
  per_sample.delta_map_hold = per_sample.delta_map;
  XplorerContactMapper old(per_sample, map2);
  EXPECT_EQ(old.update(sample(0.0, 0.0, -1.6)), 1);
  EXPECT_EQ(old.update(sample(0.1, 0.0, -1.3)), 0);
  XplorerMapParams bad;
  bad.delta_map_hold = 2.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// A face traversed along -y towards a corner, a slab every 0.125 s (0.02 m
// apart), held back 0.5 s. At t = 2.5 s the slabs of t <= 2.0 s (k = 0 .. 16)
// are in the map, k = 17 .. 20 wait; the turn drops those four. The map's far
// end is the last kept slab's centre (y = -0.32 m) less 0.125 m.
TEST(XplorerMappingRules, CornerReleaseDropsTheSlabsStampedJustBeforeIt) {
  XplorerMapParams p;
  p.corner_release_s = 0.5;
  auto fly = [&](XplorerContactMapper& m) {
    for (int k = 0; k <= 20; ++k) {
      ContactSample s = sample(0.125 * k, 0.0, -2.0);
      s.position = Vec3(0.5, -0.02 * k, 0.7);
      ASSERT_EQ(m.update(s), 1);
    }
  };
  PointMap map;
  XplorerContactMapper m(p, map);
  fly(m);
  EXPECT_EQ(m.pending(), 4u);
  EXPECT_EQ(m.release_corner(2.5), 4u);
  EXPECT_EQ(m.stats().dropped_at_corner, 4u);
  m.flush();
  EXPECT_NEAR(map.measure().min.y(), -0.32 - 0.125, 1e-6);
  EXPECT_NEAR(map.measure().max.y(), 0.125, 1e-6);
  // Without a release every slab enters: to -0.40 - 0.125 m.
  PointMap map2;
  XplorerContactMapper all(p, map2);
  fly(all);
  all.flush();
  EXPECT_NEAR(map2.measure().min.y(), -0.40 - 0.125, 1e-6);
  // corner_release_s = 0: straight into the map, nothing to drop.
  PointMap map3;
  XplorerMapParams at_once;
  at_once.corner_release_s = 0.0;
  XplorerContactMapper now(at_once, map3);
  fly(now);
  EXPECT_EQ(now.pending(), 0u);
  EXPECT_EQ(now.release_corner(2.5), 0u);
}

// 001 Sec. V-C1: "the yaw is in admittance ensuring two arms of the UAV are in
// contact". Obstacle ahead (+b1): arms 0 (-45 deg) and 1 (+45 deg) face it.
// One guard on a corner deflects one of them only (SITL, an oblique first
// contact: arm 1 0.08 rad, arm 0 0.000-0.002 rad): no slab below 0.002 rad.
TEST(XplorerMappingRules, SlabsOnlyWhileBothArmsFacingTheContactAreDeflected) {
  EXPECT_TRUE(both_arms_touch({1, 0}, {-0.014, 0.08, 0, 0}, 0.005));
  EXPECT_FALSE(both_arms_touch({1, 0}, {-0.002, 0.08, 0, 0}, 0.005));
  EXPECT_FALSE(both_arms_touch({1, 0}, {-0.05, 0.0, 0.3, 0.3}, 0.005));
  // Obstacle on the right (-b2): arms 0 (-45 deg) and 3 (-135 deg).
  EXPECT_TRUE(both_arms_touch({0, -1}, {0.05, 0.0, 0.0, -0.05}, 0.005));
  EXPECT_FALSE(both_arms_touch({0, -1}, {0.05, 0.05, 0.05, 0.0}, 0.005));
  XplorerMapParams p;
  p.min_arm_deflection = 0.002;
  PointMap map;
  XplorerContactMapper m(p, map);
  EXPECT_EQ(m.update(sample(0.0, 0.0, -2.0, {-0.001, 0.08, 0, 0})), 0);
  EXPECT_EQ(m.stats().skipped_one_arm, 1u);
  EXPECT_EQ(m.update(sample(0.1, 0.0, -2.0, {-0.014, 0.08, 0, 0})), 1);
  // Without arm angles there is nothing to check: the slab is stamped.
  ContactSample s = sample(0.2, 0.0, -2.0);
  s.arm_angles.reset();
  EXPECT_EQ(m.update(s), 1);
}

// The node logic drops the held-back slabs when the FSM reports
// Tactile-turning, dated by the state's entry time (stamp - time_in_state).
TEST(XplorerMappingRules, LogicReleasesTheCornerOnTactileTurning) {
  auto d = XplorerMapLogic::default_parameters();
  d.set("corner_release_s", 0.5);
  d.set("min_state_time_s", 0.0);
  d.set("delta_map_hold", 0.5);
  d.set("publish_rate_hz", 0.0);
  XplorerMapLogic logic(XplorerMapLogic::params_from(d));
  tactile_msgs::msg::FsmState st;
  st.state = "tactile_traversal";
  logic.on_fsm_state(st);
  geometry_msgs::msg::WrenchStamped w;
  w.header.frame_id = "base_link";
  w.wrench.force.x = -1.6;
  logic.on_wrench_body(w);
  for (int k = 0; k <= 20; ++k) {
    const int64_t ns = tactile_common::from_seconds(0.125 * k);
    nav_msgs::msg::Odometry o;
    tactile_common::to_stamp(ns, o.header.stamp);
    o.child_frame_id = "base_link";
    o.pose.pose.position.y = -0.02 * k;
    o.pose.pose.position.z = 0.7;
    o.pose.pose.orientation.w = 1.0;
    logic.on_odometry(o);
    logic.on_timer(ns);
  }
  EXPECT_EQ(logic.mapper().stats().slabs, 21u);
  EXPECT_EQ(logic.mapper().pending(), 4u);  // t = 2.125 .. 2.5 s
  st.state = "tactile_turning";             // entered at 2.25 s, heard at 2.5 s
  tactile_common::to_stamp(tactile_common::from_seconds(2.5), st.header.stamp);
  st.time_in_state = 0.25;
  logic.on_fsm_state(st);
  EXPECT_EQ(logic.mapper().stats().dropped_at_corner, 4u);
  const MapMeasurement r = logic.finalize();
  EXPECT_NEAR(r.min.y(), -0.32 - 0.125, 0.011);
}
