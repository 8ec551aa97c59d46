// XPLORER (001): hover thrust and normalised command, compliant arm statics
// and step response (001 eq. 2), contact -> deflection, arm IMUs, collisions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "tactile_sim/xplorer.hpp"

using namespace tactile_sim;

namespace {

constexpr double kDt = 0.001;

RigidBodyState at(double x, double y, double z) {
  RigidBodyState s;
  s.position = Vec3(x, y, z);
  return s;
}

PositionSetpoint sp_at(double x, double y, double z, double yaw = 0.0) {
  PositionSetpoint sp;
  sp.position = Vec3(x, y, z);
  sp.yaw = yaw;
  return sp;
}

void run(Xplorer& v, const Arena& a, double seconds) {
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int k = 0; k < n; ++k) v.step(kDt, a);
}

// Wall along y at x = xw, normal -x (vehicle at x < xw).
Arena wall_x(double xw) {
  Arena a;
  const int id = a.add_obstacle("wall");
  a.add_wall(Vec2(xw, -5.0), Vec2(xw, 5.0), 0, id);
  return a;
}

/// Fly at 0.1 m/s (setpoint ramp with velocity feed-forward) from x = 0 to a
/// setpoint at x = 0.35 m and hold it, 6 s in all (the wall_x(0.5) press).
void press_into_wall(Xplorer& v, const Arena& arena) {
  for (int k = 0; k < 6000; ++k) {
    const double x = std::min(0.1 * k * kDt, 0.35);
    PositionSetpoint sp = sp_at(x, 0, 0.7);
    if (x < 0.35) sp.velocity_ff = Vec3(0.1, 0, 0);
    v.set_setpoint(sp);
    v.step(kDt, arena);
  }
}

}  // namespace

