// XPLORER behaviours (001 Sec. III-B, IV): eq. 8 against its closed-form
// solution, the state machine's transitions on scripted inputs, ricocheting
// and the post-collision model by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_fsm/xplorer_explorer.hpp"

using namespace tactile_fsm;

TEST(Admittance, StepResponseMatchesTheClosedForm) {
  AdmittanceController a;  // m_v = 1, D = K = 24.5 (001 Sec. V-A3)
  a.reset(XVec3::Zero(), 0.0);
  const double e = 1.0, dt = 1e-4, D = 24.5, K = 24.5;
  // x'' + D x' + K x = e, x(0) = x'(0) = 0: x = e/K (1 + (s2 e^{s1 t} - s1 e^{s2 t}) / (s1 - s2)).
  const double disc = std::sqrt(D * D - 4 * K), s1 = (-D + disc) / 2, s2 = (-D - disc) / 2;
  double t = 0.0;
  for (int k = 0; k < 100000; ++k) {
    a.update(XVec3(e, 0, 0), XVec3::Zero(), XVec3::Zero(), 0.0, 0.0, 0.0, dt);
    t += dt;
    if (k % 5000 == 4999) {
      const double x = e / K * (1 + (s2 * std::exp(s1 * t) - s1 * std::exp(s2 * t)) / (s1 - s2));
      ASSERT_NEAR(a.position().x(), x, 2e-4) << "t = " << t;
    }
  }
  EXPECT_NEAR(a.position().x(), e / K, 1e-3);  // 1 N error -> 4.1 cm
  EXPECT_NEAR(a.position().y(), 0.0, 1e-12);
}

TEST(Admittance, ForceErrorSetsTheOffsetZPassesThroughYawYields) {
  AdmittanceController a;
  a.reset(XVec3(1, 2, 0.7), 0.3);
  for (int k = 0; k < 20000; ++k)
    a.update(XVec3(-0.5, 0.2, 5.0), XVec3(-1.25, 0, 0), XVec3(1, 2, 0.9), 0.05, 0.0, 0.3, 1e-3);
  EXPECT_NEAR(a.position().x(), 1.0 + 0.75 / 24.5, 1e-4);  // (f - f_des) / K
  EXPECT_NEAR(a.position().y(), 2.0 + 0.2 / 24.5, 1e-4);
  EXPECT_DOUBLE_EQ(a.position().z(), 0.9);                 // D_zz = K_zz = 0: r_d,z = r*_z
  EXPECT_NEAR(a.yaw(), 0.3 + 0.05 / 1.0, 1e-3);            // tau / K_yaw
}

TEST(Directions, PostCollisionModel) {
  // 1.5 m/s into a wall with normal -x (out of the wall), 0.3 m/s along it, e = 0.2:
  // normal -> -0.3 m/s, tangential kept.
  const XVec2 v = post_collision_velocity(XVec2(1.5, 0.3), XVec2(-1, 0), 0.2);
  EXPECT_NEAR(v.x(), -0.3, 1e-12);
  EXPECT_NEAR(v.y(), 0.3, 1e-12);
}

namespace {
XplorerInput input(double t, XVec3 p, double yaw, XVec3 f, double rate = 0.0) {
  XplorerInput in;
  in.t = t;
  in.position = p;
  in.yaw = yaw;
  in.force = f;
  in.yaw_rate = rate;
  return in;
}

/// Takes off at `takeoff` (t = 0, no force), then presses with force `f` at
/// `p` for 60 ticks of 0.02 s (into Tactile-traversal or the static wrench);
/// returns the time of the last tick.
double take_off_and_press(XplorerExplorer& x, const XVec3& takeoff, const XVec3& p, const XVec3& f) {
  double t = 0;
  x.update(input(t, takeoff, 0.0, XVec3::Zero()), 0.02);
  for (int i = 0; i < 60; ++i) x.update(input(t += 0.02, p, 0.0, f), 0.02);
  return t;
}
}  // namespace

TEST(XplorerExplorer, TakeoffExplorationContactTraversalTurningAndReContact) {
  XplorerExplorer x{XplorerParams{}};
  const double dt = 0.02;
  double t = 0.0;
  XplorerOutput o = x.update(input(t, XVec3(0, 0, 0), 0.0, XVec3::Zero()), dt);
  EXPECT_EQ(o.state, XplorerState::kTakeoff);
  EXPECT_DOUBLE_EQ(o.position.z(), 0.7);
  o = x.update(input(t += dt, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), dt);
  EXPECT_EQ(o.state, XplorerState::kExploration);
  o = x.update(input(t += dt, XVec3(0.1, 0, 0.7), 0.0, XVec3::Zero()), dt);
  EXPECT_NEAR(o.position.x(), 0.1 + 0.3 / 1.5, 1e-12);  // lead = speed / position gain, along body +x
  // A 2 N push back (obstacle ahead): with the three force-free samples of the
  // take-off and exploration already in the average, 2k / (k + 3) > 1.5 at k = 10.
  int k = 0;
  while (x.state() == XplorerState::kExploration && k < 100) {
    x.update(input(t += dt, XVec3(0.79, 0, 0.7), 0.0, XVec3(-2, 0, 0)), dt);
    ++k;
  }
  EXPECT_EQ(k, 10);
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  EXPECT_EQ(x.contact(), BodyDirection::kPlusX);
  EXPECT_EQ(x.move(), BodyDirection::kMinusY);
  // Traversal pressing with exactly 1.25 N: moves along -y, no normal offset.
  for (int i = 0; i < 100; ++i) o = x.update(input(t += dt, XVec3(0.79, 0, 0.7), 0.0, XVec3(-1.25, 0, 0)), dt);
  EXPECT_NEAR(o.position.x(), 0.79, 1e-3);
  EXPECT_LT(o.position.y(), -0.05);
  // A yaw-rate peak (release at a corner) -> Tactile-turning, same direction, 0.26 rad/s.
  for (int i = 0; i < 10 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += dt, XVec3(0.79, -1.0, 0.7), 0.0, XVec3(-0.5, 0, 0), 1.0), dt);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  const double t_turn = t;
  for (int i = 0; i < 50; ++i) o = x.update(input(t += dt, XVec3(0.79, -1.0, 0.7), 0.0, XVec3::Zero()), dt);
  EXPECT_NEAR(o.yaw, 0.26 * (t - t_turn), 0.03);
  // Re-contact above delta_psi0 = 1.6 N along world +y at yaw 90 deg: body -x force... obstacle at body +x.
  for (int i = 0; i < 200 && x.state() == XplorerState::kTactileTurning; ++i)
    x.update(input(t += dt, XVec3(1.0, -1.2, 0.7), M_PI / 2, XVec3(0, -2.5, 0)), dt);
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  EXPECT_EQ(x.contact(), BodyDirection::kPlusX);
  EXPECT_EQ(x.turns(), 1u);
}

