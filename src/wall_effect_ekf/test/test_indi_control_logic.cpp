// INDI controller node logic and the 004 setpoint scripts.
#include <gtest/gtest.h>

#include <cmath>
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
  EXPECT_FALSE(logic.on_timer(500'000'000).has_value());  // stale inputs
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
  ASSERT_NE(d.info("max_tilt"), nullptr);
  EXPECT_EQ(d.info("max_tilt")->range->text(), "(0, 1.4)");
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
  ASSERT_NE(d.info("amplitude"), nullptr);
  EXPECT_EQ(d.info("amplitude")->range->text(), "[0, inf)");
  EXPECT_EQ(d.info("sweep_hold_s")->range->text(), "(0, inf)");
  EXPECT_EQ(d.info("yaw_deg")->unit, "deg");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}
