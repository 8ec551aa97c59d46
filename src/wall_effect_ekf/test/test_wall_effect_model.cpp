// Near-wall model against hand computations: 004 eq. 4, 5, 6, 7-8, 9-10.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "wall_effect_ekf/wall_effect_model.hpp"

using namespace wall_effect_ekf;

namespace {
Mat3 yaw(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
}  // namespace

TEST(Proximity, Eq4HandValues) {
  const ProximityParams p;  // R = 38 mm, 0.21 * 0.34^d, 1 + 0.06 * 0.54^d
  Proximity g = proximity(0.0, p);
  EXPECT_NEAR(g.gh, 0.21, 1e-12);
  EXPECT_NEAR(g.gv, 1.06, 1e-12);
  g = proximity(0.038, p);  // d_bar = 1
  EXPECT_NEAR(g.gh, 0.0714, 1e-12);
  EXPECT_NEAR(g.gv, 1.0324, 1e-12);
  g = proximity(0.076, p);  // d_bar = 2
  EXPECT_NEAR(g.gh, 0.21 * 0.1156, 1e-12);
  EXPECT_NEAR(g.gv, 1.0 + 0.06 * 0.2916, 1e-12);
  // Far away: gamma_h -> 0, gamma_v -> 1 (004: "as anticipated").
  g = proximity(2.0, p);
  EXPECT_LT(g.gh, 1e-20);
  EXPECT_NEAR(g.gv, 1.0, 1e-12);
  // Touching / inside the wall: clamped to d_bar = 0, no slope.
  g = proximity(-0.01, p);
  EXPECT_NEAR(g.gh, 0.21, 1e-12);
  EXPECT_EQ(g.dgh, 0.0);
}

TEST(Proximity, DerivativesMatchFiniteDifferences) {
  const ProximityParams p;
  for (double y : {0.005, 0.02, 0.05, 0.1, 0.2}) {
    const double h = 1e-7;
    const Proximity a = proximity(y + h, p), b = proximity(y - h, p), g = proximity(y, p);
    EXPECT_NEAR(g.dgh, (a.gh - b.gh) / (2 * h), 1e-6 * std::abs(g.dgh) + 1e-9) << y;
    EXPECT_NEAR(g.dgv, (a.gv - b.gv) / (2 * h), 1e-6 * std::abs(g.dgv) + 1e-9) << y;
  }
}

TEST(Proximity, ValidateNamesTheField) {
  ProximityParams p;
  p.b1 = 1.2;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ProximityParams.b1"), std::string::npos);
  }
  VehicleParams v;
  v.max_rotor_thrust = 0.5;  // 4 * 0.5 N < 0.28 kg * g
  EXPECT_THROW(v.validate(), std::invalid_argument);
}

TEST(GammaMatrix, Eq5) {
  const ProximityParams p;
  const Mat3 G = gamma_matrix(0.038, p);
  Mat3 expect;
  expect << 1, 0, 0, 0, 1, -0.0714, 0, 0, 1.0324;
  EXPECT_TRUE(G.isApprox(expect, 1e-12));
}

