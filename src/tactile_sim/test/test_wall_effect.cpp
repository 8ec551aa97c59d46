// Wall effect (004 eq. 3-7): values computed by hand / independently.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "tactile_sim/wall_effect.hpp"

using namespace tactile_sim;

namespace {
Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
Mat3 rot_x(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
}  // namespace

TEST(WallEffect, GammaMatchesPaperFitAtHandComputedDistances) {
  // 004 eq. 4: gamma_h = 0.21 * 0.34^d, gamma_v = 1 + 0.06 * 0.54^d.
  // Hand values: 0.34^1 = 0.34, 0.34^2 = 0.1156, 0.34^0.5 = 0.583095;
  // 0.54^1 = 0.54, 0.54^2 = 0.2916, 0.54^0.5 = 0.734847.
  EXPECT_NEAR(gamma_h(0.0), 0.21, 1e-12);
  EXPECT_NEAR(gamma_v(0.0), 1.06, 1e-12);
  EXPECT_NEAR(gamma_h(1.0), 0.0714, 1e-12);
  EXPECT_NEAR(gamma_v(1.0), 1.0324, 1e-12);
  EXPECT_NEAR(gamma_h(2.0), 0.024276, 1e-12);
  EXPECT_NEAR(gamma_v(2.0), 1.017496, 1e-12);
  EXPECT_NEAR(gamma_h(0.5), 0.21 * 0.583095, 1e-6);
  EXPECT_NEAR(gamma_v(0.5), 1.0 + 0.06 * 0.734847, 1e-6);
  // Far away: gamma_h -> 0, gamma_v -> 1 (004 text after eq. 4), cutoff at 8.
  EXPECT_EQ(gamma_h(9.0), 0.0);
  EXPECT_EQ(gamma_v(9.0), 1.0);
  // Inside the wall is clamped to contact.
  EXPECT_EQ(gamma_h(-0.3), gamma_h(0.0));
}

TEST(WallEffect, RotorForceHorizontalAndVerticalMatchEq3AtSeveralDistances) {
  // Upright rotor, wall normal +y (004 frame: wall at y = 0, robot at y > 0).
  // Eq. 3/5: T_h = gamma_h T0 towards the wall (-y), T_v = gamma_v T0.
  const double T0 = 0.7;  // [N]
  const double R = 0.038;
  RotorWall w;
  w.present = true;
  w.normal_world = Vec3(0, 1, 0);
  for (double d_mm : {0.0, 10.0, 38.0, 76.0, 150.0}) {
    w.distance = d_mm * 1e-3;
    const double db = w.distance / R;
    const double th = 0.21 * std::pow(0.34, db);
    const double tv = 1.0 + 0.06 * std::pow(0.54, db);
    const Vec3 f = rotor_force_world(T0, Mat3::Identity(), w);
    EXPECT_NEAR(f.x(), 0.0, 1e-12) << d_mm;
    EXPECT_NEAR(f.y(), -th * T0, 1e-12) << d_mm;
    EXPECT_NEAR(f.z(), tv * T0, 1e-12) << d_mm;
  }
}

TEST(WallEffect, WallNormalInAnyDirectionAndBodyFrame) {
  // Wall normal pointing -x (wall east of the rotor): attraction along +x.
  RotorWall w{true, 0.038, Vec3(-1, 0, 0)};
  const Vec3 f = rotor_force_world(1.0, Mat3::Identity(), w);
  EXPECT_NEAR(f.x(), 0.0714, 1e-12);
  EXPECT_NEAR(f.y(), 0.0, 1e-12);
  EXPECT_NEAR(f.z(), 1.0324, 1e-12);
  // Body yawed 90 deg: world +x is body -y.
  const Vec3 fb = rotor_force_body(1.0, rot_z(M_PI / 2), w);
  EXPECT_NEAR(fb.x(), 0.0, 1e-12);
  EXPECT_NEAR(fb.y(), -0.0714, 1e-12);
  EXPECT_NEAR(fb.z(), 1.0324, 1e-12);
}

TEST(WallEffect, TiltedRotorUsesVerticalComponentOnly) {
  // 004 eq. 5: Gamma acts on R e3; only its z component is amplified/deflected.
  const double a = 0.2;
  const Mat3 R = rot_x(a);  // R e3 = (0, -sin a, cos a)
  RotorWall w{true, 0.0, Vec3(0, 1, 0)};
  const Vec3 f = rotor_force_world(2.0, R, w);
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 2.0 * (-std::sin(a) - 0.21 * std::cos(a)), 1e-12);
  EXPECT_NEAR(f.z(), 2.0 * 1.06 * std::cos(a), 1e-12);
}