// Traversal round a cylinder (vehicle path radius 0.38 m, yaw facing the
// centre so C_n = body +x points at it, force exactly delta_f_des): the
// force error is zero, so r* should stay at the vehicle along C_n. With
// reshape_follows_contact the setpoint's offset along C_n stays ~0 after a
// quarter turn; with a fixed world r* the stale point projects onto the
// turned C_n as rho (1 - cos 90 deg) = 0.38 m, clamped at reshape_limit 0.3 m,
// and the setpoint is driven into the surface.
TEST(XplorerExplorer, ReshapedSetpointFollowsATurningContactDirection) {
  for (bool follow : {true, false}) {
    XplorerParams p;
    p.reshape_follows_contact = follow;
    XplorerExplorer x{p};
    const double dt = 0.02, rho = 0.38;
    const XVec2 c(1.0, 0.0);
    double t = 0.0;
    auto at = [&](double phi) { return XVec3(c.x() + rho * std::cos(phi), c.y() + rho * std::sin(phi), 0.7); };
    x.update(input(t, XVec3(0.62, 0, 0), 0.0, XVec3::Zero()), dt);
    x.update(input(t += dt, at(M_PI), 0.0, XVec3::Zero()), dt);
    for (int k = 0; k < 20 && x.state() != XplorerState::kTactileTraversal; ++k)
      x.update(input(t += dt, at(M_PI), 0.0, XVec3(-2, 0, 0)), dt);
    ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
    XplorerOutput o;
    XVec3 pos;
    XVec2 n;
    const double omega = 0.15 / rho;  // traverse speed round the path
    for (double phi = M_PI; phi < 1.5 * M_PI; phi += omega * dt) {
      pos = at(phi);
      const double yaw = phi - M_PI;  // facing the centre
      n = XVec2(std::cos(yaw), std::sin(yaw));
      o = x.update(input(t += dt, pos, yaw, XVec3(-1.25 * n.x(), -1.25 * n.y(), 0.0), omega), dt);
      ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
    }
    const double offset_n = (o.position - pos).head<2>().dot(n);
    if (follow) {
      EXPECT_NEAR(offset_n, 0.0, 0.02);
    } else {
      EXPECT_GT(offset_n, 0.2);
    }
  }
}

TEST(XplorerExplorer, TurnIsLimitedTo180Degrees) {
  XplorerExplorer x{XplorerParams{}};
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-2, 0, 0));
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  XplorerOutput o;
  for (int i = 0; i < 100 && x.state() != XplorerState::kTactileTurning; ++i)
    o = x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3(-1, 0, 0), 2.0), 0.02);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  for (int i = 0; i < 700; ++i) o = x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  EXPECT_NEAR(std::abs(o.yaw), M_PI, 1e-9);  // pi limit (13 s > pi / 0.26 = 12.1 s)
}

// Right-hand traversal (C_n = +x, lambda = -y: the object on the left of the motion)
// goes round a convex object counter-clockwise, so every convex corner turns the yaw
// up. With max_clockwise_turns_in_a_row = 1 a clockwise yaw-rate peak (-2 rad/s) turns
// clockwise once; after the re-contact a second clockwise peak is ignored (counted once
// per peak) and the traversal goes on; a counter-clockwise turn re-arms it. With 0 no
// clockwise peak turns; with 5 both turn.
namespace {
/// One yaw-rate peak of 1 s (after 1.2 s of steady traversal at 1.3 N), then, if it
/// turned, 2 s of turning and a re-contact at 2.5 N along body +x. Returns the sign of
/// the yaw setpoint at the end of the turn (0: no turn).
int peak(XplorerExplorer& x, double& t, double rate) {
  for (int i = 0; i < 60; ++i) x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3(-1.3, 0, 0)), 0.02);
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  for (int i = 0; i < 50 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3(-1.3, 0, 0), rate), 0.02);
  if (x.state() == XplorerState::kTactileTraversal) return 0;
  XplorerOutput o;
  for (int i = 0; i < 100; ++i) o = x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  const int sign = o.yaw > 0.2 ? 1 : (o.yaw < -0.2 ? -1 : 99);
  for (int i = 0; i < 100 && x.state() == XplorerState::kTactileTurning; ++i)
    x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3(-2.5, 0, 0)), 0.02);
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  return sign;
}
}  // namespace

TEST(XplorerExplorer, SecondClockwiseTurnInARowIsNoConvexCorner) {
  {
    XplorerExplorer x{XplorerParams{}};
    double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-2, 0, 0));
    EXPECT_EQ(peak(x, t, -2.0), -1);  // the first clockwise peak turns clockwise
    EXPECT_EQ(peak(x, t, -2.0), 0);   // the second is ignored
    EXPECT_EQ(x.turns_against(), 1u);
    EXPECT_EQ(peak(x, t, -2.0), 0);   // and the next, as a peak of its own
    EXPECT_EQ(x.turns_against(), 2u);
    EXPECT_EQ(peak(x, t, 2.0), 1);    // counter-clockwise turns
    EXPECT_EQ(peak(x, t, -2.0), -1);  // and re-arms one clockwise turn
    EXPECT_EQ(x.turns(), 3u);
  }
  {
    XplorerParams p;
    p.max_clockwise_turns_in_a_row = 0;
    XplorerExplorer x{p};
    double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-2, 0, 0));
    EXPECT_EQ(peak(x, t, -2.0), 0);
    EXPECT_EQ(peak(x, t, 2.0), 1);
  }
  {
    XplorerParams p;
    p.max_clockwise_turns_in_a_row = 5;
    XplorerExplorer x{p};
    double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-2, 0, 0));
    EXPECT_EQ(peak(x, t, -2.0), -1);
    EXPECT_EQ(peak(x, t, -2.0), -1);
    EXPECT_EQ(x.turns_against(), 0u);
  }
}

// Contact lost (averaged force < 0.3 N for 1 s) after a traversal of >= 4 s: the face
// ended without a yaw-rate peak, so Tactile-turning counter-clockwise about its end; the
// pivot is on the face as it was when the force went (vehicle at (0, -0.5), yaw 0: C_n
// +x, 0.21 m ahead), abreast of the vehicle along lambda. A contact lost 2 s into a
// traversal (it never settled) and turn_on_contact_lost = false go back to Exploration.
TEST(XplorerExplorer, ContactLostAfterALongTraversalTurnsAboutTheFacesEnd) {
  for (const double traverse_s : {5.0, 2.0}) {
    for (const bool turn : {true, false}) {
      XplorerParams p;
      p.turn_on_contact_lost = turn;
      XplorerExplorer x{p};
      double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-2, 0, 0));
      ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
      const double t0 = t;
      while (t < t0 + traverse_s - 1.0)
        x.update(input(t += 0.02, XVec3(0, -0.5, 0.7), 0.0, XVec3(-1.3, 0, 0)), 0.02);
      for (int i = 0; i < 150 && x.state() == XplorerState::kTactileTraversal; ++i)
        x.update(input(t += 0.02, XVec3(0, -0.5, 0.7), 0.0, XVec3::Zero()), 0.02);
      if (turn && traverse_s > 4.0) {
        ASSERT_EQ(x.state(), XplorerState::kTactileTurning) << x.reason();
        // mapping_pcl's rule 10 (impact_turn_reasons: ["contact_lost_turn"]) tells this turn
        // from a corner turn by its reason code (FsmState.reason_code).
        EXPECT_EQ(x.reason_code(), XplorerReason::kContactLostTurn) << x.reason();
        EXPECT_EQ(x.turns(), 1u);
        EXPECT_NEAR(x.pivot().x(), 0.21, 1e-9);
        EXPECT_NEAR(x.pivot().y(), -0.5, 1e-9);
        XplorerOutput o;
        for (int i = 0; i < 50; ++i) o = x.update(input(t += 0.02, XVec3(0, -0.5, 0.7), 0.0, XVec3::Zero()), 0.02);
        EXPECT_NEAR(o.yaw, 0.26 * 1.0, 0.03);  // counter-clockwise at turn_rate
      } else {
        EXPECT_EQ(x.state(), XplorerState::kExploration) << traverse_s << " s, turn " << turn;
        EXPECT_EQ(x.turns(), 0u);
      }
    }
  }
}

