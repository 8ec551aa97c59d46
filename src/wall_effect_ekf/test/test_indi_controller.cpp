// INDI controller (004 eq. 26-36): increments against hand computations,
// allocation, and a closed loop on the near-wall model.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "wall_effect_ekf/indi_controller.hpp"
#include "wall_effect_ekf/wall_ekf.hpp"

using namespace wall_effect_ekf;

namespace {
constexpr double kM = 0.28;
IndiParams hand_params() {
  IndiParams p;
  p.k_p = Vec3(6, 6, 6);
  p.k_d = Vec3(4.5, 4.5, 4.5);
  p.k_i = Vec3(1, 1, 1);
  p.attitude_time_constant = 0.5;
  return p;
}
}  // namespace

TEST(Indi, OuterLoopLevelHoverByHand) {
  IndiController c(hand_params());
  IndiSetpoint sp;
  sp.position = Vec3(0.04, 0.0, 0.0);
  IndiFeedback fb;  // at the origin, level, at rest: a_m = (0, 0, g)
  const IndiOuterOutput o = c.outer(sp, fb, 0.01);
  // eq. 26: a_t = K_p e + K_i e dt = 0.24 + 0.0004
  EXPECT_NEAR(o.accel_target.x(), 0.2404, 1e-12);
  // eq. 30: Delta = m (a_t - (R a_m - g e3)) = m a_t
  EXPECT_NEAR(o.increment.x(), kM * 0.2404, 1e-12);
  // eq. 32-33 with T0(t_k-1) = m g and tau = 0.5 s
  EXPECT_NEAR(o.rate_x, 0.0, 1e-12);
  EXPECT_NEAR(o.rate_y, 0.2404 / (kGravity * 0.5), 1e-12);
  // eq. 34: z_B^T e = 0
  EXPECT_NEAR(o.thrust, kM * kGravity, 1e-12);
  // Vertical error: only T0 changes (eq. 34), increment m * 0.601.
  IndiController c2(hand_params());
  sp.position = Vec3(0.0, 0.0, 0.04);
  const IndiOuterOutput o2 = c2.outer(sp, fb, 0.01);
  EXPECT_NEAR(o2.thrust, kM * kGravity + kM * 0.2404, 1e-12);
  // Outside integral_zone the integral does not run (anti-windup).
  IndiController c3(hand_params());
  sp.position = Vec3(0.1, 0.0, 0.0);
  EXPECT_NEAR(c3.outer(sp, fb, 0.01).accel_target.x(), 0.6, 1e-12);
  EXPECT_NEAR(o2.rate_x, 0.0, 1e-12);
  EXPECT_NEAR(o2.rate_y, 0.0, 1e-12);
}

TEST(Indi, OuterLoopTiltedWithMeasuredAccelerationByHand) {
  IndiParams p = hand_params();
  p.k_i.setZero();
  IndiController c(p);
  const Mat3 R = Eigen::AngleAxisd(0.1, Vec3::UnitX()).toRotationMatrix();
  IndiFeedback fb;
  fb.R = R;
  fb.velocity = Vec3(0.0, 0.2, 0.0);
  // Specific force: thrust m g / cos along z_B -> measured acceleration.
  fb.specific_force = Vec3(0.0, 0.0, kGravity / std::cos(0.1));
  const Vec3 a_meas = R * fb.specific_force - kGravity * Vec3::UnitZ();
  IndiSetpoint sp;  // hold the origin: a_t = K_d (0 - v)
  const IndiOuterOutput o = c.outer(sp, fb, 0.01);
  const Vec3 a_t(0.0, -4.5 * 0.2, 0.0);
  EXPECT_TRUE(o.accel_target.isApprox(a_t, 1e-12));
  const Vec3 e = a_t - a_meas;
  const double T_prev = kM * kGravity;
  EXPECT_NEAR(o.rate_x, -kM / (T_prev * 0.5) * R.col(1).dot(e), 1e-12);  // eq. 32
  EXPECT_NEAR(o.rate_y, kM / (T_prev * 0.5) * R.col(0).dot(e), 1e-12);   // eq. 33
  EXPECT_NEAR(o.thrust, T_prev + kM * R.col(2).dot(e), 1e-12);            // eq. 34
  // The increments chain: the next T0 starts from this one.
  EXPECT_NEAR(c.previous_thrust(), o.thrust, 0.0);
}

TEST(Indi, VelocityModeIgnoresPositionError) {
  IndiController c(hand_params());
  IndiSetpoint sp;
  sp.position = Vec3(5.0, 0.0, 0.0);
  sp.velocity = Vec3(0.25, 0.0, 0.0);
  sp.position_control = {false, true, true};  // pilot direction along x (004: K_p = K_i = 0)
  const IndiOuterOutput o = c.outer(sp, IndiFeedback{}, 0.01);
  EXPECT_NEAR(o.accel_target.x(), 4.5 * 0.25, 1e-12);
}