TEST(Wrench, LevelVehicleEq5To7ByHand) {
  VehicleParams v;  // L = 0.082, c_tau = 0.01
  const double L = v.rotor_offset, Rr = v.proximity.rotor_radius;
  // Level, yaw 0: rotors 0 (FR) and 3 (BR) at body y = -L are nearest.
  const double y = 0.18;
  const double y_near = y - L - Rr, y_far = y + L - Rr;  // 004: y_i = y + e2^T R r_i - R
  EXPECT_NEAR(rotor_wall_distance(y, Mat3::Identity(), v.rotor_positions()[0], v.proximity), y_near, 1e-15);
  EXPECT_NEAR(rotor_wall_distance(y, Mat3::Identity(), v.rotor_positions()[1], v.proximity), y_far, 1e-15);
  const Proximity gn = proximity(y_near, v.proximity), gf = proximity(y_far, v.proximity);
  // Only rotor 0 spinning, T = 0.7 N.
  const double T = 0.7;
  Wrench w = rotor_wrench(Vec4(T, 0, 0, 0), y, Mat3::Identity(), v);
  EXPECT_NEAR(w.force_wall.x(), 0.0, 1e-15);
  EXPECT_NEAR(w.force_wall.y(), -gn.gh * T, 1e-15);  // attraction towards the wall (-y_W)
  EXPECT_NEAR(w.force_wall.z(), gn.gv * T, 1e-15);
  // tau = ([r]x + c_tau I) f, r = (L, -L, 0), f = (0, -gh T, gv T)
  const Vec3 tau_hand(-L * gn.gv * T, -L * gn.gv * T - v.torque_coefficient * gn.gh * T,
                      -L * gn.gh * T + v.torque_coefficient * gn.gv * T);
  EXPECT_TRUE(w.torque_body.isApprox(tau_hand, 1e-12)) << w.torque_body.transpose();
  // All four: eq. 6 sum.
  w = rotor_wrench(Vec4(T, T, T, T), y, Mat3::Identity(), v);
  EXPECT_NEAR(w.force_wall.y(), -2 * T * (gn.gh + gf.gh), 1e-14);
  EXPECT_NEAR(w.force_wall.z(), 2 * T * (gn.gv + gf.gv), 1e-14);
  // The near side pushes up more: a roll torque tilting away... sign by hand:
  // tau_x = sum r_y f_z = -L (2 T gn.gv) + L (2 T gf.gv) < 0.
  EXPECT_NEAR(w.torque_body.x(), 2 * L * T * (gf.gv - gn.gv), 1e-14);
  // Free flight: T R e3 and the usual quadrotor torque.
  w = rotor_wrench(Vec4(T, T, T, T), y, Mat3::Identity(), v, false);
  EXPECT_TRUE(w.force_wall.isApprox(Vec3(0, 0, 4 * T)));
  EXPECT_LT(w.torque_body.norm(), 1e-15);
}

TEST(Wrench, FarFromTheWallIsFreeFlight) {
  const VehicleParams v;
  const Mat3 R = Eigen::AngleAxisd(0.2, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec4 T(0.6, 0.7, 0.65, 0.72);
  const Wrench near_inf = rotor_wrench(T, 5.0, R, v);
  const Wrench free = rotor_wrench(T, 5.0, R, v, false);
  EXPECT_TRUE(near_inf.force_wall.isApprox(free.force_wall, 1e-12));
  EXPECT_TRUE(near_inf.torque_body.isApprox(free.torque_body, 1e-12));
}

TEST(Wrench, TorqueMatrixEq8IsLinearInT0) {
  const VehicleParams v;
  const Mat3 R = Eigen::AngleAxisd(0.1, Vec3(0.3, -1, 0.2).normalized()).toRotationMatrix() * yaw(0.7);
  const Vec4 T(0.6, 0.7, 0.65, 0.72);
  for (double y : {0.12, 0.18, 0.3}) {
    const Mat34 B = torque_matrix(y, R, v);
    EXPECT_TRUE((B * T).isApprox(rotor_wrench(T, y, R, v).torque_body, 1e-12)) << y;
  }
}

TEST(Flow, Eq9And10ByHand) {
  // Yaw 90 deg: world x velocity is body -y.
  const Vec2 n = optical_flow(Vec3(1.0, 0.0, 0.0), yaw(M_PI / 2), Vec3(0.1, 0.2, 0.0), 2.0);
  EXPECT_NEAR(n.x(), 0.0 / 2.0 - 0.2, 1e-12);
  EXPECT_NEAR(n.y(), -1.0 / 2.0 + 0.1, 1e-12);
  // Level, forward 0.5 m/s at 1 m, no rotation.
  const Vec2 m = optical_flow(Vec3(0.5, 0.0, 0.0), Mat3::Identity(), Vec3::Zero(), 1.0);
  EXPECT_NEAR(m.x(), 0.5, 1e-12);
  EXPECT_NEAR(m.y(), 0.0, 1e-12);
}