// Convex corner with turn_pivot (default): the face is the one of 0.6 s
// before the trigger (yaw 0, C_n = +x, lambda = -y), the pivot on it abreast
// of the vehicle, phi starts at the 0.2 rad the vehicle has already turned;
// after tau: phi = 0.2 + 0.26 tau, radius 0.15 + 0.2 exp(-tau / 1.5), slide
// min(0.2, 0.15 tau), setpoint = pivot + R(phi) (slide lambda - radius C_n).
TEST(XplorerExplorer, ConvexCornerTurnOrbitsThePivot) {
  XplorerExplorer x{XplorerParams{}};
  const double dt = 0.02;
  double t = take_off_and_press(x, XVec3(0.79, 0, 0.7), XVec3(0.79, 0, 0.7), XVec3(-2, 0, 0));
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  double y = 0;
  for (int i = 0; i < 100; ++i) x.update(input(t += dt, XVec3(0.79, y -= 0.002, 0.7), 0.0, XVec3(-1.25, 0, 0)), dt);
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += dt, XVec3(0.80, -0.5, 0.7), 0.2, XVec3(-1.0, 0, 0), 1.0), dt);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  EXPECT_EQ(x.reason_code(), XplorerReason::kYawRatePeak) << x.reason();  // a corner turn (mapping_pcl rule 10)
  EXPECT_NEAR(x.pivot().x(), 0.79 + 0.21, 1e-12);  // on the face (x = 0.79 + contact_reach)
  EXPECT_NEAR(x.pivot().y(), -0.5, 1e-12);         // abreast of the vehicle along lambda
  const double t_turn = t;
  XplorerOutput o;
  for (int i = 0; i < 50; ++i) o = x.update(input(t += dt, XVec3(0.8, -0.5, 0.7), 0.3, XVec3::Zero()), dt);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  const double tau = t - t_turn, phi = 0.2 + 0.26 * tau, r = 0.15 + 0.2 * std::exp(-tau / 1.5);
  const double slide = std::min(0.2, 0.15 * tau);
  // R(phi) (slide (0, -1) - r (1, 0)) by hand:
  const double ox = -r * std::cos(phi) + slide * std::sin(phi), oy = -r * std::sin(phi) - slide * std::cos(phi);
  EXPECT_NEAR(o.position.x(), 1.0 + ox, 1e-9);
  EXPECT_NEAR(o.position.y(), -0.5 + oy, 1e-9);
  EXPECT_NEAR(o.yaw, phi, 1e-9);
  // Without re-contact the orbit stops at the 180 deg limit (0.2 + 0.26 x 11.4 s > pi).
  for (int i = 0; i < 520; ++i) o = x.update(input(t += dt, XVec3(0.8, -0.5, 0.7), 0.3, XVec3::Zero()), dt);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  EXPECT_NEAR(o.yaw, M_PI, 1e-9);
  EXPECT_NEAR(o.position.x(), 1.0 + 0.15 + 0.2 * std::exp(-(t - t_turn) / 1.5), 1e-9);  // R(pi): +radius along x
  EXPECT_NEAR(o.position.y(), -0.5 + 0.2, 1e-9);                                       // and slide along -lambda
}

TEST(XplorerExplorer, StaticWrenchHoldsWhenTheForceMatchesTheReference) {
  XplorerParams p;
  p.mission = XplorerMission::kStaticWrench;
  XplorerExplorer x(p);
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0.79, 0, 0.7), XVec3(-2, 0, 0));
  ASSERT_EQ(x.state(), XplorerState::kStaticWrench);
  // delta_f = delta_f_ref = [-1 0 0]: r* no longer reshaped, the setpoint settles.
  XplorerOutput o, o1;
  for (int i = 0; i < 400; ++i) {
    o = x.update(input(t += 0.02, XVec3(0.79, 0, 0.7), 0.0, XVec3(-1.0, 0, 0)), 0.02);
    if (i == 349) o1 = o;
  }
  EXPECT_NEAR(o.position.x(), o1.position.x(), 1e-3);
  EXPECT_NEAR(o.position.y(), 0.0, 1e-9);
  // Too weak (0.5 N): r* moves into the wall at reshape_gain x 0.5 N = 5 cm/s.
  const double x0 = o.position.x();
  double prev = x0;
  for (int i = 0; i < 100; ++i) {
    o = x.update(input(t += 0.02, XVec3(0.79, 0, 0.7), 0.0, XVec3(-0.5, 0, 0)), 0.02);
    EXPECT_GE(o.position.x(), prev - 1e-12);
    prev = o.position.x();
  }
  EXPECT_GT(o.position.x() - x0, 0.05);
  EXPECT_LT(o.position.x() - x0, 0.1 + 0.5 / 24.5 + 0.01);  // at most the r* ramp plus the eq. 8 offset
}

