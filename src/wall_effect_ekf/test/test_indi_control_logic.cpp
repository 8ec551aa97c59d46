// INDI controller node logic and the 004 setpoint scripts.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "wall_effect_ekf/indi_control_logic.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"

using namespace wall_effect_ekf;
using tactile_common::ParamMap;

TEST(IndiControlLogic, HoversAtTheOdometryPoseAndCountsBadInput) {
  IndiControlLogic logic(IndiControlLogic::params_from(IndiControlLogic::default_parameters()));
  EXPECT_FALSE(logic.on_timer(0).has_value());  // no odometry / IMU yet
  nav_msgs::msg::Odometry o;
  o.pose.pose.orientation.w = 1.0;
  o.pose.pose.position.z = 1.0;
  o.child_frame_id = "cf1/base_link";
  logic.on_odometry(o);
  sensor_msgs::msg::Imu imu;
  imu.orientation.w = 1.0;
  imu.linear_acceleration.z = kGravity;
  logic.on_imu(imu);
  const auto out = logic.on_timer(0);
  ASSERT_TRUE(out.has_value());
  ASSERT_EQ(out->rotor_thrust.size(), 4u);
  EXPECT_EQ(out->header.frame_id, "cf1/base_link");  // the odometry's body frame
  EXPECT_NEAR(out->total_thrust, 0.28 * kGravity, 1e-9);  // hover: T0 = m g, no torque
  for (double t : out->rotor_thrust) EXPECT_NEAR(t, 0.28 * kGravity / 4, 1e-9);
  imu.linear_acceleration.x = NAN;
  logic.on_imu(imu);
  nav_msgs::msg::Odometry sp;
  sp.pose.pose.orientation.w = 0.0;  // not a rotation
  logic.on_setpoint(sp);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 2u);
  const auto stale = logic.on_timer(500'000'000);  // stale IMU: motors stopped on purpose, not silence
  ASSERT_TRUE(stale.has_value());
  EXPECT_EQ(stale->total_thrust, 0.0);
  EXPECT_EQ(logic.state(), IndiFailsafeState::kMotorsStopped);
}

TEST(IndiControlLogic, NanPositionAxesAreVelocityOnly) {
  IndiControlLogic logic(IndiControlLogic::params_from(IndiControlLogic::default_parameters()));
  nav_msgs::msg::Odometry sp;
  sp.pose.pose.orientation.w = 1.0;
  sp.pose.pose.position.x = NAN;
  sp.pose.pose.position.y = 0.02;
  sp.twist.twist.linear.x = 0.25;
  logic.on_setpoint(sp);
  nav_msgs::msg::Odometry o;
  o.pose.pose.orientation.w = 1.0;
  logic.on_odometry(o);
  sensor_msgs::msg::Imu imu;
  imu.orientation.w = 1.0;
  imu.linear_acceleration.z = kGravity;
  logic.on_imu(imu);
  ASSERT_TRUE(logic.on_timer(0).has_value());
  const auto& a = logic.controller().last_outer().accel_target;
  const IndiParams ip;
  EXPECT_NEAR(a.x(), ip.k_d.x() * 0.25, 1e-12);        // no position term on x
  EXPECT_NEAR(a.y(), ip.k_p.y() * 0.02 + ip.k_i.y() * 0.02 * 0.01, 1e-12);  // position term on y
}

TEST(WallFrame, DirectionToTheWallBecomesMinusYw) {
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3::UnitZ()).toRotationMatrix();
  const Mat3 W = wall_frame_attitude(R, -M_PI / 2);  // wall on the right
  // In the wall frame the body direction to the wall is -e2.
  const Vec3 u = W * Vec3(0.0, -1.0, 0.0);
  EXPECT_NEAR(u.y(), -1.0, 1e-12);
  EXPECT_NEAR(W.determinant(), 1.0, 1e-12);
}

TEST(Trajectory, EstimationFlightProtocolOf004) {
  const TrajectoryParams p;
  EXPECT_NEAR(trajectory_setpoint(p, 1.0).position.y(), 0.4, 1e-12);   // take-off ~40 cm
  EXPECT_NEAR(trajectory_setpoint(p, 10.0).position.y(), 0.18, 1e-12);
  EXPECT_NEAR(trajectory_setpoint(p, 10.0).position.z(), 1.0, 1e-12);
  const double t = 25.0 + M_PI / 2;  // 0.18 - 0.03 sin(t - 25)
  EXPECT_NEAR(trajectory_setpoint(p, t).position.y(), 0.15, 1e-12);
  EXPECT_NEAR(trajectory_setpoint(p, 25.0).velocity.y(), -0.03, 1e-12);
  EXPECT_NEAR(trajectory_setpoint(p, 40.0).yaw, 0.0, 1e-12);
  EXPECT_NEAR(trajectory_setpoint(p, 46.0).yaw, -M_PI / 4, 1e-12);
  EXPECT_NEAR(trajectory_setpoint(p, 60.0).yaw, -M_PI / 2, 1e-12);
  EXPECT_NEAR(std::abs(trajectory_setpoint(p, 79.0).yaw), M_PI, 1e-9);
  TrajectoryParams s;
  s.mode = "sweep";
  EXPECT_EQ(sweep_segment(s, 4.0), -1);
  EXPECT_EQ(sweep_segment(s, 5.0 + 60.0 * 3 + 1.0), 3);
  EXPECT_NEAR(trajectory_setpoint(s, 5.0 + 60.0 * 3 + 1.0).position.y(), 0.16, 1e-12);
  EXPECT_EQ(sweep_segment(s, 5.0 + 60.0 * 11 + 1.0), -1);
  auto m = WallTrajectoryLogic::default_parameters();
  m.set("mode", std::string("zigzag"));
  EXPECT_THROW(WallTrajectoryLogic::params_from(m), tactile_common::ParamError);
}

