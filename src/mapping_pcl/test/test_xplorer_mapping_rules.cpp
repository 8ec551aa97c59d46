// The issue-17 stamping rules of the XPLORER mapper (README "Procedural
// objects"), each against a hand-made case: mapping initiated at delta_map and
// held down to delta_map_hold, slabs held back and dropped at a corner
// release, and the two-arm (square) contact check.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

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

// The node logic in Tactile-traversal pressed with 1.6 N, flying along -y at 0.16 m/s
// with a timer tick every 0.125 s for 2.5 s (21 slabs; the last corner_release_s of them
// held back).
void traverse_one_face(XplorerMapLogic& logic) {
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
}

// Node parameters of the contact-now tests: the check over the latest 5 wrench samples at
// 0.5 N, nothing held back, no minimum state time (after Exploration or a turn).
auto contact_now_params() {
  auto d = XplorerMapLogic::default_parameters();
  d.set("min_state_time_s", 0.0);
  d.set("min_state_time_after_turn_s", 0.0);
  d.set("corner_release_s", 0.0);
  d.set("publish_rate_hz", 0.0);
  d.set("min_force_now", 0.5);
  d.set("force_now_samples", static_cast<int64_t>(5));
  return XplorerMapLogic::params_from(d);
}
// Odometry at the origin (0.7 m up, yaw 0) stamped t, then the node's timer at t.
void tick_at_origin(XplorerMapLogic& logic, double t) {
  const int64_t ns = tactile_common::from_seconds(t);
  nav_msgs::msg::Odometry o;
  o.child_frame_id = "base_link";
  o.pose.pose.position.z = 0.7;
  o.pose.pose.orientation.w = 1.0;
  tactile_common::to_stamp(ns, o.header.stamp);
  logic.on_odometry(o);
  logic.on_timer(ns);
}

// A traversal entered at 0 s from `previous`, pressed along -x (1.6 N), at rest 0.7 m up;
// one odometry sample and one timer tick at `t` seconds.
void enter_traversal_and_press(XplorerMapLogic& logic, const std::string& previous, double t) {
  tactile_msgs::msg::FsmState st;
  st.state = "tactile_traversal";
  st.previous_state = previous;
  logic.on_fsm_state(st);
  geometry_msgs::msg::WrenchStamped w;
  w.header.frame_id = "base_link";
  w.wrench.force.x = -1.6;
  logic.on_wrench_body(w);
  tick_at_origin(logic, t);
}

/// One traversal stamp 0.21 m (slab_offset, edge_from_arms off) behind a surface
/// point, the yaw (C_n = +b1) on the face normal c turned by tilt; t advances 0.1 s.
void stamp_at(XplorerContactMapper& m, double& t, const Eigen::Vector2d& surface, const Eigen::Vector2d& c,
              double tilt = 0.0) {
  ContactSample s = sample(t, 0.0, -2.0);
  s.arm_angles.reset();
  const Eigen::Vector2d cn = Eigen::Rotation2Dd(tilt) * c;
  s.position = Vec3(surface.x() - 0.21 * cn.x(), surface.y() - 0.21 * cn.y(), 0.7);
  s.yaw = std::atan2(cn.y(), cn.x());
  m.update(s);
  t += 0.1;
}

/// The stamping rules' tests' parameters: no corner release, and the near face at
/// slab_offset = 0.21 m behind the contact (edge_from_arms off), as stamp_at() assumes.
XplorerMapParams rule_params() {
  XplorerMapParams p;
  p.corner_release_s = 0.0;
  p.edge_from_arms = false;
  return p;
}

/// A point map and the contact mapper stamping into it, with stamp_at()'s clock.
struct Stamper {
  explicit Stamper(const XplorerMapParams& p) : mapper(p, map) {}
  PointMap map;
  XplorerContactMapper mapper;
  double t = 0.0;
  void at(const Eigen::Vector2d& surface, const Eigen::Vector2d& c, double tilt = 0.0) {
    stamp_at(mapper, t, surface, c, tilt);
  }
};
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
  traverse_one_face(logic);
  EXPECT_EQ(logic.mapper().stats().slabs, 21u);
  tactile_msgs::msg::FsmState st;
  EXPECT_EQ(logic.mapper().pending(), 4u);  // t = 2.125 .. 2.5 s
  st.state = "tactile_turning";             // entered at 2.25 s, heard at 2.5 s
  tactile_common::to_stamp(tactile_common::from_seconds(2.5), st.header.stamp);
  st.time_in_state = 0.25;
  logic.on_fsm_state(st);
  EXPECT_EQ(logic.mapper().stats().dropped_at_corner, 4u);
  const MapMeasurement r = logic.finalize();
  EXPECT_NEAR(r.min.y(), -0.32 - 0.125, 0.011);
}

// README "Contact now": the 50-sample (1 s) average still reads the impact of
// the first contact after the vehicle has rebounded off the face (SITL seed
// 1040: the average 1.8-2.3 N at 5.0-5.2 s, the latest samples < 0.1 N, the
// vehicle centre 0.25 m from the face, slabs 4.5-5 cm outside it). A slab is
// stamped only with the mean of the latest samples >= min_force_now.
TEST(XplorerMappingRules, SlabsOnlyWhileTheLatestSamplesStillPress) {
  XplorerMapParams p;
  p.min_force_now = 0.5;
  PointMap map;
  XplorerContactMapper m(p, map);
  ContactSample s = sample(0.0, 0.0, -2.0);
  s.force_body_now = Eigen::Vector2d(-0.05, 0.02);  // contact ended, average still 2 N
  EXPECT_EQ(m.update(s), 0);
  EXPECT_EQ(m.stats().skipped_no_contact_now, 1u);
  EXPECT_TRUE(m.initiated());  // the latch keeps the averaged force's state
  s = sample(0.1, 0.0, -2.0);
  s.force_body_now = Eigen::Vector2d(-0.3, 0.45);  // |(-0.3, 0.45)| = 0.54 N >= 0.5 N
  EXPECT_EQ(m.update(s), 1);
  s = sample(0.2, 0.0, -2.0);  // not known: no check
  EXPECT_EQ(m.update(s), 1);
  XplorerMapParams off;
  off.min_force_now = 0.0;
  PointMap map2;
  XplorerContactMapper m2(off, map2);
  s = sample(0.0, 0.0, -2.0);
  s.force_body_now = Eigen::Vector2d::Zero();
  EXPECT_EQ(m2.update(s), 1);
  XplorerMapParams bad;
  bad.min_force_now = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The node logic's "now" force is the mean of the latest force_now_samples
// wrench messages: 45 at 2 N then 5 at 0.1 N average 1.81 N over 50 (mapping
// initiated and held) but 0.1 N over the latest 5: no slab; one more 2 N
// sample makes the latest 5 (4 x 0.1 + 2) / 5 = 0.48 N (still none), two more
// 0.86 N: a slab.
TEST(XplorerMappingRules, LogicTakesTheContactNowFromTheLatestSamples) {
  XplorerMapLogic logic(contact_now_params());
  geometry_msgs::msg::WrenchStamped w;
  w.header.frame_id = "base_link";
  auto push = [&](double fx, int n) {
    for (int i = 0; i < n; ++i) {
      w.wrench.force.x = fx;
      logic.on_wrench_body(w);
    }
  };
  nav_msgs::msg::Odometry o;
  o.child_frame_id = "base_link";
  o.pose.pose.position.z = 0.7;
  o.pose.pose.orientation.w = 1.0;
  auto tick = [&](double t) {
    const int64_t ns = tactile_common::from_seconds(t);
    tactile_common::to_stamp(ns, o.header.stamp);
    logic.on_odometry(o);
    logic.on_timer(ns);
  };
  push(-2.0, 45);
  push(-0.1, 5);
  tick(0.0);
  EXPECT_TRUE(logic.mapper().initiated());
  EXPECT_EQ(logic.mapper().stats().slabs, 0u);
  EXPECT_EQ(logic.mapper().stats().skipped_no_contact_now, 1u);
  push(-2.0, 1);
  tick(0.1);
  EXPECT_EQ(logic.mapper().stats().slabs, 0u);
  push(-2.0, 1);
  tick(0.2);
  EXPECT_EQ(logic.mapper().stats().slabs, 1u);
  auto d = XplorerMapLogic::default_parameters();
  d.set("force_now_samples", static_cast<int64_t>(51));  // more than the 50-sample average
  try {
    XplorerMapLogic::params_from(d);
    FAIL() << "no error";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("force_now_samples: must be in [0, force_average_samples], got 51"),
              std::string::npos) << e.what();
  }
  d.set("force_now_samples", static_cast<int64_t>(4294967306));  // 2^32 + 10: not taken as 10
  try {
    XplorerMapLogic::params_from(d);
    FAIL() << "no error";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("force_now_samples: must be in [0, 2147483647], got 4294967306"),
              std::string::npos) << e.what();
  }
}