TEST(XplorerExplorer, RicochetCollidesRecoversAndRegulatesAtTheGoal) {
  XplorerParams p;
  p.mission = XplorerMission::kRicochet;
  p.goal = XVec2(2.0, 0.0);
  XplorerExplorer x(p);
  double t = 0;
  x.update(input(t, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  XplorerOutput o = x.update(input(t += 0.02, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  EXPECT_EQ(o.state, XplorerState::kRicocheting);
  o = x.update(input(t += 0.02, XVec3(0.5, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  EXPECT_NEAR(o.position.x(), 0.5 + 1.5 / 1.5 + 1.0, 1e-12);  // carrot beyond the goal line
  // Collision peak 5 N pushing back: recovery setpoint 0.02 m/N x 5 N away from the wall.
  o = x.update(input(t += 0.02, XVec3(1.8, 0, 0.7), 0.0, XVec3(-5, 0, 0)), 0.02);
  EXPECT_EQ(x.collisions(), 1u);
  EXPECT_NEAR(o.position.x(), 1.8 - 0.1, 1e-12);
  for (int i = 0; i < 20; ++i) o = x.update(input(t += 0.02, XVec3(1.75, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  EXPECT_EQ(x.state(), XplorerState::kGoTo);
  EXPECT_NEAR(o.position.x(), 2.0, 1e-12);
}

namespace {
/// Takes off, presses at the origin facing +x (C_n = +x, lambda = -y), then goes round
/// a square of side 1 m counter-clockwise (right-hand: -y, +x, +y, -x; the object at
/// (0.5, -0.5) on the left) with the yaw `winding_per_side` x the perimeter position in
/// sides (pi / 2: a real circuit, C_n turning with the faces; 0: the same path without
/// turning the heading), pressing 1.3 N along body +x. Ends after `ticks` ticks or
/// when the traversal ends.
void go_round_square(XplorerExplorer& x, double winding_per_side, int ticks = 400) {
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-1.6, 0, 0));
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  for (int i = 1; i <= ticks && x.state() == XplorerState::kTactileTraversal; ++i) {
    const double s = 4.0 * i / 400.0;  // perimeter position
    XVec3 p(0, 0, 0.7);
    if (s < 1) p.y() = -s;
    else if (s < 2) p = XVec3(s - 1, -1, 0.7);
    else if (s < 3) p = XVec3(1, -1 + (s - 2), 0.7);
    else p = XVec3(1 - (s - 3), 0, 0.7);
    const double yaw = winding_per_side * std::min(s, 3.999);
    x.update(input(t += 0.02, p, yaw, XVec3(-1.3 * std::cos(yaw), -1.3 * std::sin(yaw), 0)), 0.02);
  }
}
}  // namespace

TEST(XplorerExplorer, LoopClosureEndsTheExploration) {
  XplorerExplorer x{XplorerParams{}};
  go_round_square(x, M_PI / 2);
  EXPECT_TRUE(x.loop_closed());
  EXPECT_EQ(x.state(), XplorerState::kDone);
  EXPECT_GT(x.traversed_path(), 3.5);
  // 90 deg counter-clockwise per side; the closure fires 0.25 m before the start point.
  EXPECT_NEAR(x.winding(), (4.0 - 0.25) * M_PI / 2, 0.05);
}

// Back at the first contact point after 4 m of path but with the heading not wound
// (the vehicle wobbling round one corner, issue 17 seed 2028): no closure with
// loop_min_winding = pi, a closure with 0 (the test off). Wound clockwise (-2 pi): none.
TEST(XplorerExplorer, LoopClosureNeedsTheHeadingWoundOnce) {
  {
    XplorerExplorer x{XplorerParams{}};
    go_round_square(x, 0.0);
    EXPECT_FALSE(x.loop_closed());
    EXPECT_NEAR(x.winding(), 0.0, 1e-9);
  }
  {
    XplorerExplorer x{XplorerParams{}};
    go_round_square(x, -M_PI / 2);
    EXPECT_FALSE(x.loop_closed());
    EXPECT_LT(x.winding(), -M_PI);
  }
  {
    XplorerParams p;
    p.loop_min_winding = 0.0;
    XplorerExplorer x{p};
    go_round_square(x, 0.0);
    EXPECT_TRUE(x.loop_closed());
  }
}

// A turn swinging past the first contact point does not close the loop (the
// last face would not be traversed): only Tactile-traversal there does.
TEST(XplorerExplorer, LoopDoesNotCloseWhileTurning) {
  XplorerExplorer x{XplorerParams{}};
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-1.6, 0, 0));
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  for (int i = 1; i <= 300; ++i) x.update(input(t += 0.02, XVec3(0, -3.0 * i / 300, 0.7), 0.0, XVec3(-1.3, 0, 0)), 0.02);
  ASSERT_GT(x.traversed_path(), 2.0);
  for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += 0.02, XVec3(0, -3.0, 0.7), 0.0, XVec3(-1.0, 0, 0), 1.0), 0.02);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  for (int i = 0; i < 10; ++i) x.update(input(t += 0.02, XVec3(0.05, 0.0, 0.7), 0.3, XVec3::Zero()), 0.02);
  EXPECT_FALSE(x.loop_closed());  // at the first contact point, but turning
  EXPECT_EQ(x.state(), XplorerState::kTactileTurning);
}

// loop_turn_min_winding (issue 17, 13020): a first contact next to a convex corner is
// passed again inside the turn at that corner. Round the square to 0.4 m short of the
// first contact point (heading wound by 3.6 x 90 deg = 5.65 rad), a yaw-rate peak starts
// the turn, the turn swings to 0.05 m of the point: closed with the closure allowed in a
// turn from 5.5 rad, not by default (0: off) nor from 2 pi; the early turn of
// LoopDoesNotCloseWhileTurning (wound 0.3 rad) does not close with 5.5 either.
namespace {
bool turn_past_first_contact_after_a_circuit(double loop_turn_min_winding) {
  XplorerParams p;
  p.loop_turn_min_winding = loop_turn_min_winding;
  XplorerExplorer x{p};
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-1.6, 0, 0));
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  double yaw = 0.0;
  XVec3 pos(0, 0, 0.7);
  for (int i = 1; i <= 360; ++i) {
    const double s = 4.0 * i / 400.0;
    if (s < 1) pos = XVec3(0, -s, 0.7);
    else if (s < 2) pos = XVec3(s - 1, -1, 0.7);
    else if (s < 3) pos = XVec3(1, -1 + (s - 2), 0.7);
    else pos = XVec3(1 - (s - 3), 0, 0.7);
    yaw = M_PI / 2 * s;
    x.update(input(t += 0.02, pos, yaw, XVec3(-1.3 * std::cos(yaw), -1.3 * std::sin(yaw), 0)), 0.02);
  }
  EXPECT_EQ(x.state(), XplorerState::kTactileTraversal);
  EXPECT_FALSE(x.loop_closed());
  for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += 0.02, pos, yaw, XVec3(-1.0 * std::cos(yaw), -1.0 * std::sin(yaw), 0), 1.0), 0.02);
  EXPECT_EQ(x.state(), XplorerState::kTactileTurning);
  for (int i = 0; i < 10 && !x.loop_closed(); ++i)
    x.update(input(t += 0.02, XVec3(0.05, 0.0, 0.7), yaw + 0.1, XVec3::Zero()), 0.02);
  EXPECT_GT(x.winding(), 5.5);
  EXPECT_LT(x.winding(), 2 * M_PI);
  if (x.loop_closed()) {
    EXPECT_EQ(x.state(), XplorerState::kDone);
  }
  return x.loop_closed();
}
}  // namespace