// The trajectory's positions and velocity are tracked with the odometry: odom (REP 105),
// behind frame_prefix for one of several vehicles (they were labelled map).
TEST(WallTrajectory, SetpointsAreInThePrefixedOdomFrame) {
  auto m = WallTrajectoryLogic::default_parameters();
  EXPECT_EQ(WallTrajectoryLogic(WallTrajectoryLogic::params_from(m)).on_timer(0).header.frame_id, "odom");
  m.set("frame_prefix", std::string("cf1/"));
  const auto sp = WallTrajectoryLogic(WallTrajectoryLogic::params_from(m)).on_timer(0);
  EXPECT_EQ(sp.header.frame_id, "cf1/odom");
  EXPECT_EQ(sp.child_frame_id, "cf1/odom");  // the twist is a world velocity
  m.set("frame_prefix", std::string("/cf1/"));
  try {
    WallTrajectoryLogic::params_from(m);
    FAIL() << "accepted frame_prefix /cf1/";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("frame_prefix"), std::string::npos) << e.what();
  }
}

// x, angular_frequency and yaw_deg go into the setpoint unchecked: a NaN x made the
// position along the wall NaN, which the INDI controller takes as a velocity-only axis (no
// position hold along the wall); a NaN frequency or yaw made y_d or psi_d NaN. Each must be
// finite, and the error names the key.
TEST(WallTrajectory, NonFiniteXFrequencyOrYawIsRefusedNamingTheKey) {
  const double inf = std::numeric_limits<double>::infinity();
  for (const std::string key : {"x", "angular_frequency", "yaw_deg"}) {
    for (const double v : {std::numeric_limits<double>::quiet_NaN(), inf, -inf}) {
      auto m = WallTrajectoryLogic::default_parameters();
      m.set(key, v);
      try {
        WallTrajectoryLogic::params_from(m);
        ADD_FAILURE() << key << " = " << v << " accepted";
      } catch (const tactile_common::ParamError& e) {
        EXPECT_NE(std::string(e.what()).find("wall_trajectory.ros__parameters." + key + ": "), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("must be finite"), std::string::npos) << e.what();
      }
    }
  }
}

namespace {
void expect_config_equals_defaults(const std::string& file, const std::string& node, const tactile_common::ParamMap& d) {
  const auto f = tactile_common::load_node_parameters(file, node, d);
  for (const auto& [key, value] : d.values()) {
    EXPECT_EQ(f.origin(key), file) << key << " not set in " << file;
    EXPECT_TRUE(value == f.values().at(key)) << key;
  }
}
}  // namespace

TEST(RepoConfig, IndiControllerAndWallTrajectoryEqualDefaults) {
  expect_config_equals_defaults("../../config/indi_controller.yaml", "/indi_controller",
                                IndiControlLogic::default_parameters());
  expect_config_equals_defaults("../../config/wall_trajectory.yaml", "/wall_trajectory",
                                WallTrajectoryLogic::default_parameters());
}