// README "Right-angle corners". The corner slab of 001 (0.417 m along the
// bisector of the previous and the new C_n) fits a 90 deg corner. Cases by
// hand: a box corner (same body axis +b1, C_n turned 84 deg in the world, as
// measured at the SITL box corners): kept; a 5-6 sided polygon's corner (C_n
// turned 62 deg): none; a face at 45 deg to the world axes (C_n turned 1 deg
// across the 45 deg line, lambda's world axis changes): none; the contact
// jumping from +b1 to -b2 mid-face: none.
TEST(XplorerMappingRules, CornerSlabOnlyAtRightAngleCorners) {
  const double tol = 10.0 * M_PI / 180.0;
  auto dir = [](double deg) { return Eigen::Vector2d(std::cos(deg * M_PI / 180.0), std::sin(deg * M_PI / 180.0)); };
  const auto X = BodyDirection::kPlusX;
  EXPECT_TRUE(is_right_angle_corner(X, dir(0), X, dir(84), tol));
  EXPECT_TRUE(is_right_angle_corner(X, dir(10), X, dir(-88), tol));
  EXPECT_FALSE(is_right_angle_corner(X, dir(0), X, dir(62), tol));
  EXPECT_FALSE(is_right_angle_corner(X, dir(44.5), X, dir(45.5), tol));
  EXPECT_FALSE(is_right_angle_corner(X, dir(0), BodyDirection::kMinusY, dir(-90), tol));
  EXPECT_FALSE(is_right_angle_corner(BodyDirection::kNone, dir(0), X, dir(90), tol));
  EXPECT_TRUE(is_right_angle_corner(X, dir(44.5), X, dir(45.5), M_PI / 2));  // 001: every lambda change
  // The mapper: vehicle yawed so that C_n (+b1) points along 44 deg, then 46 deg
  // (lambda's world axis changes from -X... to the next): no corner slab; then
  // yawed by a further 90 deg: a corner slab.
  XplorerMapParams p;
  p.corner_angle_tolerance = tol;
  p.corner_release_s = 0.0;
  PointMap map;
  XplorerContactMapper m(p, map);
  auto at = [&](double t, double yaw_deg) {
    ContactSample s = sample(t, 0.0, -2.0);
    s.yaw = yaw_deg * M_PI / 180.0;
    return m.update(s);
  };
  EXPECT_EQ(at(0.0, 44.0), 1);
  EXPECT_EQ(at(0.1, 46.0), 1);  // lambda: world axis changed, C_n turned 2 deg
  EXPECT_EQ(m.stats().skipped_corner_angle, 1u);
  EXPECT_EQ(at(0.2, 136.0), 2);  // turned 90 deg: face slab + corner slab
  EXPECT_EQ(m.stats().corner_slabs, 1u);
  XplorerMapParams bad;
  bad.corner_angle_tolerance = 4.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  XplorerMapParams every;  // 1.5708 > pi/2 in a config file: every lambda change, as 001
  every.corner_angle_tolerance = 1.5708;
  EXPECT_NO_THROW(every.validate());
  EXPECT_TRUE(is_right_angle_corner(X, dir(44.5), X, dir(45.5), every.corner_angle_tolerance));
}

// README "Release on every end of a traversal": the loop closing ("done",
// SITL seed 1041: the first contact point next to a corner, the last slabs
// 3 cm past it) and the contact lost ("exploration") drop the held-back slabs
// as Tactile-turning does; a state not in release_states does not.
TEST(XplorerMappingRules, LogicReleasesOnEveryEndOfATraversal) {
  for (const std::string state : {"done", "exploration", "static_wrench"}) {
    auto d = XplorerMapLogic::default_parameters();
    d.set("corner_release_s", 0.5);
    d.set("min_state_time_s", 0.0);
    d.set("publish_rate_hz", 0.0);
    d.set("min_force_now", 0.0);
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    traverse_one_face(logic);  // a slab every 0.125 s, 0.5 s held back
    ASSERT_EQ(logic.mapper().pending(), 4u) << state;
    tactile_msgs::msg::FsmState st;
    st.state = state;  // entered at 2.5 s
    tactile_common::to_stamp(tactile_common::from_seconds(2.5), st.header.stamp);
    st.time_in_state = 0.0;
    logic.on_fsm_state(st);
    EXPECT_EQ(logic.mapper().stats().dropped_at_corner, state == "static_wrench" ? 0u : 4u) << state;
  }
}

// contact_now_after: the contact-now check applies in a traversal entered from
// Exploration (the impact at 0.3 m/s), not in one entered from Tactile-turning.
TEST(XplorerMappingRules, LogicChecksTheContactNowAfterExplorationOnly) {
  for (const std::string previous : {"exploration", "tactile_turning"}) {
    XplorerMapLogic logic(contact_now_params());
    tactile_msgs::msg::FsmState st;
    st.state = "tactile_traversal";
    st.previous_state = previous;
    logic.on_fsm_state(st);
    geometry_msgs::msg::WrenchStamped w;
    w.header.frame_id = "base_link";
    for (int i = 0; i < 50; ++i) {
      w.wrench.force.x = i < 45 ? -2.0 : -0.1;  // average 1.81 N, latest 5: 0.1 N
      logic.on_wrench_body(w);
    }
    tick_at_origin(logic, 0.0);
    EXPECT_EQ(logic.mapper().stats().slabs, previous == "exploration" ? 0u : 1u) << previous;
  }
}

