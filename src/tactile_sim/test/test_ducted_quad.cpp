// Ducted quadrotor (004): hover, external rotor commands, yaw drag torque,
// wall effect applied per rotor, wall truth, guard collisions, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <tuple>

#include "tactile_sim/ducted_quad.hpp"
#include "tactile_sim/sensors.hpp"

using namespace tactile_sim;

namespace {

constexpr double kDt = 0.001;

// A straight wall along x at y = 0 (normal +y towards the vehicle at y > 0).
Arena wall_arena() {
  Arena a;
  const int id = a.add_obstacle("wall");
  a.add_wall(Vec2(-5.0, 0.0), Vec2(5.0, 0.0), 0, id);
  return a;
}

RigidBodyState at(double x, double y, double z) {
  RigidBodyState s;
  s.position = Vec3(x, y, z);
  return s;
}

void run(DuctedQuad& q, const Arena& a, double seconds) {
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int k = 0; k < n; ++k) q.step(kDt, a);
}

}  // namespace

TEST(DuctedQuad, HoverThrustEqualsWeight) {
  DuctedQuadParams p;
  DuctedQuad q(p, at(0, 0, 1.0));
  Arena empty;
  PositionSetpoint sp;
  sp.position = Vec3(0, 0, 1.0);
  q.set_position_setpoint(sp);
  run(q, empty, 4.0);
  EXPECT_NEAR(q.collective_thrust(), 0.280 * 9.81, 0.001 * 0.280 * 9.81);
  EXPECT_NEAR(q.state().position.z(), 1.0, 0.005);
  EXPECT_NEAR(q.specific_force_body().z(), 9.81, 0.01);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q.rotor_thrusts()[i], 0.280 * 9.81 / 4, 1e-3);
  EXPECT_FALSE(q.wall_truth().present);
  EXPECT_NEAR(q.wall_truth().height, 1.0, 0.005);
}

TEST(DuctedQuad, TakesOffFromTheFloorAndReachesSetpoint) {
  DuctedQuad q(DuctedQuadParams{}, at(0, 0, 0));
  Arena empty;
  run(q, empty, 0.5);  // holds the floor position: stays on the floor
  EXPECT_NEAR(q.state().position.z(), 0.0, 1e-9);
  EXPECT_NEAR(q.specific_force_body().z(), 9.81, 1e-9);  // IMU on the floor reads +g
  PositionSetpoint sp;
  sp.position = Vec3(0.5, -0.3, 0.8);
  sp.yaw = 0.5;
  q.set_position_setpoint(sp);
  run(q, empty, 8.0);
  EXPECT_LT((q.state().position - sp.position).norm(), 0.01);
  EXPECT_NEAR(q.state().yaw(), 0.5, 0.01);
}

TEST(DuctedQuad, ExternalThrustsGiveAnalyticAccelerationAndYawTorque) {
  DuctedQuadParams p;
  p.motor_time_constant = 1e-5;  // motors follow within one step
  p.linear_drag = 0.0;
  DuctedQuad q(p, at(0, 0, 1.0));
  Arena empty;
  const double a = 0.8, d = 0.05;
  q.set_rotor_thrusts({a + d, a - d, a + d, a - d});
  q.step(kDt, empty);
  ASSERT_TRUE(q.external_control());
  // Vertical: m a_z = sum T - m g; yaw: J_zz w_z_dot = c_tau * sum s_i T_i = 0.01 * 4 d.
  EXPECT_NEAR(q.specific_force_body().z(), 4 * a / 0.280, 1e-6);
  EXPECT_NEAR(q.state().velocity.z(), (4 * a / 0.280 - 9.81) * kDt, 1e-8);
  EXPECT_NEAR(q.state().angular_velocity.z(), 0.01 * 4 * d / p.inertia_diag.z() * kDt, 1e-8);
  EXPECT_NEAR(q.state().angular_velocity.x(), 0.0, 1e-12);
  EXPECT_NEAR(q.state().angular_velocity.y(), 0.0, 1e-12);
  // Front rotors harder -> nose-up torque -r_x f: pitch negative about y... with
  // FLU: tau_y = sum(-r_x T_i) = -L(T0 + T1) + L(T2 + T3) < 0 for more front thrust.
  DuctedQuad q2(p, at(0, 0, 1.0));
  q2.set_rotor_thrusts({a + d, a + d, a - d, a - d});
  q2.step(kDt, empty);
  EXPECT_NEAR(q2.state().angular_velocity.y(), -p.rotor_offset * 4 * d / p.inertia_diag.y() * kDt, 1e-8);
  // Commands are clamped to [0, max].
  q2.set_rotor_thrusts({-1.0, 5.0, std::nan(""), 0.5});
  EXPECT_EQ(q2.rotor_commands()[0], 0.0);
  EXPECT_NEAR(q2.rotor_commands()[1], 0.44 * 9.81 / 4, 1e-12);
  EXPECT_EQ(q2.rotor_commands()[2], 0.0);
}