// Issue 35 item 5: every key has a description, a unit and the range validate() takes
// for it alone (none wider: range_leaks), and none is live (the components apply none).
TEST(IndiControlLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = IndiControlLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak : tactile_common::range_leaks(d, [](const ParamMap& m) { IndiControlLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& inf :
       tactile_common::infinities_accepted(d, [](const ParamMap& m) { IndiControlLogic::params_from(m); })) {
    ADD_FAILURE() << inf.key << " = " << inf.value << " is accepted, its described range says finite";
  }
  ASSERT_NE(d.info("max_tilt"), nullptr);
  EXPECT_EQ(d.info("max_tilt")->range->text(), "(0, 1)");
  EXPECT_EQ(d.info("max_tilt")->unit, "rad");
  EXPECT_EQ(d.info("vehicle.max_rotor_thrust")->unit, "N");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(WallTrajectory, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = WallTrajectoryLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const ParamMap& m) { WallTrajectoryLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& inf :
       tactile_common::infinities_accepted(d, [](const ParamMap& m) { WallTrajectoryLogic::params_from(m); })) {
    ADD_FAILURE() << inf.key << " = " << inf.value << " is accepted, its described range says finite";
  }
  ASSERT_NE(d.info("amplitude"), nullptr);
  EXPECT_EQ(d.info("amplitude")->range->text(), "[0, inf)");
  EXPECT_EQ(d.info("x")->range->text(), "(-inf, inf)");  // any finite value
  EXPECT_EQ(d.info("t_yaw2")->range->text(), "[0, inf]");  // inf: no second ramp
  EXPECT_EQ(d.info("sweep_hold_s")->range->text(), "(0, inf)");
  EXPECT_EQ(d.info("yaw_deg")->unit, "deg");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

// --- The fail-safe on stale odometry / IMU ---------------------------------------------

namespace {

constexpr int64_t kMs = 1'000'000;
const double kHover = 0.28 * kGravity;  // m g of the default vehicle [N]

nav_msgs::msg::Odometry odometry_at(int64_t t_ns, double z = 1.0) {
  nav_msgs::msg::Odometry o;
  o.pose.pose.orientation.w = 1.0;
  o.pose.pose.position.z = z;
  tactile_common::to_stamp(t_ns, o.header.stamp);
  return o;
}

/// Level IMU at rest / in steady flight (a_m = +g), or rolled by `roll` [rad].
sensor_msgs::msg::Imu imu_at(int64_t t_ns, double roll = 0.0, double accel_z = kGravity) {
  sensor_msgs::msg::Imu m;
  m.orientation.w = std::cos(roll / 2);
  m.orientation.x = std::sin(roll / 2);
  m.linear_acceleration.z = accel_z;
  tactile_common::to_stamp(t_ns, m.header.stamp);
  return m;
}

IndiControlLogic::Params default_params() {
  return IndiControlLogic::params_from(IndiControlLogic::default_parameters());
}

/// Hovers on odometry + IMU for 0.1 s (NOMINAL; the odometry goes stale at 202 ms), then
/// only the IMU comes (every 2 ms) until `until_ns`: at rest on the floor (a_m = g), or in
/// the air (`air`: the specific force of the commanded thrust, m a_m = T0); returns the last command.
std::optional<tactile_msgs::msg::ThrustCommand> lose_odometry(IndiControlLogic& l, int64_t until_ns,
                                                              double roll = 0.0, bool air = false) {
  std::optional<tactile_msgs::msg::ThrustCommand> out;
  for (int64_t t = 0; t <= until_ns; t += 2 * kMs) {
    if (t <= 100 * kMs) l.on_odometry(odometry_at(t));
    const bool lost = t > 100 * kMs;
    l.on_imu(imu_at(t, lost ? roll : 0.0, lost && air ? l.controller().last_outer().thrust / 0.28 : kGravity));
    out = l.on_timer(t);
  }
  return out;
}

}  // namespace

TEST(IndiFailsafeGuards, InputsReadyOnlyWithBothFresh) {
  using indi_guards::InputAges;
  EXPECT_TRUE(indi_guards::inputs_ready(InputAges{true, true, 0.05, 0.1}, 0.1));
  EXPECT_FALSE(indi_guards::inputs_ready(InputAges{false, true, 0.0, 0.0}, 0.1));   // no odometry yet
  EXPECT_FALSE(indi_guards::inputs_ready(InputAges{true, false, 0.0, 0.0}, 0.1));   // no IMU yet
  EXPECT_FALSE(indi_guards::inputs_ready(InputAges{true, true, 0.11, 0.0}, 0.1));   // stale odometry
  EXPECT_FALSE(indi_guards::inputs_ready(InputAges{true, true, 0.0, 0.11}, 0.1));   // stale IMU
  // An age of exactly max_input_age_s is fresh, also through integer nanoseconds
  // (to_seconds(300 ms) = 0.30000000000000004).
  const double age = tactile_common::to_seconds(300'000'000);
  EXPECT_TRUE(indi_guards::inputs_ready(InputAges{true, true, age, age}, 0.3));
}

TEST(IndiFailsafeGuards, ImuLostWhenMissingOrStaleWhateverTheOdometry) {
  using indi_guards::InputAges;
  EXPECT_FALSE(indi_guards::imu_lost(InputAges{true, true, 0.0, 0.1}, 0.1));
  EXPECT_FALSE(indi_guards::imu_lost(InputAges{true, true, 5.0, 0.0}, 0.1));  // odometry is another guard's
  EXPECT_TRUE(indi_guards::imu_lost(InputAges{true, true, 0.0, 0.11}, 0.1));
  EXPECT_TRUE(indi_guards::imu_lost(InputAges{true, false, 0.0, 0.0}, 0.1));
}

TEST(IndiFailsafeGuards, OdometryLostOnlyWithAFreshImu) {
  using indi_guards::InputAges;
  EXPECT_TRUE(indi_guards::odometry_lost(InputAges{true, true, 0.11, 0.0}, 0.1));
  EXPECT_FALSE(indi_guards::odometry_lost(InputAges{true, true, 0.1, 0.0}, 0.1));   // still fresh
  EXPECT_FALSE(indi_guards::odometry_lost(InputAges{true, true, 0.11, 0.11}, 0.1)); // both: the IMU guard
}

TEST(IndiFailsafeGuards, TouchdownIsLowThrustAtRest) {
  const double m = 0.28;
  EXPECT_TRUE(indi_guards::touchdown(0.4 * m * kGravity, Vec3(0.1, 0.0, -0.2), m));   // floor carries it
  EXPECT_FALSE(indi_guards::touchdown(0.6 * m * kGravity, Vec3::Zero(), m));          // steady descent / hover
  EXPECT_FALSE(indi_guards::touchdown(0.4 * m * kGravity, Vec3(0, 0, -0.6 * kGravity), m));  // falling in the air
  EXPECT_FALSE(indi_guards::touchdown(0.0, Vec3(0, 0, 3.0), m));                       // impact spike: not rest yet
}

TEST(IndiFailsafeGuards, BelowFloorOnlyPastTheMargin) {
  EXPECT_FALSE(indi_guards::below_floor(-0.09, 0.0));
  EXPECT_TRUE(indi_guards::below_floor(-0.11, 0.0));
  EXPECT_TRUE(indi_guards::below_floor(0.89, 1.0));  // a floor at z = 1 m in the odometry frame
}

TEST(IndiFailsafeGuards, FloorProbeRampsTheThrustLinearlyToZero) {
  EXPECT_DOUBLE_EQ(indi_guards::floor_probe_thrust(2.0, 0.0), 2.0);
  EXPECT_DOUBLE_EQ(indi_guards::floor_probe_thrust(2.0, indi_guards::kFloorProbeRampS / 2), 1.0);
  EXPECT_DOUBLE_EQ(indi_guards::floor_probe_thrust(2.0, indi_guards::kFloorProbeRampS), 0.0);
  EXPECT_DOUBLE_EQ(indi_guards::floor_probe_thrust(2.0, 2.0 * indi_guards::kFloorProbeRampS), 0.0);  // stays 0
}

TEST(IndiFailsafeGuards, AirborneInProbeOnlyOnAClearDownwardAcceleration) {
  EXPECT_TRUE(indi_guards::airborne_in_probe(Vec3(0, 0, -2.1)));
  EXPECT_FALSE(indi_guards::airborne_in_probe(Vec3(0, 0, -1.9)));
  EXPECT_FALSE(indi_guards::airborne_in_probe(Vec3(0, 0, 0.0)));   // at rest on the floor
  EXPECT_FALSE(indi_guards::airborne_in_probe(Vec3(5.0, 0, 3.0)));  // horizontal or impact: not a fall
}

TEST(IndiFailsafeGuards, DescentTimesOutAtTheBound) {
  EXPECT_FALSE(indi_guards::descent_timed_out(9.99, 10.0));
  EXPECT_TRUE(indi_guards::descent_timed_out(10.0, 10.0));
}

TEST(IndiFailsafeGuards, CrashedBeforeLossWithinTheMemory) {
  EXPECT_TRUE(indi_guards::crashed_before_loss(0.0));
  EXPECT_TRUE(indi_guards::crashed_before_loss(1.0));
  EXPECT_FALSE(indi_guards::crashed_before_loss(1.01));
}

TEST(IndiFailsafeGuards, CrashAttitudeBeyondSixtyDegreesFromTheVertical) {
  auto rolled = [](double deg) { return Mat3(Eigen::AngleAxisd(deg * M_PI / 180.0, Vec3::UnitX())); };
  EXPECT_FALSE(indi_guards::crash_attitude(Mat3::Identity()));
  EXPECT_FALSE(indi_guards::crash_attitude(rolled(59.0)));
  EXPECT_TRUE(indi_guards::crash_attitude(rolled(61.0)));
  EXPECT_TRUE(indi_guards::crash_attitude(rolled(180.0)));  // upside down
  // Pitch 45 deg and roll 45 deg together: the body z axis 60 deg from the vertical (cos = 1/2).
  const Mat3 both = Mat3(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitY())) * Mat3(Eigen::AngleAxisd(M_PI / 4.0 + 0.02, Vec3::UnitX()));
  EXPECT_TRUE(indi_guards::crash_attitude(both));
}

// Before the first odometry + IMU nothing is sent (on the ground, motors idle), as before.
TEST(IndiFailsafe, NothingIsSentBeforeTheFirstFreshOdometryAndImu) {
  IndiControlLogic l(default_params());
  EXPECT_FALSE(l.on_timer(0).has_value());
  l.on_odometry(odometry_at(0));
  EXPECT_FALSE(l.on_timer(2 * kMs).has_value());  // no IMU yet
  l.on_imu(imu_at(-500 * kMs));                   // an old IMU sample: stale
  EXPECT_FALSE(l.on_timer(4 * kMs).has_value());
  EXPECT_EQ(l.state(), IndiFailsafeState::kWaitingForInput);
  EXPECT_EQ(l.stats().ticks_without_input, 3u);
  EXPECT_EQ(l.stats().published, 0u);
  l.on_imu(imu_at(6 * kMs));
  EXPECT_TRUE(l.on_timer(6 * kMs).has_value());
  EXPECT_EQ(l.state(), IndiFailsafeState::kNominal);
  EXPECT_EQ(l.stats().ticks_nominal, 1u);
}

// Odometry stale, IMU fresh: a command every tick, a level descent below hover thrust.
TEST(IndiFailsafe, OdometryLossFliesALevelDescentBelowHoverEveryTick) {
  IndiControlLogic l(default_params());
  const auto out = lose_odometry(l, 400 * kMs, 0.0, true);
  EXPECT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  EXPECT_STREQ(l.stats().reason, "odometry stale: descent on the IMU");
  EXPECT_EQ(l.stats().published, 201u);  // every tick from t = 0 to 400 ms: never nullopt once flying
  EXPECT_GT(l.stats().ticks_odometry_lost, 0u);
  EXPECT_EQ(l.stats().ticks_nominal + l.stats().ticks_odometry_lost, 201u);
  ASSERT_TRUE(out.has_value());
  EXPECT_LT(out->total_thrust, kHover);  // descending: the estimate (0 m/s) is slower than 0.25 m/s down
  EXPECT_GT(out->total_thrust, 0.0);
  for (double f : out->rotor_thrust) EXPECT_NEAR(f, out->total_thrust / 4, 1e-9);  // level, no torque
  EXPECT_LT(l.stats().vertical_speed_estimate, -0.05);  // descending, not yet at 0.25 m/s
  EXPECT_GT(l.stats().vertical_speed_estimate, -0.25);
  // Odometry again before touchdown: the descent is terminal (README).
  l.on_odometry(odometry_at(402 * kMs));
  l.on_imu(imu_at(402 * kMs));
  l.on_timer(402 * kMs);
  EXPECT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  EXPECT_EQ(l.stats().odometry_ignored, 1u);
}

// The descent holds the horizontal velocity at 0 on the IMU: a measured 1.5 m/s^2 along x
// (the wall's pull, say) for 0.2 s is 0.3 m/s, braked by K_d (eq. 26 velocity-only) with a
// pitch rate that tilts the thrust against it (eq. 33); nothing on y.
TEST(IndiFailsafe, OdometryLossHoldsTheHorizontalVelocityOnTheImu) {
  IndiControlLogic l(default_params());
  lose_odometry(l, 100 * kMs);
  for (int64_t t = 102 * kMs; t <= 300 * kMs; t += 2 * kMs) {
    auto imu = imu_at(t);
    imu.linear_acceleration.x = 1.5;
    l.on_imu(imu);
    l.on_timer(t);
  }
  ASSERT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  const auto& o = l.controller().last_outer();  // the outer loop ran at 300 ms (100 Hz)
  EXPECT_NEAR(o.accel_target.x(), -IndiParams().k_d.x() * 0.3, 1e-6);
  EXPECT_NEAR(o.accel_target.y(), 0.0, 1e-12);
  EXPECT_LT(o.rate_y, 0.0);
  EXPECT_NEAR(o.rate_x, 0.0, 1e-12);
}

// The IMU integrates the vertical speed from the last odometry's: a measured 1.5 m/s^2 down
// for 0.3 s is 0.45 m/s down, and the descent loop then asks for an upward acceleration.
TEST(IndiFailsafe, OdometryLossIntegratesTheVerticalSpeedFromTheImu) {
  IndiControlLogic l(default_params());
  lose_odometry(l, 100 * kMs);
  for (int64_t t = 102 * kMs; t <= 400 * kMs; t += 2 * kMs) {
    l.on_imu(imu_at(t, 0.0, kGravity - 1.5));
    l.on_timer(t);
  }
  EXPECT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  EXPECT_NEAR(l.stats().vertical_speed_estimate, -0.45, 1e-6);
  EXPECT_GT(l.controller().last_outer().accel_target.z(), 0.0);  // faster than 0.25 m/s: brake
}

// The accelerometer bias update of one odometry interval, by hand: the IMU integrated
// 0.002 m/s more than the odometry saw over 10 ms, a residual of 0.2 m/s^2 on world z; gain
// 0.01 s / 2 s = 0.005. Rolled -90 deg about x, world z is body -y (R^T e_z = (0, -1, 0)).
TEST(IndiAccelBias, UpdateBlendsTheBodyFrameResidualWithGainDtOverTau) {
  const Vec3 b0(0.01, 0.0, 0.0);
  const auto b = accel_bias_update(b0, Vec3(0, 0, 0.102), Vec3(0, 0, 0.1), 0.01, Mat3::Identity(), 2.0);
  ASSERT_TRUE(b);
  EXPECT_NEAR(b->x(), 0.01, 1e-12);
  EXPECT_NEAR(b->z(), 0.005 * 0.2, 1e-12);
  const Mat3 roll = Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  const auto br = accel_bias_update(Vec3::Zero(), Vec3(0, 0, 0.002), Vec3::Zero(), 0.01, roll, 2.0);
  ASSERT_TRUE(br);
  EXPECT_NEAR(br->y(), -0.005 * 0.2, 1e-12);
  EXPECT_NEAR(br->z(), 0.0, 1e-12);
  // dt longer than tau: gain 1, the whole residual is added to the estimate, within the bound.
  const auto bl = accel_bias_update(b0, Vec3(0.3, 0, 0), Vec3::Zero(), 1.0, Mat3::Identity(), 0.5);
  ASSERT_TRUE(bl);
  EXPECT_NEAR(bl->x(), 0.31, 1e-12);
}

TEST(IndiAccelBias, TheEstimateIsBoundedAndAResidualBeyondTheGateIsSkipped) {
  // A residual within the gate pushing past the bound: clamped to +-kMaxAccelBias.
  const auto b = accel_bias_update(Vec3(0.99, -0.99, 0), Vec3(0.019, -0.019, 0), Vec3::Zero(), 0.01,
                                   Mat3::Identity(), 0.01);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->x(), kMaxAccelBias);
  EXPECT_EQ(b->y(), -kMaxAccelBias);
  // A 1 ms wall contact the IMU missed: 0.05 m/s in 10 ms is 5 m/s^2, beyond the gate.
  EXPECT_FALSE(accel_bias_update(Vec3::Zero(), Vec3::Zero(), Vec3(0.05, 0, 0), 0.01, Mat3::Identity(), 2.0));
  EXPECT_FALSE(accel_bias_update(Vec3::Zero(), Vec3(NAN, 0, 0), Vec3::Zero(), 0.01, Mat3::Identity(), 2.0));
  EXPECT_TRUE(accel_bias_update(Vec3::Zero(), Vec3(0.0199, 0, 0), Vec3::Zero(), 0.01, Mat3::Identity(), 2.0));
}