TEST(WallEffect, NoWallGivesNominalThrust) {
  const Mat3 R = rot_x(0.3) * rot_z(1.0);
  const Vec3 f = rotor_force_world(1.5, R, RotorWall{});
  EXPECT_TRUE(f.isApprox(1.5 * R.col(2), 1e-12));
}

TEST(WallEffect, WrenchEq6Eq7) {
  RotorGeometry g;
  const double L = 0.1;
  g.position_body = {Vec3(L, -L, 0), Vec3(-L, -L, 0), Vec3(-L, L, 0), Vec3(L, L, 0)};
  g.torque_coefficient = 0.01;
  std::array<double, 4> T0 = {1.0, 1.0, 1.0, 1.0};
  std::array<RotorWall, 4> walls{};
  // Free flight: force 4 e3, torque 0 (symmetric, spins cancel).
  RotorWrench w = rotor_wrench(T0, Mat3::Identity(), g, walls);
  EXPECT_TRUE(w.force_world.isApprox(Vec3(0, 0, 4.0), 1e-12));
  EXPECT_LT(w.torque_body.norm(), 1e-12);
  // Wall at y = -0.2 with normal +y: rotors 1, 2 (y = -L) at d = 0.1 - R,
  // rotors 3, 4 (y = +L) at d = 0.3 - R. Hand computation:
  const double R = 0.038;
  const double d12 = (0.2 - L - R) / R, d34 = (0.2 + L - R) / R;
  for (int i : {0, 1}) walls[i] = RotorWall{true, 0.2 - L - R, Vec3(0, 1, 0)};
  for (int i : {2, 3}) walls[i] = RotorWall{true, 0.2 + L - R, Vec3(0, 1, 0)};
  w = rotor_wrench(T0, Mat3::Identity(), g, walls);
  const double gh12 = 0.21 * std::pow(0.34, d12), gh34 = 0.21 * std::pow(0.34, d34);
  const double gv12 = 1 + 0.06 * std::pow(0.54, d12), gv34 = 1 + 0.06 * std::pow(0.54, d34);
  EXPECT_NEAR(w.force_world.y(), -2 * gh12 - 2 * gh34, 1e-12);          // eq. 6
  EXPECT_NEAR(w.force_world.z(), 2 * gv12 + 2 * gv34, 1e-12);
  // eq. 7, roll: sum(r_y F_z - r_z F_y) + c s_i F_x,i = -2 L gv12 + 2 L gv34
  // (the rotors near the wall push up harder and roll the vehicle away from it).
  EXPECT_NEAR(w.torque_body.x(), -2 * L * gv12 + 2 * L * gv34, 1e-12);
  // pitch: sum(r_z F_x - r_x F_z) = -(L gv12 - L gv12 - L gv34 + L gv34) = 0
  EXPECT_NEAR(w.torque_body.y(), 0.0, 1e-12);
  // yaw: sum(r_x F_y - r_y F_x) = L(-gh12) - L(-gh12) - L(-gh34) + L(-gh34) = 0;
  // spin terms c s_i F_z,i = c (gv12 - gv12 + gv34 - gv34) = 0.
  EXPECT_NEAR(w.torque_body.z(), 0.0, 1e-12);
  // One rotor alone: spin term of eq. 7 = s_1 c (R^T T_W,1).
  std::array<double, 4> T1 = {1.0, 0.0, 0.0, 0.0};
  w = rotor_wrench(T1, Mat3::Identity(), g, walls);
  const Vec3 f1(0, -gh12, gv12);
  const Vec3 expect = g.position_body[0].cross(f1) + 0.01 * f1;
  EXPECT_TRUE(w.torque_body.isApprox(expect, 1e-12));
}

TEST(WallEffect, ParamsValidate) {
  WallEffectParams p;
  EXPECT_NO_THROW(p.validate());
  p.b1 = 1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = {};
  p.rotor_radius = 0.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("WallEffectParams.rotor_radius"), std::string::npos);
  }
}