TEST(DuctedQuad, WallEffectPerRotorMatchesEq5NearAWall) {
  DuctedQuadParams p;
  p.motor_time_constant = 1e-5;
  DuctedQuad q(p, at(0.0, 0.15, 1.0));  // centre 15 cm from the wall, upright, yaw 0
  const Arena arena = wall_arena();
  const double T = 0.7;
  q.set_rotor_thrusts({T, T, T, T});
  q.step(kDt, arena);
  // Rotors 0, 3 at y = 0.15 - L (L = 0.082: d = 0.15 - 0.082 - R = 0.030);
  // rotors 1, 2 at y = 0.15 + L (d = 0.194).
  const double R = 0.038, L = p.rotor_offset;
  ASSERT_DOUBLE_EQ(L, 0.082);  // 004 geometry (docs/physics.md)
  const double dn = 0.15 - L - R, df = 0.15 + L - R;
  // (positions moved by one step of motion only: < 1e-5 m)
  EXPECT_NEAR(q.rotor_walls()[0].distance, dn, 1e-5);
  EXPECT_NEAR(q.rotor_walls()[3].distance, dn, 1e-5);
  EXPECT_NEAR(q.rotor_walls()[1].distance, df, 1e-5);
  EXPECT_TRUE(q.rotor_walls()[0].normal_world.isApprox(Vec3(0, 1, 0), 1e-12));
  const double gh = 2 * 0.21 * (std::pow(0.34, dn / R) + std::pow(0.34, df / R));
  const double gv = 2 * 0.06 * (std::pow(0.54, dn / R) + std::pow(0.54, df / R));
  EXPECT_NEAR(q.wall_force_world().y(), -gh * T, 1e-4);
  EXPECT_NEAR(q.wall_force_world().z(), gv * T, 1e-4);
  EXPECT_NEAR(q.wall_force_world().x(), 0.0, 1e-9);
  // The near rotors lift more: roll torque tau_x = sum r_y F_z < 0 (roll away from the wall)
  // -> angular velocity about x after one step: negative.
  EXPECT_LT(q.state().angular_velocity.x(), 0.0);
  // Wall truth: 15 cm, wall at body -y (direction -pi/2), height 1 m.
  const WallTruth t = q.wall_truth();
  ASSERT_TRUE(t.present);
  EXPECT_NEAR(t.distance, 0.15, 1e-4);
  EXPECT_NEAR(t.direction, -M_PI / 2, 1e-6);
  EXPECT_LT((t.direction_body - Vec3(0, -1, 0)).norm(), 1e-4);
  EXPECT_NEAR(t.height, 1.0, 1e-4);
  // Disabled: no wall force.
  p.wall_effect_enabled = false;
  DuctedQuad q0(p, at(0.0, 0.15, 1.0));
  q0.set_rotor_thrusts({T, T, T, T});
  q0.step(kDt, arena);
  EXPECT_LT(q0.wall_force_world().norm(), 1e-12);
}

TEST(DuctedQuad, HoldsNearTheWallAgainstTheAttraction) {
  // 004 flight: y_d = 18 cm from the wall. The position loop's integrator
  // must take up the wall attraction; no collision.
  DuctedQuad q(DuctedQuadParams{}, at(0.0, 0.18, 1.0));
  const Arena arena = wall_arena();
  PositionSetpoint sp;
  sp.position = Vec3(0.0, 0.18, 1.0);
  q.set_position_setpoint(sp);
  run(q, arena, 6.0);
  EXPECT_NEAR(q.state().position.y(), 0.18, 0.005);
  EXPECT_LT(q.wall_force_world().y(), -0.005);  // attraction present (~ -0.01 N)
  EXPECT_TRUE(q.take_collisions().empty());
}