// The logic learns a constant accelerometer bias while the odometry flows (vehicle at rest:
// odometry velocity 0, the IMU reads g + 0.3 m/s^2 on z), and the ODOMETRY_LOST dead
// reckoning subtracts it: over the 0.4 s from the last odometry the vertical speed estimate
// stays ~0 (without the estimate it would read +0.12 m/s: the loop would descend 0.12 m/s
// faster). Odometry coming back in the descent is ignored and leaves the estimate as it was.
TEST(IndiAccelBias, ALearnedBiasIsSubtractedInTheDescent) {
  IndiControlLogic::Params p = default_params();
  IndiControlLogic l(p);
  constexpr double kBias = 0.3;
  int64_t t = 0;
  for (; t <= 20'000 * kMs; t += 2 * kMs) {  // 20 s of odometry at 100 Hz, IMU at 500 Hz
    if (t % (10 * kMs) == 0) l.on_odometry(odometry_at(t));
    l.on_imu(imu_at(t, 0.0, kGravity + kBias));
    l.on_timer(t);
  }
  EXPECT_NEAR(l.stats().accel_bias.z(), kBias, 1e-3);  // 20 s = 10 tau
  EXPECT_NEAR(l.stats().accel_bias.x(), 0.0, 1e-9);
  EXPECT_GT(l.stats().accel_bias_updates, 1900u);
  EXPECT_EQ(l.stats().accel_bias_gated, 0u);
  const int64_t lost_at = t;
  for (; t <= lost_at + 400 * kMs; t += 2 * kMs) {
    l.on_imu(imu_at(t, 0.0, kGravity + kBias));
    l.on_timer(t);
  }
  ASSERT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  EXPECT_NEAR(l.stats().vertical_speed_estimate, 0.0, 1e-3);
  const Vec3 frozen = l.stats().accel_bias;
  auto back = odometry_at(t);
  back.twist.twist.linear.z = 1.0;  // would be a residual of -100 m/s^2
  l.on_odometry(back);
  EXPECT_EQ(l.stats().odometry_ignored, 1u);
  EXPECT_EQ(l.stats().accel_bias, frozen);
}