TEST(XplorerExplorer, LoopClosesInsideTheLastTurnWhenAllowed) {
  EXPECT_FALSE(turn_past_first_contact_after_a_circuit(0.0));
  EXPECT_FALSE(turn_past_first_contact_after_a_circuit(2 * M_PI));
  EXPECT_TRUE(turn_past_first_contact_after_a_circuit(5.5));
  XplorerParams p;
  p.loop_turn_min_winding = 5.5;
  XplorerExplorer x{p};
  double t = take_off_and_press(x, XVec3(0, 0, 0.7), XVec3(0, 0, 0.7), XVec3(-1.6, 0, 0));
  for (int i = 1; i <= 300; ++i) x.update(input(t += 0.02, XVec3(0, -3.0 * i / 300, 0.7), 0.0, XVec3(-1.3, 0, 0)), 0.02);
  for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
    x.update(input(t += 0.02, XVec3(0, -3.0, 0.7), 0.0, XVec3(-1.0, 0, 0), 1.0), 0.02);
  ASSERT_EQ(x.state(), XplorerState::kTactileTurning);
  for (int i = 0; i < 10; ++i) x.update(input(t += 0.02, XVec3(0.05, 0.0, 0.7), 0.3, XVec3::Zero()), 0.02);
  EXPECT_FALSE(x.loop_closed());
  XplorerParams bad;
  bad.loop_turn_min_winding = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// Every tick publishes a designed setpoint, the tick of a transition included (review,
// 2026-11-26: a branch that entered Tactile-traversal, -turning or the static wrench and
// broke returned the output's default, the world origin at z = 0 with yaw 0, for that
// tick). Far from the origin (the vehicle at x ~ 3, y ~ 2) and at yaw 1 rad, every
// setpoint must be finite, at hover height and within reach of the vehicle (the turn's
// orbit, at most turn_radius + turn_backoff + turn_slide from the pivot 0.21 m beyond the
// vehicle: < 0.6 m), on a transition tick the yaw within 0.5 rad of the vehicle's; and the tick that enters a state
// carries the state's own setpoint (the orbit's first point, the contact back-off's point).
namespace {
struct SetpointChecker {
  double max_xy = 0.0, max_yaw = 0.0;
  int ticks = 0, bad = 0;
  XplorerOutput step(XplorerExplorer& x, const XplorerInput& in) {
    const XplorerOutput o = x.update(in, 0.02);
    ++ticks;
    const double dxy = (o.position.head<2>() - in.position.head<2>()).norm();
    const double dyaw = std::abs(std::remainder(o.yaw - in.yaw, 2 * M_PI));
    // The turn's yaw setpoint runs ahead of a vehicle that does not follow (scripted
    // inputs), so the yaw is bounded on the transition ticks only.
    const bool ok = o.position.allFinite() && std::isfinite(o.yaw) && std::abs(o.position.z() - 0.7) < 1e-9 &&
                    dxy < 0.6 && (!o.transitioned || dyaw < 0.5);
    if (!ok) {
      ++bad;
      ADD_FAILURE() << "t = " << in.t << " state " << to_string(o.state) << (o.transitioned ? " (transition tick)" : "")
                    << ": setpoint (" << o.position.transpose() << ") yaw " << o.yaw << " for the vehicle at ("
                    << in.position.transpose() << ") yaw " << in.yaw;
    }
    max_xy = std::max(max_xy, dxy);
    max_yaw = std::max(max_yaw, dyaw);
    return o;
  }
};
XVec3 world(double yaw, double bx, double by) {  // a body-frame force in the world frame
  return XVec3(std::cos(yaw) * bx - std::sin(yaw) * by, std::sin(yaw) * bx + std::cos(yaw) * by, 0.0);
}
}  // namespace

TEST(XplorerExplorer, EveryTickPublishesADesignedSetpointTransitionsIncluded) {
  for (const double backoff_s : {0.0, 0.3}) {
    XplorerParams p;
    p.contact_backoff_time = backoff_s;
    p.contact_backoff_gain = 0.02;
    XplorerExplorer x{p};
    SetpointChecker c;
    const double yaw = 1.0;
    const XVec3 p0(3.0, 2.0, 0.7);
    double t = 0.0;
    c.step(x, input(t, XVec3(3.0, 2.0, 0.69), yaw, XVec3::Zero()));
    XplorerOutput o = c.step(x, input(t += 0.02, p0, yaw, XVec3::Zero()));
    ASSERT_EQ(o.state, XplorerState::kExploration);
    // First contact: 2 N against body +x -> Tactile-traversal.
    const XVec3 f_contact = world(yaw, -2.0, 0.0);
    while (x.state() == XplorerState::kExploration && t < 1.0) o = c.step(x, input(t += 0.02, p0, yaw, f_contact));
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
    ASSERT_TRUE(o.transitioned);
    if (backoff_s > 0.0) {
      // 0.02 m/N x 2 N = 4 cm along the force (out of the obstacle), yaw held.
      EXPECT_EQ(x.backoffs(), 1u);
      EXPECT_NEAR((o.position - (p0 + 0.04 * f_contact.normalized())).norm(), 0.0, 1e-9);
      EXPECT_NEAR(o.yaw, yaw, 1e-12);
    } else {
      EXPECT_EQ(x.backoffs(), 0u);
      EXPECT_NEAR((o.position - p0).norm(), 0.0, 1e-9);  // holds where the contact was
    }
    // Traversal for 5 s (the face along lambda = body -y), then a yaw-rate peak -> turning.
    XVec3 q = p0;
    for (int i = 0; i < 250; ++i) {
      q.head<2>() += 0.003 * world(yaw, 0, -1).head<2>();
      c.step(x, input(t += 0.02, q, yaw, world(yaw, -1.3, 0.0)));
    }
    ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
    for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
      o = c.step(x, input(t += 0.02, q, yaw + 0.1, world(yaw, -1.0, 0.0), 1.0));
    ASSERT_EQ(o.state, XplorerState::kTactileTurning);
    ASSERT_TRUE(o.transitioned);
    // The transition tick carries the orbit's first point: 0.35 m (turn_radius +
    // turn_backoff) from the pivot, the pivot 0.21 m out along C_n.
    EXPECT_NEAR((o.position.head<2>() - x.pivot()).norm(), 0.35, 1e-9);
    // Re-contact (2.5 N on body +x after 1 s) -> traversal.
    for (int i = 0; i < 200 && x.state() == XplorerState::kTactileTurning; ++i)
      o = c.step(x, input(t += 0.02, q, yaw + 0.2, world(yaw + 0.2, -2.5, 0.0)));
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
    // A long traversal, then the contact lost -> a counter-clockwise turn about the face's end.
    for (int i = 0; i < 250; ++i) c.step(x, input(t += 0.02, q, yaw + 0.2, world(yaw + 0.2, -1.3, 0.0)));
    for (int i = 0; i < 100 && x.state() == XplorerState::kTactileTraversal; ++i)
      o = c.step(x, input(t += 0.02, q, yaw + 0.2, XVec3::Zero()));
    ASSERT_EQ(o.state, XplorerState::kTactileTurning) << x.reason();
    ASSERT_TRUE(o.transitioned);
    // No re-contact: the turn ends in Exploration after its limit.
    for (int i = 0; i < 800 && x.state() == XplorerState::kTactileTurning; ++i)
      c.step(x, input(t += 0.02, q, yaw + 0.2, XVec3::Zero()));
    EXPECT_EQ(x.state(), XplorerState::kExploration);
    // Contact again from Exploration, lost after 2 s -> Exploration.
    for (int i = 0; i < 100 && x.state() == XplorerState::kExploration; ++i)
      c.step(x, input(t += 0.02, q, yaw + 0.2, world(yaw + 0.2, -2.0, 0.0)));
    ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
    for (int i = 0; i < 200 && x.state() == XplorerState::kTactileTraversal; ++i)
      c.step(x, input(t += 0.02, q, yaw + 0.2, XVec3::Zero()));
    EXPECT_EQ(x.state(), XplorerState::kExploration);
    EXPECT_EQ(c.bad, 0) << "of " << c.ticks << " ticks";
  }
  // The static wrench's contact tick.
  for (const double backoff_s : {0.0, 0.3}) {
    XplorerParams p;
    p.mission = XplorerMission::kStaticWrench;
    p.contact_backoff_time = backoff_s;
    XplorerExplorer x{p};
    SetpointChecker c;
    const XVec3 p0(-2.0, 4.0, 0.7);
    double t = 0.0;
    c.step(x, input(t, p0, -2.0, XVec3::Zero()));
    XplorerOutput o;
    for (int i = 0; i < 100 && x.state() != XplorerState::kStaticWrench; ++i)
      o = c.step(x, input(t += 0.02, p0, -2.0, world(-2.0, 0.0, 2.0)));
    ASSERT_EQ(o.state, XplorerState::kStaticWrench);
    ASSERT_TRUE(o.transitioned);
    for (int i = 0; i < 100; ++i) c.step(x, input(t += 0.02, p0, -2.0, world(-2.0, 0.0, 1.0)));
    EXPECT_EQ(c.bad, 0) << "of " << c.ticks << " ticks";
  }
}

// The contact back-off (001 Sec. III-B3 collision recovery at first contact): its setpoint
// is held for contact_backoff_time, capped at contact_backoff_max, and no turn, release or
// reshaping runs meanwhile; afterwards the traversal starts from where the vehicle is.
TEST(XplorerExplorer, ContactBackOffHoldsItsSetpointThenTraverses) {
  XplorerParams p;
  p.contact_backoff_time = 0.5;
  p.contact_backoff_gain = 0.02;
  p.contact_backoff_max = 0.05;
  XplorerExplorer x{p};
  double t = 0.0;
  x.update(input(t, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), 0.02);
  XplorerOutput o;
  for (int i = 0; i < 100 && x.state() != XplorerState::kTactileTraversal; ++i)
    o = x.update(input(t += 0.02, XVec3(0.79, 0, 0.7), 0.0, XVec3(-4.0, 0, 0)), 0.02);
  ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
  const double t0 = t;
  EXPECT_NEAR(o.position.x(), 0.79 - 0.05, 1e-12);  // 0.02 m/N x 4 N = 8 cm, capped at 5 cm
  EXPECT_NEAR(o.position.y(), 0.0, 1e-12);
  // During the back-off: a yaw-rate peak and a vanishing force change nothing.
  while (t < t0 + 0.48) {
    o = x.update(input(t += 0.02, XVec3(0.76, 0, 0.7), 0.0, XVec3::Zero(), 1.0), 0.02);
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
    EXPECT_NEAR(o.position.x(), 0.74, 1e-12);
    EXPECT_NEAR(o.yaw, 0.0, 1e-12);
  }
  // Afterwards the traversal's admittance from the vehicle's position (pressing at 1.25 N:
  // along lambda = -y, no offset along C_n).
  for (int i = 0; i < 100; ++i) o = x.update(input(t += 0.02, XVec3(0.76, 0, 0.7), 0.0, XVec3(-1.25, 0, 0)), 0.02);
  EXPECT_EQ(o.state, XplorerState::kTactileTraversal);
  EXPECT_NEAR(o.position.x(), 0.76, 1e-3);
  EXPECT_LT(o.position.y(), -0.05);
  EXPECT_EQ(x.turns(), 0u);
}

TEST(XplorerParams, ValidateNamesTheField) {
  XplorerParams p;
  p.delta_psi0 = 1.4;  // must exceed delta_0 = 1.5
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("XplorerParams.delta_psi0"), std::string::npos) << e.what();
  }
  p = XplorerParams{};
  p.turn_limit = 4.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.loop_min_winding = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.loop_min_winding = 7.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.max_clockwise_turns_in_a_row = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.max_clockwise_turns_in_a_row = 1001;  // the node's range [0, 1000] (xplorer_fsm_logic)
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.max_clockwise_turns_in_a_row = 1000;
  EXPECT_NO_THROW(p.validate());
  p = XplorerParams{};
  p.contact_lost_turn_min_s = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.contact_backoff_time = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.contact_backoff_max = 0.6;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.contact_backoff_gain = std::nan("");
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.admittance.damping[1] = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_THROW(mission_from_string("fly"), std::invalid_argument);
}