TEST(DuctedQuad, WallCollisionIsLoggedOncePerImpact) {
  DuctedQuad q(DuctedQuadParams{}, at(0.0, 0.5, 0.8));
  const Arena arena = wall_arena();
  PositionSetpoint sp;
  sp.position = Vec3(0.0, -0.3, 0.8);  // behind the wall
  q.set_position_setpoint(sp);
  std::vector<CollisionEvent> all;
  for (int k = 0; k < 6000; ++k) {
    q.step(kDt, arena);
    for (auto& e : q.take_collisions()) {
      all.push_back(e);
      sp.position = Vec3(0.0, 0.5, 0.8);  // back off after the impact
      q.set_position_setpoint(sp);
    }
  }
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].part, "guard");
  EXPECT_TRUE(all[0].normal.isApprox(Vec2(0, 1), 1e-9));
  EXPECT_NEAR(all[0].point.y(), 0.0, 1e-9);
  EXPECT_GT(all[0].impact_speed, 0.1);
  EXPECT_EQ(all[0].obstacle_id, 0);
  EXPECT_GT(q.state().position.y(), 0.4);  // recovered
}

TEST(DuctedQuad, ContactForceIsReportedAsExternalForce) {
  DuctedQuadParams p;
  DuctedQuad q(p, at(0.0, 0.5, 0.8));
  const Arena arena = wall_arena();
  PositionSetpoint sp;
  sp.position = Vec3(0.0, 0.05, 0.8);  // presses the front guards into the wall
  q.set_position_setpoint(sp);
  run(q, arena, 5.0);
  // Pressing: the wall pushes +y; the guard centre is within guard_radius of y = 0.
  EXPECT_GT(q.external_force_world().y(), 0.05);
  EXPECT_NEAR(q.external_force_world().z(), 0.0, 1e-12);
}

TEST(DuctedQuad, DeterministicForTheSameInputs) {
  const Arena arena = wall_arena();
  auto go = [&]() {
    DuctedQuad q(DuctedQuadParams{}, at(0.1, 0.4, 0.0));
    PositionSetpoint sp;
    sp.position = Vec3(0.3, 0.1, 0.7);
    q.set_position_setpoint(sp);
    run(q, arena, 3.0);
    return q.state();
  };
  const RigidBodyState a = go(), b = go();
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.velocity, b.velocity);
  EXPECT_EQ(a.orientation.coeffs(), b.orientation.coeffs());
}

TEST(DuctedQuad, OnboardSensorsOnTheHoveringVehicle) {
  // IMU, ToF and flow fed from the vehicle truth while it hovers at 0.8 m:
  // IMU ~ (0, 0, 9.81) and zero rate, ToF ~ 0.8 m, flow ~ 0; the same seed
  // gives the same samples.
  auto fly = [](uint64_t seed) {
    DuctedQuad q(DuctedQuadParams{}, at(0, 0, 0.8));
    Arena empty;
    PositionSetpoint sp;
    sp.position = Vec3(0, 0, 0.8);
    q.set_position_setpoint(sp);
    run(q, empty, 2.0);
    ImuModel imu(ImuParams{}, seed);
    RangeModel tof(RangeParams{}, seed);
    FlowModel flow(FlowParams{}, seed);
    Vec3 acc = Vec3::Zero(), gyr = Vec3::Zero();
    double range = 0.0, height = 0.0, nx = 0.0, ny = 0.0;
    const int n = 500;
    for (int k = 0; k < n; ++k) {
      q.step(kDt, empty);
      const ImuSample s = imu.sample(q.specific_force_body(), q.state().angular_velocity);
      acc += s.accel / n;
      gyr += s.gyro / n;
      range += tof.sample(q.wall_truth().height, q.state().orientation) / n;
      height += q.wall_truth().height / n;
      const FlowSample f = flow.sample(q.state().velocity, q.state().orientation,
                                       q.state().angular_velocity, q.wall_truth().height);
      nx += f.n_x / n;
      ny += f.n_y / n;
    }
    return std::make_tuple(acc, gyr, range, nx, ny, height);
  };
  const auto [acc, gyr, range, nx, ny, height] = fly(3);
  EXPECT_LT((acc - Vec3(0, 0, 9.81)).norm(), 0.01);
  EXPECT_LT(gyr.norm(), 0.002);
  // ToF noise std 2 mm + 0.5 % of 0.8 m = 6 mm; mean of 500 within 5 sigma / sqrt(500).
  EXPECT_NEAR(range, height, 5 * 0.006 / std::sqrt(500.0));
  EXPECT_NEAR(height, 0.8, 0.01);
  EXPECT_NEAR(nx, 0.0, 0.005);
  EXPECT_NEAR(ny, 0.0, 0.005);
  const auto again = fly(3);
  EXPECT_EQ(std::get<0>(again), acc);
  EXPECT_EQ(std::get<2>(again), range);
  EXPECT_EQ(std::get<3>(again), nx);
  EXPECT_NE(std::get<2>(fly(4)), range);
}