// An odometry interval the IMU did not cover (no IMU sample in it, or an IMU window more
// than twice the interval) teaches nothing: the residual would be the odometry's whole
// velocity change (1 m/s^2 here, within the gate). A duplicate or older odometry is dropped
// and counted (it would restart the IMU integrals).
TEST(IndiAccelBias, NoUpdateOnAnIntervalTheImuDidNotCover) {
  IndiControlLogic l(default_params());
  l.on_imu(imu_at(0));
  l.on_odometry(odometry_at(0));
  auto o = odometry_at(10 * kMs);
  o.twist.twist.linear.x = 0.01;
  l.on_odometry(o);  // no IMU sample since the last odometry
  for (int64_t t = 2 * kMs; t <= 30 * kMs; t += 2 * kMs) l.on_imu(imu_at(t));  // 30 ms of IMU
  l.on_odometry(odometry_at(20 * kMs));  // a 10 ms interval, 30 ms integrated
  EXPECT_EQ(l.stats().accel_bias_updates, 0u);
  EXPECT_EQ(l.stats().accel_bias_gated, 0u);
  EXPECT_EQ(l.stats().accel_bias, Vec3::Zero());
  l.on_odometry(odometry_at(20 * kMs));  // duplicate
  l.on_odometry(odometry_at(15 * kMs));  // older
  EXPECT_EQ(l.stats().dropped_out_of_order, 2u);
  EXPECT_EQ(l.stats().odometry, 5u);
}