// Issue 17, class B (square_*): Exploration along +x slides along a face at -40 deg to the
// approach (the path deflected along the face's tangent t, the force out of the face with a
// friction part against the motion, both axes under delta_0 for 2 s), then the average
// crosses delta_0 on body x. Without the rule C_n is body +X (50 deg off the face's normal)
// and the traversal keeps the approach yaw; with it C_n is body +Y (the axis nearest to the
// normal, 40 deg off), lambda = +X, and the traversal first yaws clockwise at turn_rate to
// -40 deg, holding the contact along the normal with no lead along the face, no turn on a
// yaw-rate peak meanwhile; then it traverses along body +X = the face's tangent.
namespace {
struct SlideResult {
  XplorerExplorer x;
  double t;
  XVec3 p;
};
SlideResult slide_along_a_face(const XplorerParams& prm, double face_deg, bool slide) {
  SlideResult r{XplorerExplorer{prm}, 0.0, XVec3(0, 0, 0.7)};
  const double a = face_deg * M_PI / 180.0;
  const XVec2 t(std::cos(a), std::sin(a));
  const XVec2 n = a < 0 ? XVec2(-t.y(), t.x()) : XVec2(t.y(), -t.x());  // into the obstacle
  r.x.update(input(r.t, r.p, 0.0, XVec3::Zero()), 0.02);
  // 1 s of free Exploration along +x at 0.3 m/s.
  for (int i = 0; i < 50; ++i) {
    r.p.x() += 0.3 * 0.02;
    r.x.update(input(r.t += 0.02, r.p, 0.0, XVec3::Zero()), 0.02);
  }
  // Touching the face: 2 s at ~1.1 N per axis, then ~1.9 N until the average crosses delta_0.
  for (int i = 0; i < 400 && r.x.state() == XplorerState::kExploration; ++i) {
    const double fn = i < 100 ? 1.4 : 2.2;
    const XVec2 f = -fn * n - 0.3 * fn * (slide ? t : XVec2::Zero());
    if (slide) r.p.head<2>() += 0.25 * 0.02 * t;
    r.x.update(input(r.t += 0.02, r.p, 0.0, XVec3(f.x(), f.y(), 0.0)), 0.02);
  }
  return r;
}
}  // namespace

TEST(XplorerExplorer, FaceSlidAlongInExplorationIsSquaredUpTo) {
  const double target = -40.0 * M_PI / 180.0;
  {  // rule off (main's behaviour): C_n from the body axes, no squaring
    XplorerParams p;
    p.square_min_deflection = 0.0;
    SlideResult r = slide_along_a_face(p, -40.0, true);
    ASSERT_EQ(r.x.state(), XplorerState::kTactileTraversal);
    EXPECT_EQ(r.x.contact(), BodyDirection::kPlusX);
    EXPECT_EQ(r.x.move(), BodyDirection::kMinusY);
    EXPECT_EQ(r.x.squarings(), 0u);
  }
  XplorerParams p;
  p.square_min_deflection = 0.35;
  p.square_to_x = false;  // the nearest body axis first; square_to_x below
  SlideResult r = slide_along_a_face(p, -40.0, true);
  XplorerExplorer& x = r.x;
  ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
  EXPECT_EQ(x.contact(), BodyDirection::kPlusY);
  EXPECT_EQ(x.move(), BodyDirection::kPlusX);
  EXPECT_EQ(x.squarings(), 1u);
  EXPECT_NEAR(x.square_target_yaw(), target, 1e-6);
  EXPECT_EQ(x.reason().rfind("contact +Y (square up -40 deg)", 0), 0u) << x.reason();
  EXPECT_EQ(x.reason_code(), XplorerReason::kContactSquareUp);
  const double t0 = r.t + p.contact_backoff_time;  // the squaring starts after the back-off
  const XVec2 tf(std::cos(target), std::sin(target)), nf(-std::sin(target), std::cos(target));
  XplorerOutput o;
  double yaw = 0.0;
  // The yaw setpoint ramps at turn_rate; the vehicle follows it; a yaw-rate peak changes nothing.
  while (r.t < t0 + -target / p.turn_rate + p.square_hold - 0.05) {
    const XVec2 f = -1.25 * nf;
    o = x.update(input(r.t += 0.02, r.p, yaw, XVec3(f.x(), f.y(), 0.0), 1.0), 0.02);
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal) << r.t;
    ASSERT_TRUE(x.squaring() || r.t < t0) << r.t;
    if (r.t > t0 + 0.02) {
      EXPECT_NEAR(o.yaw, std::max(target, -p.turn_rate * (r.t - t0)), 0.021) << r.t;
      EXPECT_NEAR((o.position.head<2>() - r.p.head<2>()).dot(tf), 0.0, 1e-3) << r.t;  // no lead along the face
    }
    yaw = o.yaw;
  }
  EXPECT_EQ(x.turns(), 0u);
  EXPECT_NEAR(yaw, target, 1e-6);
  // Squared: the traversal of 001 along lambda = body +X, i.e. along the face.
  for (int i = 0; i < 100; ++i) {
    const XVec2 f = -1.25 * nf;
    o = x.update(input(r.t += 0.02, r.p, target, XVec3(f.x(), f.y(), 0.0)), 0.02);
    // No torque: the yaw setpoint stays on the squared heading (the yaw row restarts there).
    EXPECT_NEAR(o.yaw, target, 0.5 * M_PI / 180.0) << r.t;
  }
  EXPECT_FALSE(x.squaring());
  EXPECT_EQ(o.state, XplorerState::kTactileTraversal);
  EXPECT_GT((o.position.head<2>() - r.p.head<2>()).dot(tf), 0.05);
  EXPECT_NEAR((o.position.head<2>() - r.p.head<2>()).dot(nf), 0.0, 1e-3);
  EXPECT_EQ(x.turns(), 0u);
  // The mirrored face (+40 deg, the vehicle slides left): C_n = -Y, squared counter-clockwise.
  SlideResult m = slide_along_a_face(p, 40.0, true);
  EXPECT_EQ(m.x.contact(), BodyDirection::kMinusY);
  EXPECT_EQ(m.x.move(), BodyDirection::kMinusX);
  EXPECT_NEAR(m.x.square_target_yaw(), -target, 1e-6);
  // square_to_x: C_n is body +X (the frame of a square first contact), lambda = -Y, squared
  // counter-clockwise by 50 deg onto the face's normal.
  {
    XplorerParams px = p;
    px.square_to_x = true;
    SlideResult rx = slide_along_a_face(px, -40.0, true);
    EXPECT_EQ(rx.x.contact(), BodyDirection::kPlusX);
    EXPECT_EQ(rx.x.move(), BodyDirection::kMinusY);
    EXPECT_NEAR(rx.x.square_target_yaw(), 50.0 * M_PI / 180.0, 1e-6);
    EXPECT_EQ(rx.x.reason().rfind("contact +X (square up 50 deg)", 0), 0u) << rx.x.reason();
    EXPECT_EQ(rx.x.reason_code(), XplorerReason::kContactSquareUp);
  }
  // No slide (a square hit, or the vehicle stopped at the face): nothing changes.
  SlideResult s = slide_along_a_face(p, -40.0, false);
  EXPECT_EQ(s.x.squarings(), 0u);
  EXPECT_EQ(s.x.contact(), BodyDirection::kPlusY);  // 001's body axis of the larger force component
  EXPECT_FALSE(s.x.squaring());
  p.square_hold = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = XplorerParams{};
  p.square_min_deflection = 1.6;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// Entry actions: the tick that enters a state publishes that state's own first setpoint,