// README "Corner fill": a corner of a pentagon (C_n turned by 72 deg) at (1, 0).
// Face a: the surface y = 0 (object at +y, C_n = +y, lambda = +x), slabs' near
// faces at x = 0 ... 0.7 (0.3 m short of the corner: the release and the pivot
// orbit); face b: from the corner along (cos 72, sin 72) deg, slabs from 0.3 to
// 0.8 m. The lines meet at the corner (1, 0); the triangle (1, 0), (0.7, 0),
// 0.3 (cos 72, sin 72) from the corner is filled. Without the fill the nearest
// map point is the end of face a's last slab, 0.175 m from the corner.
TEST(XplorerMappingRules, CornerFillBetweenTwoFacesJoinedByATurn) {
  auto run = [](double fill_gap, double turn_deg, double start_b) {
    XplorerMapParams p = rule_params();
    p.corner_fill_max_gap = fill_gap;
    Stamper rig(p);
    for (int k = 0; k <= 14; ++k) rig.at(Eigen::Vector2d(0.05 * k, 0.0), Eigen::Vector2d(0.0, 1.0));
    rig.mapper.end_face(true);  // Tactile-turning
    const double a = turn_deg * M_PI / 180.0;
    const Eigen::Vector2d cb(-std::sin(a), std::cos(a)), tb(std::cos(a), std::sin(a));
    for (int k = 0; k <= 10; ++k) rig.at(Eigen::Vector2d(1.0, 0.0) + (start_b + 0.05 * k) * tb, cb);
    rig.mapper.end_face(false);  // the loop closed
    double nearest = 1e9;
    for (const auto& q : rig.map.cloud()) nearest = std::min(nearest, std::hypot(q.x - 1.0, q.y - 0.0));
    return std::make_tuple(nearest, rig.mapper.stats().corner_fills, rig.mapper.stats().skipped_corner_fill);
  };
  const auto [with, fills, skipped] = run(0.4, 72.0, 0.3);
  EXPECT_LT(with, 1e-4);
  EXPECT_EQ(fills, 1u);
  EXPECT_EQ(skipped, 0u);
  const auto [without, fills0, skipped0] = run(0.0, 72.0, 0.3);
  EXPECT_NEAR(without, 0.175, 1e-3);
  EXPECT_EQ(fills0, 0u);
  EXPECT_GT(std::get<0>(run(0.4, 72.0, 0.5)), 0.17);  // face b starts 0.5 m past the corner: gap > 0.4 m
  EXPECT_EQ(std::get<2>(run(0.4, 72.0, 0.5)), 1u);
  EXPECT_EQ(std::get<2>(run(0.4, 10.0, 0.3)), 1u);   // turned by 10 deg < corner_fill_min_turn
  XplorerMapParams bad;
  bad.corner_fill_max_gap = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.corner_fill_min_turn = 3.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.corner_fill_fit_length = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The node logic ends a face when the FSM leaves Tactile-traversal: the corner
// is filled across a Tactile-turning, not across a contact lost (Exploration).
TEST(XplorerMappingRules, LogicFillsTheCornerAcrossATurnOnly) {
  for (const std::string between : {"tactile_turning", "exploration"}) {
    auto d = XplorerMapLogic::default_parameters();
    d.set("corner_release_s", 0.0);
    d.set("min_state_time_s", 0.0);
    d.set("publish_rate_hz", 0.0);
    d.set("min_force_now", 0.0);
    d.set("edge_from_arms", false);
    d.set("corner_fill_max_gap", 0.4);  // off by default (README "Corner fill")
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    traverse_one_face(logic);  // along -y, C_n = +x: the surface x = 0.21
    tactile_msgs::msg::FsmState st;  // entered at 2.6 s (the release drops nothing: corner_release_s 0)
    st.state = between;
    tactile_common::to_stamp(tactile_common::from_seconds(2.6), st.header.stamp);
    logic.on_fsm_state(st);
    st.state = "tactile_traversal";
    tactile_common::to_stamp(tactile_common::from_seconds(2.9), st.header.stamp);
    logic.on_fsm_state(st);
    // Round the corner (0.21, -0.6): C_n = +y (yaw 90 deg), the surface y = -0.6, moving along +x.
    geometry_msgs::msg::WrenchStamped w;
    w.header.frame_id = "base_link";
    w.wrench.force.x = -1.6;
    logic.on_wrench_body(w);
    for (int k = 0; k <= 10; ++k) {
      const int64_t ns = tactile_common::from_seconds(3.0 + 0.125 * k);
      nav_msgs::msg::Odometry o;
      tactile_common::to_stamp(ns, o.header.stamp);
      o.child_frame_id = "base_link";
      o.pose.pose.position.x = 0.3 + 0.02 * k;
      o.pose.pose.position.y = -0.81;
      o.pose.pose.position.z = 0.7;
      o.pose.pose.orientation.z = std::sqrt(0.5);
      o.pose.pose.orientation.w = std::sqrt(0.5);
      logic.on_odometry(o);
      logic.on_timer(ns);
    }
    st.state = "done";
    tactile_common::to_stamp(tactile_common::from_seconds(4.5), st.header.stamp);
    logic.on_fsm_state(st);
    EXPECT_EQ(logic.mapper().stats().corner_fills, between == "tactile_turning" ? 1u : 0u)
        << between << " slabs " << logic.mapper().stats().slabs << " skipped " << logic.mapper().stats().skipped_corner_fill;
  }
}

// README "Recent axis": 0.3 s after a 72 deg turn the 50-sample average still
// reads the face just left (-2.0 N along b1: C_n = +b1) while the latest
// samples press along b2 (the new face, C_n = +b2): no slab; once the latest
// samples agree with the average's axis, a slab.
TEST(XplorerMappingRules, SlabsOnlyWhileTheLatestSamplesPressAlongTheAveragesAxis) {
  for (const bool on : {true, false}) {
    XplorerMapParams p;
    p.corner_release_s = 0.0;
    p.recent_axis = on;
    PointMap map;
    XplorerContactMapper m(p, map);
    ContactSample s = sample(0.0, 0.0, -2.0);
    s.force_body_recent = Eigen::Vector2d(-0.3, -1.4);
    EXPECT_EQ(m.update(s), on ? 0 : 1);
    EXPECT_EQ(m.stats().skipped_recent_axis, on ? 1u : 0u);
    s = sample(0.1, 0.0, -2.0);
    s.force_body_recent = Eigen::Vector2d(-1.3, 0.2);
    EXPECT_EQ(m.update(s), 1);
  }
}

// README "Recent axis": a traversal entered from Tactile-turning stamps after
// min_state_time_after_turn_s (0.3 s), one entered from Exploration after
// min_state_time_s (1 s): 0.4 s after the entry, a slab only after the turn.
// Without the recent-axis check (recent_axis false, or no latest samples: force_now_samples
// 0) the shorter gate would stamp the average of the face before the turn: the 1 s applies.
TEST(XplorerMappingRules, LogicGatesATraversalAfterATurnForTheShorterTime) {
  struct Case {
    std::string previous;
    bool recent_axis;
    int64_t force_now_samples;
    uint64_t slabs;
  };
  for (const Case& c : {Case{"tactile_turning", true, 10, 1}, Case{"exploration", true, 10, 0},
                        Case{"tactile_turning", false, 10, 0}, Case{"tactile_turning", true, 0, 0}}) {
    const std::string& previous = c.previous;
    auto d = XplorerMapLogic::default_parameters();
    d.set("publish_rate_hz", 0.0);
    d.set("recent_axis", c.recent_axis);
    d.set("force_now_samples", c.force_now_samples);
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    enter_traversal_and_press(logic, previous, 0.4);
    EXPECT_EQ(logic.mapper().stats().slabs, c.slabs)
        << previous << " recent_axis " << c.recent_axis << " force_now_samples " << c.force_now_samples;
  }
}

// README "Steady first contact": after an impact the vehicle backs off the
// face (x 0.79 -> 0.71 m, C_n = +b1 along the world x, the 1 s average still
// pressing) and comes back to traverse it along -y. The face is at x = 1.0 m
// (0.21 m ahead of x = 0.79). With the rule, the three slabs of the rebound
// (near faces at 1.00, 0.96, 0.92 m: each off the held line by 0.04 m) are
// dropped and the map starts at the face; without it, it reaches to 0.92 m.
// A traversal that ends while its slabs are still held leaves nothing.
TEST(XplorerMappingRules, SteadyFirstContactDropsTheRebound) {
  for (const bool on : {true, false}) {
    XplorerMapParams p;
    p.corner_release_s = 0.0;
    p.steady_distance = on ? 0.1 : 0.0;
    PointMap map;
    XplorerContactMapper m(p, map);
    m.begin_steady_hold();
    auto at = [](double t, double x, double y) {
      ContactSample s = sample(t, x, -2.0);
      s.arm_angles.reset();  // the fixed 0.21 m slab offset
      s.position.y() = y;
      return s;
    };
    const double rebound[3] = {0.79, 0.75, 0.71};
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.update(at(0.1 * k, rebound[k], 0.0)), 1);
    for (int k = 0; k < 8; ++k) m.update(at(0.3 + 0.1 * k, 0.79, -0.02 * k));
    EXPECT_EQ(m.stats().slabs, 11u);
    EXPECT_EQ(m.held(), 0u);
    EXPECT_EQ(m.stats().dropped_unsteady, on ? 3u : 0u);
    double min_x = 1e9;
    for (const auto& q : map.cloud()) min_x = std::min(min_x, static_cast<double>(q.x));
    EXPECT_NEAR(min_x, on ? 1.0 : 0.92, 1e-3) << on;
  }
  XplorerMapParams p;
  p.corner_release_s = 0.0;
  p.steady_distance = 0.1;
  PointMap map;
  XplorerContactMapper m(p, map);
  m.begin_steady_hold();
  ContactSample s = sample(0.0, 0.79, -2.0);
  EXPECT_EQ(m.update(s), 1);
  EXPECT_EQ(m.held(), 1u);
  m.end_face(false);  // back to Exploration before a steady stretch
  EXPECT_EQ(m.held(), 0u);
  EXPECT_EQ(map.size(), 0u);
  EXPECT_EQ(m.stats().dropped_unsteady, 1u);
}