// On the floor the IMU measures rest while the loop asks for the descent: the thrust winds
// down below m g / 2, and after touchdown_confirm_s the motors stop (zeros, every tick, terminal).
TEST(IndiFailsafe, TouchdownStopsTheMotors) {
  IndiControlLogic l(default_params());
  lose_odometry(l, 2000 * kMs);
  EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
  EXPECT_STREQ(l.stats().reason, "touchdown: low thrust at rest for touchdown_confirm_s");
  const double since = tactile_common::to_seconds(l.stats().state_since_ns);
  EXPECT_GT(since, 0.202 + 0.5);  // the land detector held touchdown_confirm_s
  EXPECT_LT(since, 1.0);
  for (int64_t t = 2002 * kMs; t < 2010 * kMs; t += 2 * kMs) {
    l.on_odometry(odometry_at(t));  // fresh inputs again: still stopped
    l.on_imu(imu_at(t));
    const auto out = l.on_timer(t);
    ASSERT_TRUE(out.has_value());
    ASSERT_EQ(out->rotor_thrust.size(), 4u);
    for (double f : out->rotor_thrust) EXPECT_EQ(f, 0.0);
    EXPECT_EQ(out->total_thrust, 0.0);
  }
  EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
  EXPECT_GT(l.stats().ticks_motors_stopped, 4u);
}

// A crash in the descent: the IMU's attitude 70 deg from the vertical. Held 0.3 s, the
// motors stop (reason 85); a tilt that comes back under 60 deg before that does not.
TEST(IndiFailsafe, ACrashAttitudeHeldInTheDescentStopsTheMotors) {
  IndiControlLogic l(default_params());
  lose_odometry(l, 300 * kMs, 0.0, true);
  ASSERT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  const double tilt = 70.0 * M_PI / 180.0;
  int64_t t = 302 * kMs;
  for (; t <= 500 * kMs; t += 2 * kMs) {  // 0.2 s tilted, then level again
    l.on_imu(imu_at(t, tilt, kGravity));
    l.on_timer(t);
  }
  for (; t <= 600 * kMs; t += 2 * kMs) {
    l.on_imu(imu_at(t));
    l.on_timer(t);
  }
  ASSERT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  const int64_t tilted_at = t;
  for (; t <= tilted_at + 400 * kMs; t += 2 * kMs) {
    l.on_imu(imu_at(t, tilt, kGravity));
    l.on_timer(t);
  }
  EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
  EXPECT_EQ(l.stats().reason_code, IndiReason::kCrashed);
  EXPECT_NEAR(tactile_common::to_seconds(l.stats().state_since_ns - tilted_at), indi_guards::kCrashConfirmS, 0.003);
}

