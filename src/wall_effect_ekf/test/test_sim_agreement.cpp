// The estimator's own near-wall model against the simulator's independent
// implementation (tactile_sim/wall_effect.hpp, sensors.hpp) where both
// describe the same physics: the 004 eq. 5-7 wrench near a straight wall,
// the eq. 9-10 flow and the ToF slant range.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/ducted_quad.hpp"
#include "tactile_sim/sensors.hpp"
#include "tactile_sim/wall_effect.hpp"
#include "wall_effect_ekf/wall_ekf.hpp"
#include "wall_effect_ekf/wall_effect_model.hpp"

namespace we = wall_effect_ekf;
namespace ts = tactile_sim;

namespace {

/// The wall of 004 Fig. 3a: along x at y = 0, free side y > 0, so the wall
/// frame of the estimator is the simulator's world frame.
ts::Arena wall_arena() {
  ts::Arena a;
  const int id = a.add_obstacle("wall");
  a.add_wall(ts::Vec2(-5.0, 0.0), ts::Vec2(5.0, 0.0), 0, id);
  return a;
}

}  // namespace

TEST(SimAgreement, WrenchNearAWallMatchesTheSimulator) {
  const ts::Arena arena = wall_arena();
  const ts::DuctedQuadParams qp;  // the simulated vehicle
  we::VehicleParams vp;           // the estimator's vehicle: same geometry by default
  ASSERT_DOUBLE_EQ(vp.rotor_offset, qp.rotor_offset);
  ASSERT_DOUBLE_EQ(vp.torque_coefficient, qp.torque_coefficient);
  ASSERT_DOUBLE_EQ(vp.proximity.rotor_radius, qp.wall_effect.rotor_radius);
  ts::RotorGeometry g;
  const double L = qp.rotor_offset;
  g.position_body = {ts::Vec3(L, -L, 0), ts::Vec3(L, L, 0), ts::Vec3(-L, L, 0), ts::Vec3(-L, -L, 0)};
  g.torque_coefficient = qp.torque_coefficient;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int compared = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const double y = 0.17 + 0.05 * u(rng);
    const we::Mat3 R = we::so3_exp(we::Vec3(0.2 * u(rng), 0.2 * u(rng), M_PI * u(rng)));
    const std::array<double, 4> T = {0.6 + 0.1 * u(rng), 0.7 + 0.1 * u(rng), 0.65 + 0.1 * u(rng), 0.7 + 0.1 * u(rng)};
    // Simulator: per-rotor wall from the arena (as DuctedQuad::step does).
    std::array<ts::RotorWall, 4> walls{};
    const ts::Vec3 p(0.3 * u(rng), y, 1.0);
    // Physical configurations only: every duct outside the wall (the
    // simulator's distance is unsigned; the guards collide before that).
    bool inside = false;
    double tol = 1e-12;
    for (int i = 0; i < 4; ++i) {
      const double yi = (p + R * g.position_body[static_cast<size_t>(i)]).y() - qp.wall_effect.rotor_radius;
      inside |= yi < qp.guard_radius - qp.wall_effect.rotor_radius;
      // The simulator cuts the effect off beyond d_bar = 8 (its choice): up to
      // T0 (a1 b1^8 + a2 b2^8) per rotor there.
      if (yi / qp.wall_effect.rotor_radius > qp.wall_effect.cutoff_normalized) tol += 0.8 * 5e-4;
    }
    if (inside) continue;
    for (int i = 0; i < 4; ++i) {
      const ts::Vec3 rw = p + R * g.position_body[static_cast<size_t>(i)];
      const ts::Hit h = arena.closest(rw.head<2>(), 1.0);
      ASSERT_TRUE(h.hit);
      walls[static_cast<size_t>(i)] = ts::RotorWall{true, h.distance - qp.wall_effect.rotor_radius,
                                                    ts::Vec3(h.normal.x(), h.normal.y(), 0.0)};
    }
    // The estimator's model applies eq. 5 to every rotor; the simulator's
    // cut-off (d_bar > 8) does not matter for rotors within 8 R.
    const ts::RotorWrench s = ts::rotor_wrench(T, R, g, walls, qp.wall_effect);
    const we::Wrench e = we::rotor_wrench(we::Vec4(T[0], T[1], T[2], T[3]), y, R, vp);
    EXPECT_LT((s.force_world - e.force_wall).norm(), tol) << trial;
    EXPECT_LT((s.torque_body - e.torque_body).norm(), tol) << trial;
    ++compared;
    // The specific force the estimator predicts is what DuctedQuad feeds the IMU
    // (without drag at v = 0): R^T T_W / m.
    we::WallState x;
    x.y = y;
    x.R = R;
    x.z = 1.0;
    const we::Vec3 a = we::predict_accel(x, we::Vec4(T[0], T[1], T[2], T[3]), vp);
    EXPECT_LT((a - R.transpose() * s.force_world / vp.mass).norm(), tol / vp.mass);
  }
  EXPECT_GT(compared, 300);
}

TEST(SimAgreement, FlowAndTofMatchTheSimulatorSensorModels) {
  ts::FlowParams fp;
  fp.noise_std = 0.0;
  ts::FlowModel flow(fp, 1);
  ts::RangeParams rp;
  rp.noise_std = 0.0;
  rp.noise_proportional = 0.0;
  ts::RangeModel tof(rp, 1);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    we::WallState x;
    x.y = 0.2;
    x.z = 0.5 + 0.4 * u(rng);
    x.v = we::Vec3(0.5 * u(rng), 0.5 * u(rng), 0.2 * u(rng));
    x.R = we::so3_exp(we::Vec3(0.2 * u(rng), 0.2 * u(rng), M_PI * u(rng)));
    x.omega = we::Vec3(u(rng), u(rng), u(rng));
    const ts::Quat q(x.R);
    const ts::FlowSample s = flow.sample(x.v, q, x.omega, x.z);
    ASSERT_TRUE(s.valid);
    const we::Vec2 n = we::predict_flow(x);
    EXPECT_NEAR(s.n_x, n.x(), 1e-12);
    EXPECT_NEAR(s.n_y, n.y(), 1e-12);
    EXPECT_NEAR(tof.true_range(x.z, q), we::predict_tof(x), 1e-12);
  }
}
