// SimLogic as a node: parameters, sensor rates at the physics rate, setpoint
// validation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "tactile_common/time.hpp"
#include "tactile_sim/logic/sim_logic.hpp"

using tactile_sim::SimLogic;

namespace {
const std::string kSweep = std::string(TACTILE_CONFIG_DIR) + "/scenarios/whisker_sweep.yaml";
}

TEST(SimLogic, FromParametersNamesTheBadParameter) {
  auto p = SimLogic::default_parameters();
  try {
    SimLogic::from_parameters(p);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("tactile_sim.ros__parameters.scenario"), std::string::npos) << e.what();
  }
  p.set("scenario", kSweep);
  p.set("seed", int64_t{-5});
  EXPECT_THROW(SimLogic::from_parameters(p), tactile_common::ParamError);
  p.set("seed", int64_t{-1});
  EXPECT_EQ(SimLogic::from_parameters(p)->seed(), 1u);  // the scenario's seed
  p.set("seed", int64_t{9});
  EXPECT_EQ(SimLogic::from_parameters(p)->seed(), 9u);
  p.set("scenario", std::string("no/such/scenario.yaml"));
  EXPECT_THROW(SimLogic::from_parameters(p), tactile_sim::ScenarioError);
}

TEST(SimLogic, SensorRatesDivideThePhysicsRate) {
  auto p = SimLogic::default_parameters();
  p.set("scenario", kSweep);
  auto sim = SimLogic::from_parameters(p);
  ASSERT_EQ(sim->period_ns(), 1000000);  // 1 kHz
  SimLogic::Outputs out;
  const int steps = 1000;                // one simulated second
  for (int k = 0; k < steps; ++k) sim->step(k * sim->period_ns(), out);
  size_t left = 0, truth = 0, odom = 0;
  for (const auto& m : out.pressure) left += m.topic == "/whisker/left/pressure";
  for (const auto& m : out.whisker_truth) truth += m.topic == "/ground_truth/whisker/left/contact";
  for (const auto& m : out.odometry) odom += m.topic == "/odom";
  EXPECT_EQ(left, 50u);   // 50 Hz barometers (000)
  EXPECT_EQ(truth, 50u);
  EXPECT_EQ(odom, 100u);  // 100 Hz state estimate
  EXPECT_EQ(out.imu.size(), 100u);
  // Samples are stamped with the tick that produced them, 20 ms apart.
  EXPECT_EQ(tactile_common::from_stamp(out.pressure[2].msg.header.stamp) -
                tactile_common::from_stamp(out.pressure[0].msg.header.stamp),
            20000000);
  EXPECT_FALSE(sim->finished(0));
  EXPECT_TRUE(sim->finished(tactile_common::from_seconds(16.0)));
}

TEST(SimLogic, NonFiniteOrWrongKindSetpointsAreDroppedAndCounted) {
  auto p = SimLogic::default_parameters();
  p.set("scenario", kSweep);
  auto sim = SimLogic::from_parameters(p);
  tactile_msgs::msg::HoverSetpoint bad;
  bad.vx = std::nan("");
  sim->on_hover_setpoint(bad);
  geometry_msgs::msg::PoseStamped pose;  // the Crazyflie takes no position setpoints
  pose.pose.orientation.w = 1.0;
  sim->on_position_setpoint(pose);
  tactile_msgs::msg::ThrustCommand thrust;  // wrong rotor count
  thrust.rotor_thrust = {1.0, 1.0};
  sim->on_rotor_thrust(thrust);
  EXPECT_EQ(sim->dropped_setpoints(), 3u);
  tactile_msgs::msg::HoverSetpoint good;
  good.height = 0.4;
  sim->on_hover_setpoint(good);
  EXPECT_EQ(sim->dropped_setpoints(), 3u);
}