// The node logic holds only a traversal entered from Exploration (contact_now_after).
TEST(XplorerMappingRules, LogicHoldsATraversalAfterExplorationOnly) {
  for (const std::string previous : {"exploration", "tactile_turning"}) {
    auto d = XplorerMapLogic::default_parameters();
    d.set("publish_rate_hz", 0.0);
    d.set("min_state_time_s", 0.0);
    d.set("min_state_time_after_turn_s", 0.0);
    d.set("steady_distance", 0.1);
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    enter_traversal_and_press(logic, previous, 0.1);
    EXPECT_EQ(logic.mapper().stats().slabs, 1u) << previous;
    EXPECT_EQ(logic.mapper().held(), previous == "exploration" ? 1u : 0u) << previous;
  }
}

// README "Re-contact after a contact-lost turn": tactile_fsm turns about a face's end
// when the contact is lost (REASON_XPLORER_CONTACT_LOST_TURN); the traversal after that
// turn re-contacts the object from off its face, an impact like the one after Exploration.
// With impact_turn_reasons = ["contact_lost_turn"] (default) it gets the first-contact rules
// listed in impact_turn_rules: contact now (the average 1.81 N, the latest samples 0.1 N: no
// slab), the steady hold and the 1 s state gate; after a corner turn (yaw_rate_peak) none of
// them; with impact_turn_reasons empty the contact-lost turn is a corner turn. The reason
// text is whatever tactile_fsm writes today; the mapper reads the code only (next test).
TEST(XplorerMappingRules, LogicTreatsTheReContactAfterAContactLostTurnAsAnImpact) {
  using tactile_msgs::msg::FsmState;
  const uint8_t lost = FsmState::REASON_XPLORER_CONTACT_LOST_TURN, peak = FsmState::REASON_XPLORER_YAW_RATE_PEAK;
  const std::vector<std::string> all = {"contact_now", "steady", "gate"};
  struct Case {
    uint8_t code;                      // FsmState.reason_code of the turn
    std::vector<std::string> reasons;  // impact_turn_reasons
    std::vector<std::string> rules;    // impact_turn_rules
    bool now, gate, steady;            // which rules apply
  };
  for (const Case& c : {Case{lost, {"contact_lost_turn"}, all, true, true, true},
                        Case{peak, {"contact_lost_turn"}, all, false, false, false},
                        Case{lost, {}, all, false, false, false},
                        Case{peak, {"yaw_rate_peak"}, all, true, true, true},
                        Case{lost, {"contact_lost_turn"}, {"contact_now", "steady"}, true, false, true},
                        Case{lost, {"contact_lost_turn"}, {"gate"}, false, true, false}}) {
    std::string what = "code " + std::to_string(c.code) + " reasons " + std::to_string(c.reasons.size()) + " rules";
    for (const auto& r : c.rules) what += " " + r;
    auto make = [&](bool no_gate) {
      auto d = XplorerMapLogic::default_parameters();
      d.set("publish_rate_hz", 0.0);
      d.set("corner_release_s", 0.0);
      if (no_gate) {
        d.set("min_state_time_s", 0.0);
        d.set("min_state_time_after_turn_s", 0.0);
      }
      d.set("impact_turn_reasons", c.reasons);
      d.set("impact_turn_rules", c.rules);
      return XplorerMapLogic::params_from(d);
    };
    auto turn_then_traverse = [&](XplorerMapLogic& logic) {
      tactile_msgs::msg::FsmState st;
      st.state = "tactile_turning";
      st.previous_state = "tactile_traversal";
      st.reason = c.code == lost ? "contact lost: turn about the corner" : "yaw rate peak";
      st.reason_code = c.code;
      logic.on_fsm_state(st);
      st.state = "tactile_traversal";
      st.previous_state = "tactile_turning";
      st.reason = "re-contact +X";
      st.reason_code = FsmState::REASON_XPLORER_RE_CONTACT;
      logic.on_fsm_state(st);
    };
    auto press = [](XplorerMapLogic& logic, double t, int n_strong, int n) {
      geometry_msgs::msg::WrenchStamped w;
      w.header.frame_id = "base_link";
      for (int i = 0; i < n; ++i) {
        w.wrench.force.x = i < n_strong ? -2.0 : -0.1;
        logic.on_wrench_body(w);
      }
      tick_at_origin(logic, t);
    };
    {  // contact now: the average 1.81 N, the latest 10 samples 0.1 N
      XplorerMapLogic logic(make(true));
      turn_then_traverse(logic);
      press(logic, 0.0, 40, 50);
      EXPECT_EQ(logic.mapper().stats().slabs, c.now ? 0u : 1u) << what;
    }
    {  // a firm press 0.4 s into the traversal: the 1 s gate after an impact, 0.3 s after a corner turn
      XplorerMapLogic logic(make(false));
      turn_then_traverse(logic);
      press(logic, 0.4, 50, 50);
      EXPECT_EQ(logic.mapper().stats().slabs, c.gate ? 0u : 1u) << what;
    }
    {  // no gate: the slab is held until steady after an impact, in the map at once otherwise
      XplorerMapLogic logic(make(true));
      turn_then_traverse(logic);
      press(logic, 0.1, 50, 50);
      EXPECT_EQ(logic.mapper().stats().slabs, 1u) << what;
      EXPECT_EQ(logic.mapper().held(), c.steady ? 1u : 0u) << what;
    }
  }
  auto d = XplorerMapLogic::default_parameters();
  d.set("impact_turn_rules", std::vector<std::string>{"contact_now", "bogus"});
  try {
    XplorerMapLogic::params_from(d);
    ADD_FAILURE() << "an unknown rule must be rejected";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("impact_turn_rules"), std::string::npos) << e.what();
  }
  // A reason text (the rule before reason codes) or a state's code is no reason of a turn.
  for (const std::string bad : {"contact lost", "contact_lost", ""}) {
    d = XplorerMapLogic::default_parameters();
    d.set("impact_turn_reasons", std::vector<std::string>{bad});
    try {
      XplorerMapLogic::params_from(d);
      ADD_FAILURE() << "impact_turn_reasons \"" << bad << "\" must be rejected";
    } catch (const std::exception& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("impact_turn_reasons"), std::string::npos) << what;
      EXPECT_NE(what.find("\"contact_lost_turn\""), std::string::npos) << what;  // names what it takes
    }
  }
}