TEST(DuctedQuad, ParamsValidate) {
  DuctedQuadParams p;
  p.mass = -1.0;
  EXPECT_THROW(DuctedQuad(p, RigidBodyState{}), std::invalid_argument);
  p = {};
  p.max_rotor_thrust = 0.5;  // 2 N < 2.75 N weight
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DuctedQuadParams.max_rotor_thrust"), std::string::npos);
  }
  p = {};
  p.wall_effect.b2 = 1.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  DuctedQuad q(DuctedQuadParams{}, RigidBodyState{});
  EXPECT_THROW(q.step(0.0, Arena{}), std::invalid_argument);
}

namespace {

/// Thrust and torque the rotor forces f produce (the rows of allocate_rotors' M).
Eigen::Vector4d wrench_of(const RotorGeometry& g, const std::array<double, 4>& f) {
  Eigen::Vector4d w = Eigen::Vector4d::Zero();
  for (int i = 0; i < 4; ++i) {
    const Vec3& r = g.position_body[i];
    w += f[i] * Eigen::Vector4d(1.0, r.y(), -r.x(), g.spin_sign[i] * g.torque_coefficient);
  }
  return w;
}

}  // namespace

TEST(Allocation, YawFirstKeepsRollAndPitchWhenTheYawDemandSaturates) {
  // XPLORER's rotors (0.2 m along the diagonals, c_tau 0.016 m, 8.125 N max
  // each) at the 11 N hover thrust: the yaw authority is 0.016 x 11 = 0.176
  // N m (two rotors at 5.5 N, two at 0). Demand 0.5 N m of yaw (an arm
  // pressed by a contact passes up to 0.68 N m) and 0.2 N m of roll.
  RotorGeometry g;
  g.torque_coefficient = 0.016;
  const double d = 0.2 / std::sqrt(2.0);
  g.position_body = {Vec3(d, -d, 0), Vec3(d, d, 0), Vec3(-d, d, 0), Vec3(-d, -d, 0)};
  const double T = 11.0, max = 8.125;
  const Vec3 torque(0.2, 0.0, 0.5);
  // One factor for every axis: the roll torque shrinks with the yaw's.
  const Eigen::Vector4d all = wrench_of(g, allocate_rotors(g, T, torque, max, TorqueDesaturation::kScaleAll));
  EXPECT_NEAR(all[0], T, 1e-9);
  EXPECT_LT(all[1], 0.5 * torque.x());
  EXPECT_NEAR(all[1] / torque.x(), all[3] / torque.z(), 1e-9);  // direction kept
  // Roll/pitch first (PX4's mixer order): the full roll torque, yaw in what is left.
  const Eigen::Vector4d yf = wrench_of(g, allocate_rotors(g, T, torque, max, TorqueDesaturation::kYawFirst));
  EXPECT_NEAR(yf[0], T, 1e-9);
  EXPECT_NEAR(yf[1], torque.x(), 1e-9);
  EXPECT_NEAR(yf[2], 0.0, 1e-9);
  EXPECT_GT(yf[3], 0.1);
  EXPECT_LT(yf[3], 0.176 + 1e-9);
  // Within the rotors' authority both rules give the demanded wrench.
  const Vec3 small(0.1, -0.05, 0.05);
  for (auto mode : {TorqueDesaturation::kScaleAll, TorqueDesaturation::kYawFirst}) {
    const Eigen::Vector4d w = wrench_of(g, allocate_rotors(g, T, small, max, mode));
    EXPECT_NEAR(w[1], small.x(), 1e-9);
    EXPECT_NEAR(w[2], small.y(), 1e-9);
    EXPECT_NEAR(w[3], small.z(), 1e-9);
  }
  // The default is the ducted quadrotor's rule, unchanged.
  EXPECT_EQ(CascadedControllerParams{}.desaturation, TorqueDesaturation::kScaleAll);
  CascadedControllerParams p;
  p.desaturation = static_cast<TorqueDesaturation>(7);
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("CascadedControllerParams.desaturation"), std::string::npos);
  }
}