// A crash just before the loss (NOMINAL, 70 deg for 20 ms at 150 ms, then upright): the
// descent would start from a fall's velocity, so the loss stops the motors instead
// (NOMINAL -> MOTORS_STOPPED, 85; no descent tick). The same crash 1.15 s before the loss:
// the descent flies.
TEST(IndiFailsafe, ACrashInTheSecondBeforeTheLossStopsTheMotorsAtTheLoss) {
  auto fly = [](int64_t crash_at_ns, int64_t lost_after) {  // odometry until lost_after, stale 0.1 s later
    IndiControlLogic l(default_params());
    for (int64_t t = 0; t <= lost_after + 200 * kMs; t += 2 * kMs) {
      if (t <= lost_after && t % (10 * kMs) == 0) l.on_odometry(odometry_at(t));
      const bool tilted = t >= crash_at_ns && t < crash_at_ns + 20 * kMs;
      l.on_imu(imu_at(t, tilted ? 70.0 * M_PI / 180.0 : 0.0));
      l.on_timer(t);
    }
    return l.stats();
  };
  const auto recent = fly(150 * kMs, 200 * kMs);
  EXPECT_EQ(recent.state, IndiFailsafeState::kMotorsStopped);
  EXPECT_EQ(recent.reason_code, IndiReason::kCrashed);
  EXPECT_EQ(recent.previous, IndiFailsafeState::kNominal);
  EXPECT_EQ(recent.ticks_odometry_lost, 0u);
  const auto earlier = fly(150 * kMs, 1200 * kMs);  // the loss 1.15 s after the crash attitude
  EXPECT_EQ(earlier.state, IndiFailsafeState::kOdometryLost);
  EXPECT_GT(earlier.ticks_odometry_lost, 0u);
}

// In the air the land detector never holds (the IMU measures the descent's acceleration):
// the descent bound stops the motors.
TEST(IndiFailsafe, TheDescentBoundStopsTheMotors) {
  auto p = default_params();
  p.failsafe_max_descent_s = 1.0;
  IndiControlLogic l(p);
  lose_odometry(l, 100 * kMs);
  for (int64_t t = 102 * kMs; t <= 1300 * kMs; t += 2 * kMs) {
    // The specific force the commanded thrust gives in the air (m a_m = T).
    l.on_imu(imu_at(t, 0.0, l.controller().last_outer().thrust / 0.28));
    l.on_timer(t);
  }
  EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
  EXPECT_STREQ(l.stats().reason, "descent lasted failsafe_max_descent_s");
  EXPECT_NEAR(tactile_common::to_seconds(l.stats().state_since_ns), 0.202 + 1.0, 0.003);
}

// The land detector's fallback when the IMU missed the impact: the odometry's last velocity
// (-0.25 m/s) keeps the estimate descending while the vehicle rests on the floor (IMU at
// rest), so the descent loop holds hover thrust. Past the bound (failsafe_floor_z = 0.9 m,
// from 1 m) the floor probe ramps the thrust down, and the motors stop by touchdown.
TEST(IndiFailsafe, FloorProbeOnTheFloorStopsTheMotorsByTouchdown) {
  auto p = default_params();
  p.failsafe_floor_z = 0.9;
  IndiControlLogic l(p);
  double probe_start_thrust = -1.0, last_thrust = 0.0;
  bool ramp_down = true;
  for (int64_t t = 0; t <= 4000 * kMs && l.state() != IndiFailsafeState::kMotorsStopped; t += 2 * kMs) {
    if (t <= 100 * kMs) {
      auto o = odometry_at(t);
      o.twist.twist.linear.z = -0.25;  // the descent the estimate keeps reading on the floor
      l.on_odometry(o);
    }
    l.on_imu(imu_at(t));  // at rest
    const bool probing_before = l.floor_probe();
    l.on_timer(t);
    if (l.state() != IndiFailsafeState::kOdometryLost || !l.floor_probe()) continue;
    if (!probing_before) {
      probe_start_thrust = l.stats().commanded_thrust;
      EXPECT_LT(l.stats().height_estimate, 0.8);
      EXPECT_GT(probe_start_thrust, 0.5 * kHover);  // before: the loop held the thrust up
    } else if (l.stats().commanded_thrust > last_thrust) {
      ramp_down = false;
    }
    last_thrust = l.stats().commanded_thrust;
  }
  EXPECT_GT(probe_start_thrust, 0.0);
  EXPECT_TRUE(ramp_down);
  EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
  EXPECT_EQ(l.stats().reason_code, IndiReason::kTouchdown);
  EXPECT_EQ(l.stats().floor_probes, 1u);
  EXPECT_EQ(l.stats().floor_probes_aborted, 0u);
}

// A biased accelerometer (0.5 m/s^2 down) runs the estimate ahead of the vehicle, which is
// in the air (the IMU reads the specific force of the thrust sent, m a_m = T, plus the bias):
// past the bound the probe lowers the thrust, the vehicle accelerates down, airborne_in_probe
// aborts it and the descent goes on with the floor bound off (no second probe, no stop).
TEST(IndiFailsafe, FloorProbeInTheAirAbortsAndTheDescentGoesOn) {
  auto p = default_params();
  p.failsafe_floor_z = 0.9;
  IndiControlLogic l(p);
  constexpr double kBias = 0.5;
  auto out = lose_odometry(l, 100 * kMs);
  double min_thrust_after_abort = 1e9, lowest_estimate = 1.0;
  for (int64_t t = 102 * kMs; t <= 5000 * kMs; t += 2 * kMs) {
    const double thrust = out ? out->total_thrust : kHover;
    l.on_imu(imu_at(t, 0.0, thrust / 0.28 - (t > 202 * kMs ? kBias : 0.0)));
    out = l.on_timer(t);
    ASSERT_EQ(l.state() == IndiFailsafeState::kMotorsStopped, false) << "stopped in the air at t = " << t;
    if (l.stats().floor_probes_aborted > 0 && !l.floor_probe()) {
      min_thrust_after_abort = std::min(min_thrust_after_abort, l.stats().commanded_thrust);
      lowest_estimate = std::min(lowest_estimate, l.stats().height_estimate);
    }
  }
  EXPECT_EQ(l.state(), IndiFailsafeState::kOdometryLost);
  EXPECT_EQ(l.stats().floor_probes, 1u);
  EXPECT_EQ(l.stats().floor_probes_aborted, 1u);
  EXPECT_FALSE(l.floor_probe());
  EXPECT_GT(min_thrust_after_abort, 0.5 * kHover);  // the descent loop flies again
  EXPECT_LT(lowest_estimate, 0.8);                   // past the bound, and no second probe
}