// The mapper keys on FsmState.reason_code, never on the human-readable reason: the same
// flight with every reason reworded (or swapped between the two kinds of turn) maps the
// same, slab for slab; a different code with the same text does not.
TEST(XplorerMappingRules, RewordingTheReasonTextChangesNothing) {
  using tactile_msgs::msg::FsmState;
  const uint8_t lost = FsmState::REASON_XPLORER_CONTACT_LOST_TURN, peak = FsmState::REASON_XPLORER_YAW_RATE_PEAK;
  // Slabs stamped (and held) after a turn with this code and text, pressing with a firm
  // average whose latest samples are light (contact now refuses it after an impact turn).
  auto fly = [&](uint8_t code, const std::string& text) {
    auto d = XplorerMapLogic::default_parameters();
    d.set("publish_rate_hz", 0.0);
    d.set("corner_release_s", 0.0);
    d.set("min_state_time_s", 0.0);
    d.set("min_state_time_after_turn_s", 0.0);
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    FsmState st;
    st.state = "tactile_turning";
    st.previous_state = "tactile_traversal";
    st.reason = text;
    st.reason_code = code;
    logic.on_fsm_state(st);
    st.state = "tactile_traversal";
    st.previous_state = "tactile_turning";
    st.reason = text + " (re-contact)";
    st.reason_code = FsmState::REASON_XPLORER_RE_CONTACT;
    logic.on_fsm_state(st);
    geometry_msgs::msg::WrenchStamped w;
    w.header.frame_id = "base_link";
    for (int i = 0; i < 50; ++i) {
      w.wrench.force.x = i < 40 ? -2.0 : -0.1;
      logic.on_wrench_body(w);
    }
    tick_at_origin(logic, 0.0);
    return std::make_pair(logic.mapper().stats().slabs, logic.mapper().stats().skipped_no_contact_now);
  };
  const auto impact = fly(lost, "contact lost: turn about the corner");
  const auto corner = fly(peak, "yaw rate peak");
  EXPECT_EQ(impact, std::make_pair(uint64_t{0}, uint64_t{1}));  // contact now refused the slab
  EXPECT_EQ(corner, std::make_pair(uint64_t{1}, uint64_t{0}));
  for (const std::string text : {"", "face ended: pivot round its end", "contact lost", "yaw rate peak"}) {
    EXPECT_EQ(fly(lost, text), impact) << text;
    EXPECT_EQ(fly(peak, text), corner) << text;
  }
}

// README "Touching-guard half": with the yaw off the face after an oblique (re-)contact one
// front guard touches and the slab half on the other guard's side stands out of the face.
// Contact ahead (+x); arm 1 (+45 deg, the left guard, +y) deflected 0.10 rad, arm 0 (-45
// deg, right) 0.01 rad (< 0.3 x 0.10): only the left half, y in [0, 0.125] m, is stamped;
// square (-0.056 / +0.069, 2045 on a face) the whole slab, y in [-0.125, 0.125] m; with
// the ratio 0 (off) or later than touching_half_s into the state the whole slab too.
TEST(XplorerMappingRules, OnlyTheTouchingGuardsHalfAfterAnObliqueContact) {
  auto y_range = [](double ratio, std::array<double, 4> arms, std::optional<double> in_state) {
    XplorerMapParams p;
    p.corner_release_s = 0.0;
    p.touching_half_ratio = ratio;
    p.touching_half_s = 5.0;
    PointMap map;
    XplorerContactMapper m(p, map);
    ContactSample s = sample(0.0, 0.0, -2.0, arms);
    s.time_in_state = in_state;
    EXPECT_EQ(m.update(s), 1);
    double lo = 1e9, hi = -1e9;
    for (const auto& q : map.cloud()) {
      lo = std::min(lo, static_cast<double>(q.y));
      hi = std::max(hi, static_cast<double>(q.y));
    }
    return std::make_tuple(lo, hi, m.stats().touching_half);
  };
  const std::array<double, 4> left{-0.01, 0.10, 0.0, 0.0}, right{-0.10, 0.01, 0.0, 0.0}, square{-0.056, 0.069, 0.0, 0.0};
  auto [lo, hi, n] = y_range(0.3, left, 1.0);
  EXPECT_NEAR(lo, 0.0, 1e-3);
  EXPECT_NEAR(hi, 0.125, 1e-3);
  EXPECT_EQ(n, 1u);
  std::tie(lo, hi, n) = y_range(0.3, right, 1.0);
  EXPECT_NEAR(lo, -0.125, 1e-3);
  EXPECT_NEAR(hi, 0.0, 1e-3);
  EXPECT_EQ(n, 1u);
  for (const auto& [ratio, arms, in_state] :
       {std::make_tuple(0.3, square, std::optional<double>(1.0)), std::make_tuple(0.0, left, std::optional<double>(1.0)),
        std::make_tuple(0.3, left, std::optional<double>(6.0))}) {
    std::tie(lo, hi, n) = y_range(ratio, arms, in_state);
    EXPECT_NEAR(lo, -0.125, 1e-3);
    EXPECT_NEAR(hi, 0.125, 1e-3);
    EXPECT_EQ(n, 0u);
  }
  // Unknown time in the state (no FSM heard): the rule applies.
  std::tie(lo, hi, n) = y_range(0.3, left, std::nullopt);
  EXPECT_NEAR(lo, 0.0, 1e-3);
  EXPECT_EQ(n, 1u);
  XplorerMapParams bad;
  bad.touching_half_ratio = 1.5;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.touching_half_s = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad.touching_half_s = std::numeric_limits<double>::infinity();
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad.touching_half_s = 0.0;  // 0: the rule only at a state's first tick
  EXPECT_NO_THROW(bad.validate());
}