// written by its entry action (never the output's default, the world origin at z = 0), with
// the transition's reason code; the state's tick takes over on the next one. Each state is
// entered by the shortest input that gets the FSM there.
TEST(XplorerExplorer, EntryActionSetsTheFirstTickOfEachState) {
  const double dt = 0.02;
  auto expect_sp = [](const XplorerOutput& o, const XVec3& p, double yaw, const char* what) {
    EXPECT_TRUE(o.transitioned) << what;
    EXPECT_NEAR((o.position - p).norm(), 0.0, 1e-12) << what << ": " << o.position.transpose();
    EXPECT_NEAR(o.yaw, yaw, 1e-12) << what;
  };
  {  // takeoff -> Exploration (hover at the vehicle, yaw held), then the Exploration lead
    XplorerExplorer x{XplorerParams{}};
    double t = 0.0;
    x.update(input(t, XVec3(1, 2, 0.2), 0.5, XVec3::Zero()), dt);
    XplorerOutput o = x.update(input(t += dt, XVec3(1.01, 2.02, 0.69), 0.6, XVec3::Zero()), dt);
    ASSERT_EQ(o.state, XplorerState::kExploration);
    EXPECT_EQ(x.reason_code(), XplorerReason::kHoverHeightReached);
    expect_sp(o, XVec3(1.01, 2.02, 0.7), 0.6, "exploration entry");
    o = x.update(input(t += dt, XVec3(1.01, 2.02, 0.7), 0.6, XVec3::Zero()), dt);
    EXPECT_FALSE(o.transitioned);
    EXPECT_NEAR(o.position.x(), 1.01 + 0.2 * std::cos(0.6), 1e-12);  // explore_speed / position_gain along body +x
  }
  {  // Exploration -> Tactile-traversal: the contact back-off's setpoint (gain |f| along f, capped)
    XplorerParams p;
    p.contact_backoff_gain = 0.03;
    XplorerExplorer x{p};
    double t = 0.0;
    x.update(input(t, XVec3(0, 0, 0.7), 0.0, XVec3::Zero()), dt);
    XplorerOutput o;
    const XVec3 f(-3.0, 0.4, 0.0), at(0.5, 0.1, 0.72);
    for (int i = 0; i < 100 && x.state() != XplorerState::kTactileTraversal; ++i) o = x.update(input(t += dt, at, 0.0, f), dt);
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
    EXPECT_EQ(x.reason_code(), XplorerReason::kContact);
    EXPECT_EQ(x.contact(), BodyDirection::kPlusX);
    EXPECT_EQ(x.move(), BodyDirection::kMinusY);
    const XVec2 back = std::min(0.03 * f.head<2>().norm(), 0.15) * f.head<2>().normalized();
    expect_sp(o, XVec3(0.5 + back.x(), 0.1 + back.y(), 0.7), 0.0, "traversal entry (back-off)");
    EXPECT_TRUE(x.backing_off(t));
  }
  {  // Tactile-traversal -> Tactile-turning: the orbit's first point about the pivot
    XplorerExplorer x{XplorerParams{}};
    double t = take_off_and_press(x, XVec3(0.79, 0, 0.7), XVec3(0.79, 0, 0.7), XVec3(-2, 0, 0));
    ASSERT_EQ(x.state(), XplorerState::kTactileTraversal);
    for (int i = 0; i < 100; ++i) x.update(input(t += dt, XVec3(0.79, -0.002 * i, 0.7), 0.0, XVec3(-1.25, 0, 0)), dt);
    XplorerOutput o;
    for (int i = 0; i < 20 && x.state() == XplorerState::kTactileTraversal; ++i)
      o = x.update(input(t += dt, XVec3(0.80, -0.5, 0.7), 0.2, XVec3(-1.0, 0, 0), 1.0), dt);
    ASSERT_EQ(o.state, XplorerState::kTactileTurning);
    EXPECT_EQ(x.reason_code(), XplorerReason::kYawRatePeak);
    // phi0 = the 0.2 rad already turned, radius turn_radius + turn_backoff, no slide yet:
    // pivot + R(0.2) (-0.35, 0) with the face yaw 0.
    const XVec2 sp = x.pivot() + Eigen::Rotation2Dd(0.2) * XVec2(-0.35, 0.0);
    expect_sp(o, XVec3(sp.x(), sp.y(), 0.7), 0.2, "turning entry");
    // Tactile-turning -> Tactile-traversal on a re-contact: hover at the vehicle, yaw held.
    for (int i = 0; i < 200 && x.state() == XplorerState::kTactileTurning; ++i)
      o = x.update(input(t += dt, XVec3(1.0, -0.6, 0.71), 1.4, XVec3(-2.5 * std::cos(1.4), -2.5 * std::sin(1.4), 0)), dt);
    ASSERT_EQ(o.state, XplorerState::kTactileTraversal);
    EXPECT_EQ(x.reason_code(), XplorerReason::kReContact);
    expect_sp(o, XVec3(1.0, -0.6, 0.7), 1.4, "traversal entry (re-contact)");
  }
  {  // takeoff -> Ricocheting: the take-off's hover point once more (not the vehicle's position)
    XplorerParams p;
    p.mission = XplorerMission::kRicochet;
    p.goal = XVec2(2.0, 0.0);
    XplorerExplorer x{p};
    double t = 0.0;
    x.update(input(t, XVec3(0, 0, 0.3), 0.1, XVec3::Zero()), dt);
    XplorerOutput o = x.update(input(t += dt, XVec3(0.03, -0.02, 0.7), 0.2, XVec3::Zero()), dt);
    ASSERT_EQ(o.state, XplorerState::kRicocheting);
    expect_sp(o, XVec3(0, 0, 0.7), 0.1, "ricochet entry");
    // Ricocheting -> goto after the collision recovery: the goal.
    x.update(input(t += dt, XVec3(1.8, 0, 0.7), 0.2, XVec3(-5, 0, 0)), dt);
    for (int i = 0; i < 20 && x.state() == XplorerState::kRicocheting; ++i)
      o = x.update(input(t += dt, XVec3(1.75, 0, 0.7), 0.2, XVec3::Zero()), dt);
    ASSERT_EQ(o.state, XplorerState::kGoTo);
    EXPECT_EQ(x.reason_code(), XplorerReason::kCollisionRecovered);
    expect_sp(o, XVec3(2.0, 0.0, 0.7), 0.2, "goto entry");
  }
}

