// SimLogic as a node: parameters, sensor rates at the physics rate, setpoint
// validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"

using tactile_sim::SimLogic;
using tactile_sim::Vec3;

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
  p.set("seed", (int64_t{1} << 32) + 10);  // a 64-bit seed: kept whole, not wrapped to 10
  EXPECT_EQ(SimLogic::from_parameters(p)->seed(), 4294967306u);
  p.set("seed", int64_t{-2});
  try {
    SimLogic::from_parameters(p);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("tactile_sim.ros__parameters.seed: must be in [-1, 9223372036854775807], got -2"),
              std::string::npos) << e.what();
  }
  p.set("seed", int64_t{9});
  p.set("scenario", std::string("no/such/scenario.yaml"));
  EXPECT_THROW(SimLogic::from_parameters(p), tactile_sim::ScenarioError);
}

// The parameter spec: both keys described, the seed's range no wider than from_parameters
// takes, none live (the world is built from them).
TEST(SimLogic, EveryParameterIsDescribedAndNoneIsLive) {
  auto d = SimLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  d.set("scenario", kSweep);  // else every probe is refused for the missing scenario
  ASSERT_NO_THROW(SimLogic::from_parameters(d));
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { SimLogic::from_parameters(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

// The component's own keys (issue 33 item 4: one schema per node): described, read-only,
// defaults as the component had them, real_time_factor's range (0, 1000] exactly what
// component_params_from() takes, its error naming the key and the value.
TEST(SimLogic, ComponentParametersAreDescribedAndChecked) {
  const auto d = SimLogic::component_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
  const auto c = SimLogic::component_params_from(d);
  EXPECT_EQ(c.real_time_factor, 1.0);
  EXPECT_EQ(c.wait_for_publisher, "");
  EXPECT_EQ(c.wait_for_subscribers, "");
  EXPECT_EQ(d.info("real_time_factor")->range->text(), "(0, 1000]");
  for (const auto& leak : tactile_common::range_leaks(
           d, [](const tactile_common::ParamMap& m) { SimLogic::component_params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  auto m = d;
  m.set("real_time_factor", 0.0);
  try {
    SimLogic::component_params_from(m);
    FAIL() << "0 accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("tactile_sim.ros__parameters.real_time_factor: must be in (0, 1000], got 0"),
              std::string::npos)
        << e.what();
  }
  // No key of the simulation's: the component declares both maps on one node.
  const auto simulation = SimLogic::default_parameters();
  for (const auto& [key, value] : simulation.values()) EXPECT_FALSE(d.has(key)) << key;
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
  for (const auto& m : out.pressure) left += m.topic == "whisker/left/pressure";
  for (const auto& m : out.whisker_truth) truth += m.topic == "ground_truth/whisker/left/contact";
  for (const auto& m : out.odometry) odom += m.topic == "odom";
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

namespace {
tactile_sim::Scenario xplorer_scenario(const std::string& params) {
  return tactile_sim::load_scenario_from_string(
      "name: x\nduration_s: 5\narena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
      "vehicle:\n  type: xplorer\n  params: " + params + "\n"
      "pilot:\n  - {hover: 1}\n",
      "x.yaml", ".");
}
std::string construct_error(const std::string& params) {
  try {
    SimLogic sim(xplorer_scenario(params), 1);
  } catch (const tactile_sim::ScenarioError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

// 001 Sec. V-C4: the rigid-chassis comparison vehicle and the arm's
// spring-damper are set from the scenario; bad values name file, key, reason.
TEST(SimLogic, XplorerArmParametersFromTheScenario) {
  const auto fly = [](const std::string& params) {
    SimLogic sim(xplorer_scenario(params), 1);
    SimLogic::Outputs out;
    geometry_msgs::msg::PoseStamped sp;  // 0.06 m into the wall's reach (contact at x = 0.79)
    sp.pose.position.x = 0.85;
    sp.pose.position.z = 0.7;
    sp.pose.orientation.w = 1.0;
    sim.on_position_setpoint(sp);
    double max_arm = 0.0;
    for (int64_t k = 0; k < 6000; ++k) {
      out.clear();
      sim.step(k * sim.period_ns(), out);
      for (const auto& a : out.arm_imu)
        for (const auto& arm : a.msg.arms) max_arm = std::max(max_arm, std::abs(static_cast<double>(arm.arm_angle)));
    }
    return max_arm;
  };
  EXPECT_GT(fly("{}"), 0.02);                  // compliant arms deflect on the wall
  EXPECT_EQ(fly("{rigid_arms: true}"), 0.0);   // locked hinges
  EXPECT_LT(fly("{arm_stiffness: 20.0}"), 0.5 * fly("{}"));
  const auto err = construct_error("{arm_stiffness: -1.0}");
  EXPECT_NE(err.find("x.yaml: vehicle.params: XplorerParams.arm_stiffness: must be > 0"), std::string::npos) << err;
  EXPECT_NE(construct_error("{rigid_arms: 3}").find("vehicle.params.rigid_arms: expected true or false"),
            std::string::npos);
  EXPECT_NE(construct_error("{arm_stifness: 2.0}").find("vehicle.params.arm_stifness: unknown parameter of xplorer"),
            std::string::npos);
  EXPECT_NE(construct_error("{arm_max_deflection_deg: 95}").find("arm_max_deflection"), std::string::npos);
  EXPECT_EQ(construct_error("{rigid_arms: false, arm_damping: 0.02, arm_inertia: 0.002, mass: 1.2}"), "");
}

// The ducted quadrotor's IMU bias from the scenario (accel_bias_sigma, per seed): the truth
// in the summary (zero by default), the same for the same seed, another for another seed;
// a negative sigma or an unknown key refused naming the file and the field.
TEST(SimLogic, DuctedQuadrotorAccelerometerBiasFromTheScenario) {
  const auto scenario = [](const std::string& params) {
    return tactile_sim::load_scenario_from_string(
        "name: d\nduration_s: 5\narena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
        "vehicle:\n  type: ducted_quadrotor\n  params: " + params + "\n"
        "graph: wall_effect_nav\n",
        "d.yaml", ".");
  };
  const auto bias = [&](const std::string& params, uint64_t seed) {
    SimLogic sim(scenario(params), seed);
    const auto s = sim.summary();
    return Vec3(s.at("imu_accel_bias_x"), s.at("imu_accel_bias_y"), s.at("imu_accel_bias_z"));
  };
  EXPECT_EQ(bias("{}", 1), Vec3::Zero());
  const Vec3 b1 = bias("{accel_bias_sigma: 0.1}", 1);
  EXPECT_GT(b1.norm(), 0.01);
  EXPECT_LT(b1.cwiseAbs().maxCoeff(), 0.5);  // 5 sigma
  EXPECT_EQ(bias("{accel_bias_sigma: 0.1}", 1), b1);
  EXPECT_NE(bias("{accel_bias_sigma: 0.1}", 2), b1);
  const auto error = [&](const std::string& params) -> std::string {
    try {
      SimLogic sim(scenario(params), 1);
    } catch (const tactile_sim::ScenarioError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error("{accel_bias_sigma: -0.1}").find("d.yaml: vehicle.params: ImuParams.accel_bias_initial_sigma: must be >= 0"),
            std::string::npos)
      << error("{accel_bias_sigma: -0.1}");
  EXPECT_NE(error("{accel_bias: 0.1}").find("unknown parameter of ducted_quadrotor (settable: mass, accel_bias_sigma)"),
            std::string::npos)
      << error("{accel_bias: 0.1}");
}

// Issue 32 item 6: a fault on a channel its message does not have (channel 99 of a
// WhiskerPressure) corrupted nothing while it counted every injection; now it is refused
// when the simulator is built, naming the file, the fault, the type and its channels.
TEST(SimLogic, FaultOnAMissingChannelIsRefused) {
  const std::string base =
      "name: f\nduration_s: 5\narena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
      "vehicle:\n  type: whisker_crazyflie\npilot:\n  - {hover: 1}\nfaults:\n";
  const auto error = [&](const std::string& fault) -> std::string {
    try {
      SimLogic sim(tactile_sim::load_scenario_from_string(base + fault, "f.yaml", "."), 1);
    } catch (const tactile_sim::ScenarioError& e) {
      return e.what();
    }
    return "";
  };
  const std::string e = error("  - {type: nan, topic: /whisker/left/pressure, channel: 99}\n");
  EXPECT_NE(e.find("f.yaml: faults[0].channel"), std::string::npos) << e;
  EXPECT_NE(e.find("channels 0-2, got 99"), std::string::npos) << e;
  EXPECT_NE(error("  - {type: nan, topic: /imu, channel: 6}\n").find("channels 0-5"), std::string::npos);
  EXPECT_EQ(error("  - {type: nan, topic: /whisker/left/pressure, channel: 2}\n"), "");
  EXPECT_EQ(error("  - {type: nan, topic: /imu, channel: 5}\n"), "");
}