// The node logic dates the sample by the FSM state's entry: a traversal entered 6 s ago
// (time_in_state of the state message) stamps whole slabs although one guard touches.
TEST(XplorerMappingRules, LogicAppliesTheTouchingHalfEarlyInAStateOnly) {
  for (const double in_state : {0.0, 6.0}) {
    auto d = XplorerMapLogic::default_parameters();
    d.set("publish_rate_hz", 0.0);
    d.set("min_state_time_s", 0.0);
    d.set("min_state_time_after_turn_s", 0.0);
    d.set("corner_release_s", 0.0);
    d.set("touching_half_ratio", 0.3);
    d.set("touching_half_s", 5.0);
    XplorerMapLogic logic(XplorerMapLogic::params_from(d));
    tactile_msgs::msg::ArmImuArray a;
    tactile_common::to_stamp(tactile_common::from_seconds(10.0), a.header.stamp);
    for (int i = 0; i < 4; ++i) {
      tactile_msgs::msg::ArmImu arm;
      arm.arm_id = static_cast<uint8_t>(i);
      arm.arm_angle = i == 0 ? -0.01 : i == 1 ? 0.10 : 0.0;
      a.arms.push_back(arm);
    }
    logic.on_arm_imu(a);
    tactile_msgs::msg::FsmState st;
    st.state = "tactile_traversal";
    st.previous_state = "tactile_turning";
    st.time_in_state = in_state;
    tactile_common::to_stamp(tactile_common::from_seconds(10.0), st.header.stamp);
    logic.on_fsm_state(st);
    geometry_msgs::msg::WrenchStamped w;
    w.header.frame_id = "base_link";
    w.wrench.force.x = -1.6;
    logic.on_wrench_body(w);
    tick_at_origin(logic, 10.0);
    EXPECT_EQ(logic.mapper().stats().slabs, 1u) << in_state;
    EXPECT_EQ(logic.mapper().stats().touching_half, in_state > 5.0 ? 0u : 1u) << in_state;
  }
}