TEST(Xplorer, HoverThrustEqualsWeightAndNormalisedCommand) {
  Xplorer v(XplorerParams{}, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  run(v, empty, 4.0);
  const double W = 1.12 * 9.81;
  EXPECT_NEAR(v.collective_thrust(), W, 0.001 * W);
  EXPECT_NEAR(v.thrust_command(), W / 32.5, 0.001 * W / 32.5);  // 001 V-A3: 0.338
  EXPECT_NEAR(v.state().position.z(), 0.7, 0.005);
  EXPECT_NEAR(v.specific_force_body().z(), 9.81, 0.01);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(v.arm_angles()[i], 0.0, 1e-12);
}

TEST(Xplorer, ThrustCurveIsExactAtHoverOnly) {
  // 001 Sec. V-A3: thrust = command x 32.5 N, calibrated at hover. The rotors
  // follow T_max ((1 - f) u + f u^2), here f = 0.65: hover command
  // u_h = 1.12 g / 32.5 = 0.33806; T_max = (W / 4) / (0.35 u_h + 0.65 u_h^2)
  // = 2.7468 / 0.19261 = 14.261 N. At 2 u_h: 14.261 (0.35 * 0.67614 + 0.65
  // * 0.45715) = 7.6124 N per rotor vs the linear model's 5.4936 N (+38.6 %);
  // at u_h / 2: 1.1085 N vs 1.3734 N (-19.3 %).
  XplorerParams p;
  EXPECT_EQ(p.thrust_curve_factor, 0.0);  // default: ideal, thrust = command x 32.5
  p.thrust_curve_factor = 0.65;
  Xplorer v(p, at(0, 0, 0.7));
  const double W = 1.12 * 9.81, uh = W / 32.5;
  EXPECT_NEAR(v.rotor_static_thrust(uh), W / 4, 1e-9);
  EXPECT_NEAR(v.rotor_static_thrust(2 * uh), 7.6124, 1e-3);
  EXPECT_NEAR(v.rotor_static_thrust(0.5 * uh), 1.1085, 1e-3);
  EXPECT_NEAR(v.rotor_static_thrust(1.5), v.rotor_static_thrust(1.0), 0.0);  // saturates
  p.thrust_curve_factor = 0.0;  // linear: exactly command x 32.5 / 4
  Xplorer lin(p, at(0, 0, 0.7));
  EXPECT_NEAR(lin.rotor_static_thrust(0.6), 0.6 * 32.5 / 4, 1e-9);
  p.thrust_curve_factor = 1.2;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(Xplorer, TakesOffAndTracksAPositionAndYaw) {
  Xplorer v(XplorerParams{}, at(0, 0, 0));
  Arena empty;
  v.set_setpoint(sp_at(1.0, -0.5, 0.7, 1.0));
  run(v, empty, 8.0);
  EXPECT_LT((v.state().position - Vec3(1.0, -0.5, 0.7)).norm(), 0.01);
  EXPECT_NEAR(v.state().yaw(), 1.0, 0.01);
}

TEST(Xplorer, StaticTipForceGivesDeflectionTorqueOverK) {
  // A 1 N push at the motor of arm 0, perpendicular to the undeflected arm
  // (arm 0 points at -45 deg; +90 deg from it is +45 deg). Equilibrium of
  // 001 eq. 2: k theta = (rho x F)_z = F l cos(theta). Solve independently.
  XplorerParams p;
  Xplorer v(p, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  const double F = 1.0;
  const Vec3 f_b = F * Vec3(std::cos(M_PI / 4), std::sin(M_PI / 4), 0.0);
  v.set_arm_tip_force({f_b, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
  run(v, empty, 4.0);
  double th = 0.1;
  for (int k = 0; k < 50; ++k) th = F * 0.15 * std::cos(th) / 1.307;
  EXPECT_NEAR(v.arm_angles()[0], th, 0.01 * th);
  // theta = torque / k with the torque at the deflected angle, within 1 %.
  const double torque = F * p.arm_length * std::cos(v.arm_angles()[0]);
  EXPECT_NEAR(v.arm_angles()[0], torque / 1.307, 0.01 * th);
  EXPECT_NEAR(v.arm_angles()[1], 0.0, 1e-12);
  EXPECT_NEAR(v.arm_imu(0).angle, v.arm_angles()[0], 0.0);
}

TEST(Xplorer, ArmStepResponseMatchesJbk) {
  // 001 eq. 2 with J = 0.0015, b = 0.009, k = 1.307:
  // wn = sqrt(k/J) = 29.518 rad/s, zeta = b / (2 sqrt(kJ)) = 0.10164,
  // overshoot = exp(-pi zeta / sqrt(1 - zeta^2)) = 0.7255, period 2 pi / wd = 0.2139 s.
  Xplorer v(XplorerParams{}, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  const double tau = 0.05;  // theta_ss = 0.03826 rad (peak 0.066 rad < 30 deg)
  v.set_arm_external_torque({tau, 0, 0, 0});
  double prev = 0.0, prev2 = 0.0;
  std::vector<std::pair<double, double>> peaks;
  for (int k = 1; k <= 2000; ++k) {
    v.step(kDt, empty);
    const double th = v.arm_angles()[0];
    if (k > 2 && prev > prev2 && prev >= th) peaks.emplace_back((k - 1) * kDt, prev);
    prev2 = prev;
    prev = th;
  }
  const double J = 0.0015, b = 0.009, kk = 1.307;
  const double wn = std::sqrt(kk / J), zeta = b / (2 * std::sqrt(kk * J));
  const double wd = wn * std::sqrt(1 - zeta * zeta);
  const double ss = tau / kk;
  ASSERT_GE(peaks.size(), 3u);
  EXPECT_NEAR(peaks[0].second / ss - 1.0, std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta)), 0.02);
  EXPECT_NEAR(peaks[1].first - peaks[0].first, 2 * M_PI / wd, 0.01 * 2 * M_PI / wd);
  // Logarithmic decrement between successive peaks: zeta within 5 %.
  const double delta = std::log((peaks[0].second - ss) / (peaks[1].second - ss));
  EXPECT_NEAR(delta / std::sqrt(4 * M_PI * M_PI + delta * delta), zeta, 0.05 * zeta);
  EXPECT_NEAR(v.arm_angles()[0], ss, 0.01 * ss);  // settled after 2 s (decay time 1/(zeta wn) = 0.33 s)
}

TEST(Xplorer, EndStopsLimitDeflectionToAbout30Degrees) {
  Xplorer v(XplorerParams{}, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  v.set_arm_external_torque({2.0, 0, 0, 0});  // free spring would give 1.53 rad
  run(v, empty, 2.0);
  const double lim = 30.0 * M_PI / 180.0;
  // Beyond the stop: k theta + k_stop (theta - lim) = tau -> theta = (tau + k_stop lim) / (k + k_stop).
  EXPECT_NEAR(v.arm_angles()[0], (2.0 + 30.0 * lim) / (1.307 + 30.0), 1e-3);
  EXPECT_LT(v.arm_angles()[0], lim + 0.05);
}

TEST(Xplorer, WallContactDeflectsArmsConsistentlyAndLogsEachArmOnce) {
  // Hover 0.5 m from a wall at x = 0.5, then fly into it (setpoint behind the
  // wall). Front arms 0 and 1 touch; each arm's steady deflection balances the
  // contact force's hinge moment: k theta = (rho x F_b)_z.
  XplorerParams p;
  Xplorer v(p, at(0, 0, 0.7));
  const Arena arena = wall_x(0.5);
  // Approach at 0.1 m/s (setpoint ramp with velocity feed-forward). First
  // contact at x = 0.5 - 0.141 - 0.07 = 0.289 (motor 0.2 m out along the
  // diagonal, guard 0.07 m); the setpoint 0.35 presses 6 cm further.
  press_into_wall(v, arena);
  const auto ev = v.take_collisions();
  int n0 = 0, n1 = 0;
  for (const auto& e : ev) {
    EXPECT_TRUE(e.part == "arm0" || e.part == "arm1") << e.part;
    n0 += e.part == "arm0";
    n1 += e.part == "arm1";
    EXPECT_TRUE(e.normal.isApprox(Vec2(-1, 0), 1e-9));
    EXPECT_NEAR(e.point.x(), 0.5, 1e-9);
  }
  EXPECT_EQ(n0, 1);
  EXPECT_EQ(n1, 1);
  EXPECT_LT(v.external_force_world().x(), -0.3);  // the wall pushes back
  const Mat3 R = v.state().orientation.toRotationMatrix();
  for (int i : {0, 1}) {
    const Vec3 f_b = R.transpose() * v.arm_contact_force_world(i);
    ASSERT_GT(f_b.norm(), 0.05) << i;
    const double a0 = (i == 0 ? -1 : 1) * M_PI / 4, th = v.arm_angles()[i];
    const Vec3 rho = 0.15 * Vec3(std::cos(a0 + th), std::sin(a0 + th), 0);
    EXPECT_NEAR(1.307 * th, rho.cross(f_b).z(), 0.02 * std::abs(rho.cross(f_b).z()) + 1e-4) << i;
    EXPECT_GT(std::abs(th), 0.01) << i;
  }
  // Both front arms fold backwards: the wall pushes -x, so arm 0 (at -45 deg)
  // gets (rho x F)_z = -rho_y F_x < 0 and arm 1 (at +45 deg) a positive moment.
  EXPECT_LT(v.arm_angles()[0], -0.01);
  EXPECT_GT(v.arm_angles()[1], 0.01);
  // Back off: no new events.
  v.set_setpoint(sp_at(0, 0, 0.7));
  run(v, arena, 3.0);
  EXPECT_TRUE(v.take_collisions().empty());
  EXPECT_NEAR(v.arm_angles()[0], 0.0, 1e-3);
}

TEST(Xplorer, ArmImuAtRestAndSpinning) {
  Xplorer v(XplorerParams{}, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  run(v, empty, 2.0);
  for (int i = 0; i < 4; ++i) {
    const ArmImuTruth t = v.arm_imu(i);
    EXPECT_LT((t.accel - Vec3(0, 0, 9.81)).norm(), 0.01) << i;
    EXPECT_LT(t.gyro.norm(), 1e-3) << i;
    // Arm frame yaw = arm direction (-45, 45, 135, -135 deg) + body yaw 0.
    const Vec3 x = t.orientation * Vec3::UnitX();
    const double expect[4] = {-M_PI / 4, M_PI / 4, 3 * M_PI / 4, -3 * M_PI / 4};
    EXPECT_NEAR(std::atan2(x.y(), x.x()), expect[i], 1e-3) << i;
  }
  // Constant yaw rate 2 rad/s with the attitude loops off: each arm IMU
  // (0.05 + 0.10 m from the centre along its arm) feels -w^2 r = -0.6 m/s^2
  // along the arm and reads w on its z gyro.
  XplorerParams p;
  p.controller.att_p.setZero();
  p.controller.rate_p.setZero();
  p.controller.rate_i.setZero();
  p.controller.rate_d.setZero();
  RigidBodyState s = at(0, 0, 0.7);
  s.angular_velocity = Vec3(0, 0, 2.0);
  Xplorer spin(p, s);
  spin.set_setpoint(sp_at(0, 0, 0.7));
  run(spin, empty, 0.5);
  for (int i = 0; i < 4; ++i) {
    const ArmImuTruth t = spin.arm_imu(i);
    EXPECT_NEAR(t.accel.x(), -4.0 * 0.15, 0.01) << i;
    EXPECT_NEAR(t.accel.y(), 0.0, 0.01) << i;
    EXPECT_NEAR(t.gyro.z(), 2.0, 1e-9) << i;
  }
}

TEST(Xplorer, Deterministic) {
  const Arena arena = wall_x(0.5);
  auto go = [&]() {
    Xplorer v(XplorerParams{}, at(0, 0, 0));
    v.set_setpoint(sp_at(0.7, 0.1, 0.7));
    run(v, arena, 4.0);
    return std::make_pair(v.state(), v.arm_angles());
  };
  const auto a = go(), b = go();
  EXPECT_EQ(a.first.position, b.first.position);
  EXPECT_EQ(a.first.orientation.coeffs(), b.first.orientation.coeffs());
  EXPECT_EQ(a.second, b.second);
}

TEST(Xplorer, ParamsValidate) {
  XplorerParams p;
  p.arm_stiffness = 0.0;
  EXPECT_THROW(Xplorer(p, RigidBodyState{}), std::invalid_argument);
  p = {};
  p.thrust_scale = 10.0;  // < 11 N weight
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("XplorerParams.thrust_scale"), std::string::npos);
  }
  Xplorer v(XplorerParams{}, RigidBodyState{});
  EXPECT_THROW(v.arm_imu(4), std::out_of_range);
}

TEST(Xplorer, RigidArmsStayStraightAndPassTheTipMomentToTheBody) {
  // 001 Sec. V-C4's rigid chassis: a 1 N push at motor 0 perpendicular to the
  // arm leaves theta = 0 (compliant: 0.11 rad, test above), and the body gets
  // the moment of the force about the centre, tip x F (motor 0.2 m out on
  // the -45 deg diagonal, F at +45 deg -> (tip x F)_z = 0.2 N m).
  XplorerParams p;
  p.rigid_arms = true;
  Xplorer v(p, at(0, 0, 0.7));
  Arena empty;
  v.set_setpoint(sp_at(0, 0, 0.7));
  const Vec3 f_b(std::cos(M_PI / 4), std::sin(M_PI / 4), 0.0);
  run(v, empty, 1.0);
  const double yaw0 = v.state().yaw();
  v.set_arm_tip_force({f_b, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
  // First step from rest: angular acceleration = torque / I_zz.
  const double w0 = v.state().angular_velocity.z();
  v.step(kDt, empty);
  EXPECT_EQ(v.arm_angles()[0], 0.0);
  EXPECT_EQ(v.arm_rates()[0], 0.0);
  const double wdot = (v.state().angular_velocity.z() - w0) / kDt;
  // The yaw controller reacts within the same step only through its rate loop
  // (< 10 % here); the contact moment dominates.
  EXPECT_NEAR(wdot, 0.2 / 0.015, 0.1 * 0.2 / 0.015);
  run(v, empty, 1.0);
  EXPECT_EQ(v.arm_angles()[0], 0.0);
  // 0.2 N m is beyond the rotors' yaw authority: the rigid vehicle spins
  // (a compliant arm would have folded and kept the moment in its spring).
  EXPECT_GT(std::abs(v.state().yaw() - yaw0), 0.3);
}

TEST(Xplorer, RigidArmsAgainstAWallGiveNoDeflection) {
  XplorerParams p;
  p.rigid_arms = true;
  Xplorer v(p, at(0, 0, 0.7));
  const Arena arena = wall_x(0.5);
  press_into_wall(v, arena);
  EXPECT_LT(v.external_force_world().x(), -0.02);  // in contact
  for (int i = 0; i < 4; ++i) EXPECT_EQ(v.arm_angles()[i], 0.0) << i;
  // Rigid: the guard edge stays 0.2114 m ahead of the centre (compliant arms fold back).
  EXPECT_NEAR(v.state().position.x(), 0.5 - (0.2 * std::cos(M_PI / 4) + 0.07), 0.003);
}

namespace {

/// Min height after 1 s and max tilt [deg] of a flight at 0.3 m/s into the
/// corner of a 0.8 m box turned by 30 deg (centre (1.2, 0); corner at
/// x = 0.65), setpoint held 0.05 m past it (an exploration lead into the
/// object), 12 s.
std::pair<double, double> into_a_box_corner(TorqueDesaturation mode) {
  Arena a;
  const int id = a.add_obstacle("box");
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6), h = 0.4;
  const double sx[4] = {-h, h, h, -h}, sy[4] = {-h, -h, h, h};
  Vec2 p[4];
  for (int i = 0; i < 4; ++i) p[i] = Vec2(1.2 + c * sx[i] - s * sy[i], s * sx[i] + c * sy[i]);
  for (int i = 0; i < 4; ++i) a.add_wall(p[i], p[(i + 1) % 4], 0, id);
  XplorerParams params;
  params.controller.desaturation = mode;
  Xplorer v(params, at(0, 0, 0.7));
  double min_z = 1e9, max_tilt = 0.0;
  for (int k = 0; k < 12000; ++k) {
    const double x = std::min(0.3 * k * kDt, 0.7);
    PositionSetpoint sp = sp_at(x, 0, 0.7);
    if (x < 0.7) sp.velocity_ff = Vec3(0.3, 0, 0);
    v.set_setpoint(sp);
    v.step(kDt, a);
    if (k * kDt < 1.0) continue;
    min_z = std::min(min_z, v.state().position.z());
    const double r22 = v.state().orientation.toRotationMatrix()(2, 2);
    max_tilt = std::max(max_tilt, std::acos(std::clamp(r22, -1.0, 1.0)) * 180.0 / M_PI);
  }
  return {min_z, max_tilt};
}

}  // namespace

TEST(Xplorer, KeepsItsHeightPressedOnABoxCorner) {
  // The corner's faces push two arms round: their springs pass a yaw torque
  // of up to 0.68 N m per arm, ~4x what the rotors can answer at hover
  // (0.18 N m). The default allocation gives roll/pitch first and yaw what
  // is left (kYawFirst): the tilt stays near the 0.6 rad (34 deg) the
  // position loop may ask for and the height is kept.
  EXPECT_EQ(XplorerParams{}.controller.desaturation, TorqueDesaturation::kYawFirst);
  const auto [z, tilt] = into_a_box_corner(TorqueDesaturation::kYawFirst);
  EXPECT_GT(z, 0.6);
  EXPECT_LT(tilt, 35.0);
  // Scaling every axis alike (the rule before): the yaw demand shrinks the
  // roll/pitch torque, the attitude is lost and the vehicle falls to the floor.
  const auto [z_all, tilt_all] = into_a_box_corner(TorqueDesaturation::kScaleAll);
  EXPECT_LT(z_all, 0.1);
  EXPECT_GT(tilt_all, 60.0);
}