// No attitude: the motors stop max_input_age_s after the last IMU sample, from NOMINAL and
// from the descent; zeros are published every tick.
TEST(IndiFailsafe, ImuLossStopsTheMotors) {
  for (const bool in_descent : {false, true}) {
    SCOPED_TRACE(in_descent ? "ODOMETRY_LOST" : "NOMINAL");
    IndiControlLogic l(default_params());
    lose_odometry(l, in_descent ? 300 * kMs : 50 * kMs);
    ASSERT_EQ(l.state(), in_descent ? IndiFailsafeState::kOdometryLost : IndiFailsafeState::kNominal);
    const int64_t last_imu = in_descent ? 300 * kMs : 50 * kMs;
    std::optional<tactile_msgs::msg::ThrustCommand> out;
    for (int64_t t = last_imu + 2 * kMs; t <= last_imu + 100 * kMs; t += 2 * kMs) {
      if (!in_descent) l.on_odometry(odometry_at(t));
      out = l.on_timer(t);
    }
    EXPECT_EQ(l.state(), in_descent ? IndiFailsafeState::kOdometryLost : IndiFailsafeState::kNominal);
    out = l.on_timer(last_imu + 102 * kMs);
    EXPECT_EQ(l.state(), IndiFailsafeState::kMotorsStopped);
    ASSERT_TRUE(out.has_value());
    EXPECT_EQ(out->total_thrust, 0.0);
    for (double f : out->rotor_thrust) EXPECT_EQ(f, 0.0);
    EXPECT_NE(std::string(l.stats().reason).find("IMU stale"), std::string::npos) << l.stats().reason;
  }
}

// The fail-safe's state for a ground station and bags: FsmState (behaviour
// indi_failsafe) on the first tick, on every transition with its REASON_INDI_* code and
// the state left, and at 1 Hz in between -- here WAITING_FOR_INPUT -> NOMINAL (80) ->
// ODOMETRY_LOST (82) -> MOTORS_STOPPED (81, the IMU lost in the descent).
TEST(IndiFailsafe, StateMessagesOnEveryTransitionAndAtOneHz) {
  using tactile_msgs::msg::FsmState;
  IndiControlLogic l(default_params());
  std::vector<FsmState> msgs;
  const int64_t t0 = 1'700'000'000'000'000'000;  // a system clock's nanoseconds, not 0
  auto tick = [&](int64_t t) {
    l.on_timer(t0 + t);
    if (auto s = l.state_message(t0 + t)) msgs.push_back(*s);
  };
  tick(0);  // nothing received yet
  for (int64_t t = 2 * kMs; t <= 2000 * kMs; t += 2 * kMs) {
    if (t <= 100 * kMs) l.on_odometry(odometry_at(t0 + t));
    if (t <= 1500 * kMs) l.on_imu(imu_at(t0 + t, 0.0, l.controller().last_outer().thrust / 0.28));
    tick(t);
  }
  ASSERT_GE(msgs.size(), 4u);
  EXPECT_EQ(msgs[0].behaviour, "indi_failsafe");
  EXPECT_EQ(msgs[0].state, "WAITING_FOR_INPUT");
  EXPECT_EQ(msgs[0].reason_code, FsmState::REASON_NONE);
  EXPECT_EQ(msgs[0].time_in_state, 0.0);  // since the first tick, not since the clock's 0
  std::vector<std::string> changes;
  for (std::size_t i = 1; i < msgs.size(); ++i) {
    if (msgs[i].transitions == msgs[i - 1].transitions) {
      // Between transitions: 1 Hz, the state unchanged.
      EXPECT_EQ(msgs[i].state, msgs[i - 1].state);
      EXPECT_NEAR(tactile_common::to_seconds(tactile_common::from_stamp(msgs[i].header.stamp) -
                                             tactile_common::from_stamp(msgs[i - 1].header.stamp)),
                  1.0, 1e-9);
      continue;
    }
    changes.push_back(msgs[i].previous_state + " -> " + msgs[i].state + " " + std::to_string(msgs[i].reason_code));
  }
  const std::vector<std::string> want = {
      "WAITING_FOR_INPUT -> NOMINAL " + std::to_string(FsmState::REASON_INDI_INPUTS_READY),
      "NOMINAL -> ODOMETRY_LOST " + std::to_string(FsmState::REASON_INDI_ODOMETRY_LOST),
      "ODOMETRY_LOST -> MOTORS_STOPPED " + std::to_string(FsmState::REASON_INDI_IMU_LOST)};
  EXPECT_EQ(changes, want);
  EXPECT_EQ(msgs.back().state, "MOTORS_STOPPED");
  EXPECT_EQ(l.stats().state_messages, msgs.size());
}