TEST(Indi, InnerLoopEq35ByHand) {
  IndiController c(hand_params());
  IndiSetpoint sp;
  sp.position = Vec3(0.1, 0.0, 0.0);
  const IndiOuterOutput o = c.outer(sp, IndiFeedback{}, 0.01);
  const Vec3 w(0.1, -0.05, 0.2);
  const Vec3 wd = c.angular_accel(w, 0.3, 0.1);
  EXPECT_NEAR(wd.x(), -25.0 * (0.1 - o.rate_x), 1e-12);
  EXPECT_NEAR(wd.y(), -25.0 * (-0.05 - o.rate_y), 1e-12);
  EXPECT_NEAR(wd.z(), -6.0 * 0.2 - 9.0 * 0.2, 1e-12);
  // Yaw error wraps: 179 deg vs -179 deg is 2 deg.
  const Vec3 wy = c.angular_accel(Vec3::Zero(), M_PI - 0.01, -M_PI + 0.01);
  EXPECT_NEAR(wy.z(), -9.0 * (-0.02), 1e-9);
}

TEST(Indi, AllocationEq36RealisesTorqueAndThrustWithTheWallInB) {
  const IndiParams p;
  IndiController c(p);
  const Vec3 wd(2.0, -1.0, 0.5), w(0.2, 0.1, -0.3);
  const double T = 2.9;
  const Mat3 J = p.vehicle.inertia_diag.asDiagonal();
  const Vec3 tau = J * wd + w.cross(J * w);
  for (bool wall : {false, true}) {
    AllocationWall aw;
    aw.present = wall;
    aw.y = 0.15;
    aw.R = so3_exp(Vec3(0.05, -0.02, 0.4));
    const auto f = c.allocate(wd, w, T, aw);
    const Vec4 t0(f[0], f[1], f[2], f[3]);
    EXPECT_NEAR(t0.sum(), T, 1e-9);
    const Mat34 B = torque_matrix(aw.y, aw.R, p.vehicle, wall);
    EXPECT_LT((B * t0 - tau).norm(), 1e-9) << wall;
  }
  // Saturation keeps the collective thrust and every rotor within [0, max].
  const auto f = c.allocate(Vec3(500, 0, 0), Vec3::Zero(), T);
  double sum = 0.0;
  for (double x : f) {
    EXPECT_GE(x, 0.0);
    EXPECT_LE(x, p.vehicle.max_rotor_thrust);
    sum += x;
  }
  EXPECT_NEAR(sum, T, 1e-9);
}

TEST(Indi, ValidateNamesTheField) {
  IndiParams p;
  p.max_tilt = 2.0;
  try {
    IndiController c(p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("IndiParams.max_tilt"), std::string::npos);
  }
}

TEST(Indi, HoldsPositionNearTheWallDespiteTheUnmodelledAttraction) {
  // The outer loop neglects the wall effect (004: treated as a disturbance);
  // the truth follows the near-wall model (eq. 5-8). Outer loop at 100 Hz,
  // inner loop and truth at 1 kHz.
  IndiParams p;
  p.attitude_time_constant = 0.1;
  IndiController c(p);
  WallState x;
  x.y = 0.30;
  x.z = 1.0;
  Vec4 T = Vec4::Constant(kM * kGravity / 4.0);
  IndiSetpoint sp;
  sp.position = Vec3(0.0, 0.17, 1.0);
  double max_err_late = 0.0;
  for (int k = 0; k < 10000; ++k) {  // 10 s
    if (k % 10 == 0) {
      IndiFeedback fb;
      fb.position = Vec3(0.0, x.y, x.z);
      fb.velocity = x.v;
      fb.R = x.R;
      fb.specific_force = predict_accel(x, T, p.vehicle);
      c.outer(sp, fb, 0.01);
    }
    const Vec3 xb = x.R.col(0);
    AllocationWall wall;  // eq. 36: B with the wall effect (004: "integrated into B")
    wall.present = true;
    wall.y = x.y;
    wall.R = x.R;
    const auto f = c.inner(x.omega, std::atan2(xb.y(), xb.x()), 0.0, wall);
    T = Vec4(f[0], f[1], f[2], f[3]);
    const StateDerivative d = dynamics(x, T, p.vehicle);
    x.y += d.y_dot * 0.001;
    x.z += d.z_dot * 0.001;
    x.v += d.v_dot * 0.001;
    x.R = x.R * so3_exp(x.omega * 0.001);
    x.omega += d.omega_dot * 0.001;
    ASSERT_GT(x.y, 0.12) << "hit the wall at step " << k;
    if (std::getenv("WE_DEBUG") && k % 200 == 0) printf("%d y %.4f z %.4f roll %.4f\n", k, x.y, x.z, std::atan2(x.R(2,1), x.R(2,2)));
    if (k > 6000) max_err_late = std::max(max_err_late, std::abs(x.y - 0.17));
  }
  EXPECT_LT(max_err_late, 0.003);
  EXPECT_NEAR(x.z, 1.0, 0.003);
}