// Every transition carries its reason code, and the text is built from it (a reworded text
// is a change of reason_text() alone).
TEST(XplorerExplorer, ReasonCodesOfTheTransitionsOfAnExploration) {
  XplorerExplorer x{XplorerParams{}};
  EXPECT_EQ(x.reason_code(), XplorerReason::kNone);
  go_round_square(x, M_PI / 2);
  ASSERT_EQ(x.state(), XplorerState::kDone);
  EXPECT_EQ(x.reason_code(), XplorerReason::kLoopClosed);
  EXPECT_EQ(x.reason(), "loop closed");
  EXPECT_STREQ(to_string(XplorerReason::kContactLostTurn), "contact_lost_turn");
  EXPECT_STREQ(to_string(XplorerReason::kYawRatePeak), "yaw_rate_peak");
}

// Each state put directly into (for_test_enter), then its transitions alone, at their
// thresholds (issue 33): a newcomer changing one guard sees which test names it.
namespace {
constexpr double kTick = 0.02;  // 50 Hz
XplorerInput at(double t, double z = 0.7, double fx = 0.0, double fy = 0.0) {
  XplorerInput in;
  in.t = t;
  in.position = XVec3(0.0, 0.0, z);
  in.yaw = 0.0;
  in.force = XVec3(fx, fy, 0.0);
  return in;
}
}  // namespace

TEST(XplorerStates, TakeoffEndsWithinTakeoffToleranceOfTheHoverHeight) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kTakeoff, at(0.0, 0.0));
  fsm.update(at(kTick, p.hover_height - p.takeoff_tolerance - 0.001), kTick);
  EXPECT_EQ(fsm.state(), XplorerState::kTakeoff);
  fsm.update(at(2 * kTick, p.hover_height - p.takeoff_tolerance + 0.001), kTick);
  EXPECT_EQ(fsm.state(), XplorerState::kExploration);
  EXPECT_EQ(fsm.reason_code(), XplorerReason::kHoverHeightReached);
}

/// Steps the FSM at 50 Hz from t = 0 with a constant body force fx until it leaves `from`
/// (at most max_s); returns the time of the tick it left on (NaN: never).
double leaves_at(XplorerExplorer& fsm, XplorerState from, double fx, double max_s, double t0 = 0.0) {
  for (int k = 1; t0 + k * kTick <= max_s; ++k) {
    const double t = t0 + k * kTick;
    fsm.update(at(t, 0.7, fx), kTick);
    if (fsm.state() != from) return t;
  }
  return NAN;
}

TEST(XplorerStates, ExplorationEndsWhenTheAveragedForceExceedsDelta0) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kExploration, at(0.0));
  // The moving average full of free flight (one window of zero force), then a 2 N push
  // from ahead: the 50-sample average crosses delta_0 = 1.5 N at the 38th sample.
  const double window_s = p.force_average_samples * kTick;
  ASSERT_TRUE(std::isnan(leaves_at(fsm, XplorerState::kExploration, 0.0, window_s)));
  const double f = -2.0;
  const double left = leaves_at(fsm, XplorerState::kExploration, f, window_s + 4.0, window_s);
  const int expected = static_cast<int>(std::floor(p.delta_0 / std::abs(f) * p.force_average_samples)) + 1;
  EXPECT_NEAR(left - window_s, expected * kTick, 1e-9);
  EXPECT_EQ(fsm.state(), XplorerState::kTactileTraversal);
  EXPECT_EQ(fsm.contact(), BodyDirection::kPlusX);  // C_n: toward the face ahead
  EXPECT_TRUE(fsm.reason_code() == XplorerReason::kContact || fsm.reason_code() == XplorerReason::kContactSquareUp);
}

TEST(XplorerStates, TraversalEndsWhenTheForceStaysBelowReleaseForceForReleaseTime) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kTactileTraversal, at(0.0), BodyDirection::kPlusX);
  EXPECT_TRUE(fsm.backing_off(0.0));
  // No force: the release timer starts once the back-off has ended, and the contact is
  // lost release_time later (a short traversal: Exploration, not a turn about the end).
  const double left = leaves_at(fsm, XplorerState::kTactileTraversal, 0.0, 5.0);
  EXPECT_EQ(fsm.state(), XplorerState::kExploration);
  EXPECT_EQ(fsm.reason_code(), XplorerReason::kContactLost);
  // The first tick after the back-off starts the timer; the release fires release_time after it.
  EXPECT_NEAR(left, p.contact_backoff_time + p.release_time + kTick, kTick + 1e-9);
}

TEST(XplorerStates, TurningEndsOnAReContactAboveDeltaPsi0AfterSettleTime) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kTactileTurning, at(0.0), BodyDirection::kPlusX);
  ASSERT_EQ(fsm.state(), XplorerState::kTactileTurning);
  // A push well above delta_psi0 from the start: no re-contact within settle_time, then
  // on the first tick past it.
  const double left = leaves_at(fsm, XplorerState::kTactileTurning, -2.0 * p.delta_psi0, 5.0);
  EXPECT_GT(left, p.settle_time);
  EXPECT_LE(left - kTick, p.settle_time + 1e-9);
  EXPECT_EQ(fsm.state(), XplorerState::kTactileTraversal);
  EXPECT_EQ(fsm.reason_code(), XplorerReason::kReContact);
}

TEST(XplorerStates, TurningWithoutAReContactEndsAtTheTurnLimit) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kTactileTurning, at(0.0), BodyDirection::kPlusX);
  const double limit_s = p.turn_limit / p.turn_rate + 3.0;
  const double left = leaves_at(fsm, XplorerState::kTactileTurning, 0.0, limit_s + 1.0);
  EXPECT_GT(left, limit_s);
  EXPECT_LE(left - kTick, limit_s + 1e-9);
  EXPECT_EQ(fsm.state(), XplorerState::kExploration);
  EXPECT_EQ(fsm.reason_code(), XplorerReason::kTurnLimit);
}

// The named guards alone, at their edges.
TEST(XplorerGuards, EachAtItsEdge) {
  const XplorerParams p;
  XplorerExplorer fsm(p);
  fsm.for_test_enter(XplorerState::kTactileTurning, at(0.0), BodyDirection::kPlusX);
  EXPECT_TRUE(fsm.at_hover_height(at(0.0, p.hover_height + p.takeoff_tolerance - 1e-6)));
  EXPECT_FALSE(fsm.at_hover_height(at(0.0, p.hover_height + p.takeoff_tolerance)));
  const double limit_s = p.turn_limit / p.turn_rate + 3.0;
  EXPECT_FALSE(fsm.turn_limit_passed(limit_s));
  EXPECT_TRUE(fsm.turn_limit_passed(limit_s + 1e-6));
  // No force averaged yet: no contact, no re-contact, no release timer running.
  EXPECT_EQ(fsm.contact_detected(), BodyDirection::kNone);
  EXPECT_FALSE(fsm.re_contact(10.0));
  EXPECT_FALSE(fsm.released(10.0));
  EXPECT_FALSE(fsm.yaw_rate_peak(10.0));
  EXPECT_FALSE(fsm.recovered(10.0));  // no collision
  // A push of 2 delta_psi0 fills the average (within settle_time: still turning).
  for (int k = 1; k <= p.force_average_samples; ++k) fsm.update(at(k * kTick, 0.7, -2.0 * p.delta_psi0), kTick);
  ASSERT_EQ(fsm.state(), XplorerState::kTactileTurning);
  EXPECT_FALSE(fsm.re_contact(p.settle_time));
  EXPECT_TRUE(fsm.re_contact(p.settle_time + 1e-6));
  EXPECT_EQ(fsm.contact_detected(), BodyDirection::kPlusX);
}