// Rule 12, face clip (README "Face clip"): face a (surface y = 0, C_n = +y, x 0-0.8 m)
// three of whose slabs (x 0.15-0.25 m) were stamped with the yaw 15 deg off the face (the slab
// turned with it sticks 3.2 cm out of the face), then a turn to face b at
// 90 deg (x = 1, C_n = -x). Once both faces are lines meeting at a right angle,
// the points outside face a are removed, and a later tilted slab is clipped as
// it enters. At a 72 deg corner (a polygon) nothing is clipped.
TEST(XplorerMappingRules, FaceClipRemovesTiltedSlabsOutsideAFaceOfARightAngledObject) {
  auto run = [](double min_length, double turn_deg) {
    XplorerMapParams p = rule_params();
    p.face_clip_min_length = min_length;
    p.face_clip_tilted = false;  // rule 12 alone (rule 15 removes the tilted slabs outside a line at any angle)
    Stamper rig(p);
    const double tilt = 15.0 * M_PI / 180.0;
    for (int k = 0; k <= 16; ++k) rig.at(Eigen::Vector2d(0.05 * k, 0.0), Eigen::Vector2d(0.0, 1.0), k >= 3 && k < 6 ? tilt : 0.0);
    rig.mapper.end_face(true);  // Tactile-turning
    const double a = turn_deg * M_PI / 180.0;
    const Eigen::Vector2d cb(-std::sin(a), std::cos(a)), tb(std::cos(a), std::sin(a));
    for (int k = 0; k <= 10; ++k) rig.at(Eigen::Vector2d(1.0, 0.0) + (0.3 + 0.05 * k) * tb, cb, 0.0);
    rig.mapper.end_face(true);
    const double before_late = [&] {
      double y = 1e9;
      for (const auto& q : rig.map.cloud()) y = std::min<double>(y, q.y);
      return y;
    }();
    rig.at(Eigen::Vector2d(0.4, 0.0), Eigen::Vector2d(0.0, 1.0), tilt);  // a later tilted slab on face a
    double y_min = 1e9;
    for (const auto& q : rig.map.cloud()) y_min = std::min<double>(y_min, q.y);
    return std::make_tuple(before_late, y_min, rig.mapper.stats().face_lines, rig.mapper.face_lines().size() >= 2 && rig.mapper.face_lines()[0].clips);
  };
  // 0.125 m x sin 15 deg + 0.08 m x (1 - cos 15 deg) ~ 0.035 m out of the face without the rule.
  const auto [off_before, off_after, off_lines, off_clips] = run(0.0, 90.0);
  EXPECT_LT(off_before, -0.03);
  EXPECT_LT(off_after, -0.03);
  EXPECT_EQ(off_lines, 0u);
  const auto [on_before, on_after, on_lines, on_clips] = run(0.2, 90.0);
  EXPECT_GE(on_before, -0.0101);  // face_clip_tolerance 0.01 m
  EXPECT_GE(on_after, -0.0101);
  EXPECT_EQ(on_lines, 2u);
  EXPECT_TRUE(on_clips);
  const auto [poly_before, poly_after, poly_lines, poly_clips] = run(0.2, 72.0);  // not a right angle
  EXPECT_LT(poly_before, -0.03);
  EXPECT_EQ(poly_lines, 2u);
  EXPECT_FALSE(poly_clips);
  EXPECT_LT(std::get<0>(run(0.6, 90.0)), -0.03);  // faces shorter than face_clip_min_length: no line
  XplorerMapParams bad;
  bad.face_clip_min_length = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.face_clip_max_residual = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.face_clip_tolerance = -0.01;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.face_clip_margin = std::nan("");
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = XplorerMapParams{};
  bad.face_clip_angle_tolerance = 4.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// README "Face clip to the corner" (rule 13). A square object {0 < x < 1, 0 < y < 1}
// traversed right-hand from a first contact next to its corner (1, 0): the first
// traversal (5 slabs tilted 15 deg, no line) sticks ~3.5 cm out of face A (y = 0) at
// x = 0.7-0.9; face B (x = 1) starts with three tilted slabs at y = 0.05-0.15 before its
// steady part (y >= 0.35: the fitted span, + 0.15 m margin reaches y = 0.2 only); faces
// C and D are clean; the last traversal maps face A over x = 0.3-0.6 and closes the
// loop there. Without the rule the tilted slabs next to the corners stay (their points
// lie beyond the spans + margin); with it the spans of two lines at a right angle reach
// their corner, and at the closure face A joins face B (the face after the first turn).
TEST(XplorerMappingRules, FaceClipReachesTheCornersAndJoinsTheLastFaceAtTheClosure) {
  auto run = [](double reach, bool close) {
    XplorerMapParams p = rule_params();
    p.face_clip_corner_reach = reach;
    p.face_clip_tilted = false;  // rule 13 alone (rule 15 would remove the tilted slabs too)
    Stamper rig(p);
    const double tilt = 15.0 * M_PI / 180.0;
    const Eigen::Vector2d ca(0.0, 1.0), cb(-1.0, 0.0), cc(0.0, -1.0), cd(1.0, 0.0);
    for (int k = 0; k < 5; ++k) rig.at({0.7 + 0.05 * k, 0.0}, ca, tilt);  // first contact, face A
    rig.mapper.end_face(true);
    for (int k = 0; k < 3; ++k) rig.at({1.0, 0.05 + 0.05 * k}, cb, tilt);  // face B, re-contact
    for (int k = 0; k <= 10; ++k) rig.at({1.0, 0.35 + 0.05 * k}, cb, 0.0);
    rig.mapper.end_face(true);
    for (int k = 0; k < 3; ++k) rig.at({0.95 - 0.05 * k, 1.0}, cc, tilt);  // face C, re-contact
    for (int k = 0; k <= 10; ++k) rig.at({0.6 - 0.05 * k, 1.0}, cc, 0.0);
    rig.mapper.end_face(true);
    for (int k = 0; k <= 10; ++k) rig.at({0.0, 0.8 - 0.05 * k}, cd, 0.0);  // face D
    rig.mapper.end_face(true);
    for (int k = 0; k <= 10; ++k) rig.at({0.1 + 0.05 * k, 0.0}, ca, 0.0);  // face A again: the loop closes at x = 0.6
    rig.mapper.end_face(false, close);
    double out_b = -1e9, out_a = 1e9, out_c = -1e9;  // outside B (x > 1), A (y < 0) past the closure, C (y > 1)
    for (const auto& q : rig.map.cloud()) {
      if (q.y > 0.0 && q.y < 0.35) out_b = std::max<double>(out_b, q.x - 1.0);
      if (q.x > 0.8 && q.x < 1.0) out_a = std::min<double>(out_a, q.y);
      if (q.x > 0.75 && q.x < 1.0) out_c = std::max<double>(out_c, q.y - 1.0);
    }
    return std::make_tuple(out_b, out_a, out_c);
  };
  const auto [off_b, off_a, off_c] = run(0.0, true);
  EXPECT_GT(off_b, 0.02);  // 0.125 m x sin 15 deg ~ 0.03 m out
  EXPECT_LT(off_a, -0.02);
  EXPECT_GT(off_c, 0.02);
  const auto [on_b, on_a, on_c] = run(0.6, true);
  EXPECT_LE(on_b, 0.0101);  // face_clip_tolerance 0.01 m
  EXPECT_GE(on_a, -0.0101);
  EXPECT_LE(on_c, 0.0101);  // C joined to B (consecutive faces): C's span reaches their corner (1, 1)
  const auto [open_b, open_a, open_c] = run(0.6, false);  // no closure: B's start and A are not joined
  EXPECT_GT(open_b, 0.02);
  EXPECT_LT(open_a, -0.02);
  EXPECT_LE(open_c, 0.0101);
  const auto [near_b, near_a, near_c] = run(0.1, true);  // the corners lie 0.3-0.4 m beyond the spans
  EXPECT_GT(near_b, 0.02);
  EXPECT_LT(near_a, -0.02);
  EXPECT_GT(near_c, 0.02);
  XplorerMapParams bad;
  bad.face_clip_corner_reach = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// README "Hold through a traversal" (rule 14): the contact back-off of tactile_fsm pulls
// the averaged force of a first contact under delta_map_hold for a moment, and the
// steady traversal then reads 1.3 N, under delta_map. Inside a traversal
// (hold_initiation, set by the node logic from stamp_states) an initiated mapping is
// kept; outside, or with hold_in_traversal false, the 0.5 N hold releases it.
TEST(XplorerMappingRules, InitiationHeldThroughATraversal) {
  for (const bool rule : {true, false}) {
    XplorerMapParams p;
    p.hold_in_traversal = rule;
    PointMap map;
    XplorerContactMapper m(p, map);
    m.hold_initiation(true);
    EXPECT_EQ(m.update(sample(0.0, 0.0, -2.6)), 1);  // the first contact's impact: initiated
    m.observe_force({-0.25, 0.0});                    // the back-off
    EXPECT_EQ(m.initiated(), rule);
    EXPECT_EQ(m.update(sample(0.5, 0.0, -1.3)), rule ? 1 : 0);  // the steady traversal
    m.hold_initiation(false);  // the traversal ended
    m.observe_force({-0.25, 0.0});
    EXPECT_FALSE(m.initiated());
  }
  // The node logic holds the initiation in the stamp states (Tactile-traversal) only.
  auto d = XplorerMapLogic::default_parameters();
  XplorerMapLogic logic(XplorerMapLogic::params_from(d));
  EXPECT_FALSE(logic.mapper().initiation_held());
  tactile_msgs::msg::FsmState st;
  for (const std::string state : {"exploration", "tactile_traversal", "tactile_turning", "tactile_traversal", "done"}) {
    st.state = state;
    logic.on_fsm_state(st);
    EXPECT_EQ(logic.mapper().initiation_held(), state == "tactile_traversal") << state;
  }
}

// README "Tilted slabs" (rule 15). Two faces of a hexagon-like polygon meeting at a
// 120 deg corner at (1, 0) (no right angle: rule 12 does not clip): face A along y = 0,
// then, after a turn, face B along (cos 60, sin 60) deg, re-contacted with the yaw 30 deg
// off its normal: its first three slabs (0.05-0.15 m from the corner) are tilted and
// stick out of B. With the rule, B's line removes their points outside it; B's steady
// slabs and A's slabs overhanging the corner (outside B's line, C_n of another face) stay.
TEST(XplorerMappingRules, TiltedSlabsOutsideTheirFacesLineAreRemovedAtAnyCorner) {
  auto run = [](bool rule) {
    XplorerMapParams p = rule_params();
    p.face_clip_tilted = rule;
    Stamper rig(p);
    for (int k = 0; k <= 18; ++k) rig.at({0.05 * k, 0.0}, {0.0, 1.0}, 0.0);  // face A up to x = 0.9
    rig.mapper.end_face(true);
    const double a = 60.0 * M_PI / 180.0;
    const Eigen::Vector2d tb(std::cos(a), std::sin(a)), cb(-std::sin(a), std::cos(a));
    for (int k = 0; k < 3; ++k) rig.at(Eigen::Vector2d(1.0, 0.0) + (0.05 + 0.05 * k) * tb, cb, -30.0 * M_PI / 180.0);
    for (int k = 0; k <= 10; ++k) rig.at(Eigen::Vector2d(1.0, 0.0) + (0.3 + 0.05 * k) * tb, cb, 0.0);
    rig.mapper.end_face(true);
    double out_b = -1e9;    // outside B, beside it (past the corner along B)
    std::size_t a_over = 0;  // A's last slab past the corner, outside B's line
    for (const auto& q : rig.map.cloud()) {
      const Eigen::Vector2d d = Eigen::Vector2d(q.x, q.y) - Eigen::Vector2d(1.0, 0.0);
      const double along = d.dot(tb), out = -d.dot(cb);
      if (along > 0.1 && along < 0.3) out_b = std::max(out_b, out);  // beyond A's overhang (along < 0.09)
      if (q.x > 1.005 && q.y > 0.0 && q.y < 0.08 && out > 0.0101) ++a_over;
    }
    return std::make_tuple(out_b, a_over, rig.mapper.face_lines().size() == 2 && !rig.mapper.face_lines()[0].clips);
  };
  const auto [off_out, off_over, off_lines] = run(false);
  EXPECT_GT(off_out, 0.03);  // 0.125 m x sin 30 deg ~ 0.06 m out of B
  EXPECT_TRUE(off_lines);
  const auto [on_out, on_over, on_lines] = run(true);
  EXPECT_LE(on_out, 0.0101);  // face_clip_tolerance
  EXPECT_TRUE(on_lines);      // no right angle: rule 12 does not clip
  EXPECT_GT(off_over, 0u);
  EXPECT_GT(on_over, 0u);  // A's overhang past the corner, outside B's line, is kept
  XplorerMapParams bad;
  bad.face_clip_tilted_reach = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// Rule 16 (README "Fan past a right-angled corner"): face A along y = 0 (object at y > 0,
// x < 1) is traversed up to x = 0.9; the vehicle then pivots a guard on the corner (1, 0)
// without a turn, the yaw following by 12-54 deg, and its slabs, turned with the yaw, fan
// past the corner, outside face B (x = 1). The turn comes later; B is traversed over 0.08 m
// only (5 slabs: no line, so rules 12, 13 and 15 do not clip there). With the rule, B's C_n
// at 90 deg to A's normal places B through its near-face points and the fan's points
// outside it go; A's steady slabs (their overhang of 0.025 m) stay. At a 60 deg turn
// (a polygon) nothing is clipped.
TEST(XplorerMappingRules, FanPastARightAngledCornerIsClippedAtTheNextFace) {
  auto run = [](bool rule, double turn_deg) {
    XplorerMapParams p = rule_params();
    p.corner_fan_clip = rule;
    Stamper rig(p);
    for (int k = 0; k <= 18; ++k) rig.at({0.05 * k, 0.0}, {0.0, 1.0}, 0.0);  // face A up to x = 0.9
    for (int k = 0; k < 8; ++k) rig.at({0.95, 0.0}, {0.0, 1.0}, (12.0 + 6.0 * k) * M_PI / 180.0);  // the fan
    rig.mapper.end_face(true);
    const double a = turn_deg * M_PI / 180.0;
    const Eigen::Vector2d tb(std::cos(a), std::sin(a)), cb(-std::sin(a), std::cos(a));  // B's direction, C_n
    for (int k = 0; k < 5; ++k) rig.at(Eigen::Vector2d(1.0, 0.0) + (0.12 + 0.02 * k) * tb, cb, 0.0);
    rig.mapper.end_face(true);
    double fan_out = -1e9;  // outside B beyond A's steady overhang
    std::size_t inside = 0;  // points inside the object
    for (const auto& q : rig.map.cloud()) {
      const Eigen::Vector2d d = Eigen::Vector2d(q.x, q.y) - Eigen::Vector2d(1.0, 0.0);
      if (d.x() > 0.03) fan_out = std::max(fan_out, -d.dot(cb));
      if (d.x() < -0.01 && q.y > 0.01) ++inside;
    }
    return std::make_tuple(fan_out, inside, rig.mapper.stats().fan_clips);
  };
  const auto [off_out, off_over, off_clips] = run(false, 90.0);
  EXPECT_GT(off_out, 0.04);  // 0.95 + 0.125 cos 12 deg: 0.07 m past the corner
  EXPECT_EQ(off_clips, 0u);
  const auto [on_out, on_over, on_clips] = run(true, 90.0);
  EXPECT_LE(on_out, 0.0101);  // face_clip_tolerance (nothing past 0.03 m at all: -1e9)
  EXPECT_EQ(on_clips, 1u);
  EXPECT_EQ(on_over, off_over);  // nothing inside the object is removed
  const auto [poly_out, poly_over, poly_clips] = run(true, 60.0);
  const auto [poly_off_out, poly_off_over, poly_off_clips] = run(false, 60.0);
  EXPECT_EQ(poly_clips, 0u);
  EXPECT_DOUBLE_EQ(poly_out, poly_off_out);
}


// Rule 16 the other way round: face A (nine steady slabs up to x = 0.9, then two slabs turned
// by 48 and 54 deg at x = 0.97) is no line (fewer than ten slabs on one), the next face B is
// one (x = 1, 12 slabs over 0.33 m). A's mean C_n (8.6 deg off its steady slabs') meets B's
// normal at 90 deg; A's side is then taken perpendicular to B's line through A's near-face
// points, and A's fan outside B's line goes.
TEST(XplorerMappingRules, FanClipWhenOnlyTheNextFaceIsALine) {
  auto run = [](bool rule) {
    XplorerMapParams p = rule_params();
    p.corner_fan_clip = rule;
    Stamper rig(p);
    for (int k = 0; k <= 8; ++k) rig.at({0.5 + 0.05 * k, 0.0}, {0.0, 1.0}, 0.0);
    for (int k = 0; k < 2; ++k) rig.at({0.97, 0.0}, {0.0, 1.0}, (48.0 + 6.0 * k) * M_PI / 180.0);
    rig.mapper.end_face(true);
    for (int k = 0; k < 12; ++k) rig.at({1.0, 0.06 + 0.03 * k}, {-1.0, 0.0}, 0.0);
    rig.mapper.end_face(true);
    double fan_out = -1e9;
    for (const auto& q : rig.map.cloud())
      if (q.x > 1.03) fan_out = std::max(fan_out, static_cast<double>(q.x) - 1.0);
    return std::make_tuple(fan_out, rig.mapper.face_lines().size(), rig.mapper.stats().fan_clips);
  };
  const auto [off_out, off_lines, off_clips] = run(false);
  EXPECT_GT(off_out, 0.04);
  EXPECT_EQ(off_lines, 1u);  // B only
  EXPECT_EQ(off_clips, 0u);
  const auto [on_out, on_lines, on_clips] = run(true);
  EXPECT_LE(on_out, 0.0101);
  EXPECT_EQ(on_lines, 1u);
  EXPECT_EQ(on_clips, 1u);
}

// Rule 16 at a concave corner: face A along y = 0 (object at y > 0) up to x = 0.9, then a
// clockwise turn onto a wall B at x = 1 whose object lies at x > 1, traversed towards -y
// (12 slabs: a line). The faces meet at 90 deg, but each lies on the other's free side; rule
// 16's clip, and rule 12's face clip of two joined lines, would take every point of A (all of
// it is at x < 1, "outside" B). Neither clips.
TEST(XplorerMappingRules, FanClipLeavesAConcaveCornerAlone) {
  auto run = [](bool rule) {
    XplorerMapParams p = rule_params();
    p.corner_fan_clip = rule;
    Stamper rig(p);
    for (int k = 0; k <= 18; ++k) rig.at({0.05 * k, 0.0}, {0.0, 1.0}, 0.0);  // face A, a line
    rig.mapper.end_face(true);
    for (int k = 0; k < 12; ++k) rig.at({1.0, -0.06 - 0.03 * k}, {1.0, 0.0}, 0.0);  // face B
    rig.mapper.end_face(true);
    std::size_t on_a = 0;
    for (const auto& q : rig.map.cloud())
      if (q.x < 0.85 && q.y > -0.01) ++on_a;
    EXPECT_EQ(rig.mapper.face_lines().size(), 2u);
    for (const auto& l : rig.mapper.face_lines()) EXPECT_FALSE(l.clips);  // rule 12 does not join them either
    return std::make_tuple(on_a, rig.mapper.stats().fan_clips, rig.mapper.stats().skipped_concave_fan_clips);
  };
  const auto [off_a, off_clips, off_skipped] = run(false);
  EXPECT_GT(off_a, 50u);
  EXPECT_EQ(off_clips, 0u);
  const auto [on_a, on_clips, on_skipped] = run(true);
  EXPECT_EQ(on_a, off_a);  // face A kept whole
  EXPECT_EQ(on_clips, 0u);
  EXPECT_EQ(on_skipped, 1u);
}
