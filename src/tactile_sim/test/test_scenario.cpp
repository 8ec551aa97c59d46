// Scenario file parsing: every file of the library loads; malformed files
// stop with the file, the key path and the reason.
#include <gtest/gtest.h>

#include <filesystem>

#include "tactile_sim/scenario.hpp"

using tactile_sim::load_scenario;
using tactile_sim::load_scenario_from_string;
using tactile_sim::PilotStep;
using tactile_sim::ScenarioError;

namespace {

const std::string kMinimal =
    "name: t\n"
    "duration_s: 5\n"
    "arena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
    "vehicle:\n  type: whisker_crazyflie\n"
    "pilot:\n  - {takeoff: 0.4, duration: 2}\n  - {land: true}\n";

std::string error_of(const std::string& yaml) {
  try {
    load_scenario_from_string(yaml, "scn.yaml", ".");
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "";
}

void expect_error(const std::string& yaml, const std::string& key, const std::string& reason) {
  const std::string msg = error_of(yaml);
  EXPECT_NE(msg.find("scn.yaml: "), std::string::npos) << msg;
  EXPECT_NE(msg.find(key), std::string::npos) << "key '" << key << "' not in: " << msg;
  EXPECT_NE(msg.find(reason), std::string::npos) << "reason '" << reason << "' not in: " << msg;
}

}  // namespace

TEST(Scenario, MinimalDefaults) {
  const auto s = load_scenario_from_string(kMinimal, "scn.yaml", ".");
  EXPECT_EQ(s.name, "t");
  EXPECT_DOUBLE_EQ(s.duration_s, 5.0);
  EXPECT_DOUBLE_EQ(s.physics_rate_hz, 1000.0);
  EXPECT_EQ(s.seed, 1u);
  EXPECT_EQ(s.vehicle, tactile_sim::VehicleType::kWhiskerCrazyflie);
  ASSERT_EQ(s.pilot.size(), 2u);
  EXPECT_EQ(s.pilot[0].kind, PilotStep::Kind::kTakeoff);
  EXPECT_DOUBLE_EQ(s.pilot[0].height, 0.4);
  EXPECT_DOUBLE_EQ(s.pilot[0].duration_s, 2.0);
  EXPECT_EQ(s.pilot[1].kind, PilotStep::Kind::kLand);
  EXPECT_NE(s.arena_yaml.find("walls"), std::string::npos);
  EXPECT_EQ(s.arena_key, "arena.");
}

TEST(Scenario, FullSchema) {
  const std::string yaml =
      "name: full\nduration_s: 20\nphysics_rate_hz: 500\nseed: 7\n"
      "arena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
      "arena_transform: {x: 1.5, y: -2, yaw_deg: 90}\n"
      "randomize: {arena_yaw_deg: [-180, 180]}\n"
      "vehicle:\n  type: whisker_crazyflie\n  initial: {x: 0.1, y: 0.2, z: 0, yaw_deg: 45}\n"
      "  state_estimate: flow_deck\n  params: {mass: 0.05, whiskers: true}\n"
      "pilot:\n"
      "  - {takeoff: 0.4, duration: 3}\n"
      "  - {velocity: [0.2, 0], until: contact, timeout: 15}\n"
      "  - {velocity: [0, -0.2], duration: 2}\n"
      "  - {yaw_rate: 0.5, duration: 1}\n"
      "  - {hover: 1}\n"
      "  - {land: true}\n"
      "faults:\n"
      "  - {type: dropout, topic: /whisker/left/pressure, start_s: 5, duration_s: 1}\n"
      "  - {type: spike, topic: /whisker/left/pressure, channel: 2, magnitude: 300, probability: 0.01}\n"
      "  - {type: latency, topic: /odom, delay_s: 0.05}\n"
      "node_parameters:\n  whisker_fsm: {t_max: 0.105, follow_side: left}\n"
      "metrics: {target: [60, 100]}\n";
  const auto s = load_scenario_from_string(yaml, "scn.yaml", ".");
  EXPECT_EQ(s.seed, 7u);
  EXPECT_DOUBLE_EQ(s.physics_rate_hz, 500.0);
  EXPECT_DOUBLE_EQ(s.arena_x, 1.5);
  EXPECT_NEAR(s.arena_yaw, M_PI / 2, 1e-12);
  ASSERT_TRUE(s.randomize_arena_yaw.has_value());
  EXPECT_NEAR(s.randomize_arena_yaw->first, -M_PI, 1e-12);
  EXPECT_NEAR(s.initial_yaw, M_PI / 4, 1e-12);
  EXPECT_EQ(s.state_estimate, "flow_deck");
  EXPECT_DOUBLE_EQ(std::get<double>(s.vehicle_params.at("mass")), 0.05);
  EXPECT_TRUE(std::get<bool>(s.vehicle_params.at("whiskers")));
  ASSERT_EQ(s.pilot.size(), 6u);
  EXPECT_EQ(s.pilot[1].until, "contact");
  EXPECT_DOUBLE_EQ(s.pilot[1].timeout_s, 15.0);
  EXPECT_DOUBLE_EQ(s.pilot[1].velocity.x(), 0.2);
  EXPECT_DOUBLE_EQ(s.pilot[2].velocity.y(), -0.2);
  EXPECT_EQ(s.pilot[3].kind, PilotStep::Kind::kVelocity);
  EXPECT_DOUBLE_EQ(s.pilot[3].yaw_rate, 0.5);
  EXPECT_EQ(s.pilot[4].kind, PilotStep::Kind::kHover);
  EXPECT_DOUBLE_EQ(s.pilot[4].duration_s, 1.0);
  ASSERT_EQ(s.faults.size(), 3u);
  EXPECT_EQ(s.faults[1].type, tactile_sim::FaultSpec::Type::kSpike);
  EXPECT_EQ(s.faults[1].channel, 2);
  EXPECT_DOUBLE_EQ(s.faults[2].delay_s, 0.05);
  EXPECT_EQ(std::get<std::vector<double>>(s.metrics.at("target")), (std::vector<double>{60, 100}));
  EXPECT_DOUBLE_EQ(std::get<double>(s.node_parameters.at("whisker_fsm").at("t_max")), 0.105);
  EXPECT_EQ(std::get<std::string>(s.node_parameters.at("whisker_fsm").at("follow_side")), "left");
}

TEST(Scenario, MalformedFilesNameFileKeyAndReason) {
  expect_error("name: t\nduration_s: 5\n", "arena", "exactly one of 'arena' or 'arena_file'");
  expect_error(kMinimal + "bogus: 1\n", "bogus", "unknown key");
  expect_error("name: t\nduration_s: -1\n", "duration_s", "must be > 0");
  expect_error("name: t\nduration_s: five\n", "duration_s", "expected a number");
  expect_error(kMinimal + "physics_rate_hz: 100\n", "physics_rate_hz", ">= 500");
  expect_error(kMinimal + "physics_rate_hz: 1250\n", "physics_rate_hz", "multiple of 500");
  std::string bad = kMinimal;
  bad.replace(bad.find("whisker_crazyflie"), 17, "blimp");
  expect_error(bad, "vehicle.type", "unknown vehicle 'blimp'");
  std::string estimate = kMinimal;
  estimate.replace(estimate.find("whisker_crazyflie\n"), 18, "whisker_crazyflie\n  state_estimate: gps\n");
  expect_error(estimate, "vehicle.state_estimate", "must be 'mocap', 'flow_deck' or 'imu_tof', got 'gps'");
  estimate = kMinimal;
  estimate.replace(estimate.find("whisker_crazyflie\n"), 18, "xplorer\n  state_estimate: imu_tof\n");
  expect_error(estimate, "vehicle.state_estimate", "imu_tof is the whiskered Crazyflie's estimator");
  expect_error(kMinimal + "faults:\n  - {type: gremlin, topic: /x}\n", "faults[0].type", "unknown fault 'gremlin'");
  expect_error(kMinimal + "faults:\n  - {type: latency, topic: /x}\n", "faults[0]", "needs delay_s");
  expect_error(kMinimal + "faults:\n  - {type: loss, topic: /}\n", "faults[0].topic", "must name a topic");
  expect_error(kMinimal + "faults:\n  - {type: loss, topic: /x, probability: 2}\n", "faults[0].probability", "[0, 1]");
  std::string pilot = kMinimal;
  pilot.replace(pilot.find("  - {land: true}"), 16, "  - {velocity: [0.2, 0]}");
  expect_error(pilot, "pilot[1]", "needs a duration or an 'until'");
  pilot = kMinimal;
  pilot.replace(pilot.find("  - {land: true}"), 16, "  - {velocity: [0.2, 0], hover: 2}");
  expect_error(pilot, "pilot[1]", "exactly one of");
  pilot = kMinimal;
  pilot.replace(pilot.find("  - {land: true}"), 16, "  - {velocity: [0.2], duration: 1}");
  expect_error(pilot, "pilot[1].velocity", "list of 2 numbers");
  expect_error("name: t\nduration_s: 5\narena_file: nope.yaml\nvehicle: {type: xplorer}\ngraph: none\n",
               "arena_file", "not found");
  expect_error("name: [t\n", "", "YAML syntax error at line");
  expect_error(kMinimal + "graph: whisker_fsm\n", "pilot", "only used with graph: pilot");
  expect_error(kMinimal + "graph: Whisker-FSM\n", "graph", "lower-case letters");
}

// Issue 32 item 6: keys and values that used to change results silently.
TEST(Scenario, UncheckedKeysAndValuesAreErrors) {
  // A misspelt metrics key was ignored (the run then counted collisions as failures).
  expect_error(kMinimal + "metrics: {alow_collisions: true}\n", "metrics.alow_collisions", "unknown key");
  // 1e12 s overflowed the nanosecond clock and simulated 0 s; 1e9 Hz hung.
  expect_error(std::string(kMinimal).replace(kMinimal.find("duration_s: 5"), 13, "duration_s: 1e12"), "duration_s",
               "must be <= 86400 s");
  expect_error(kMinimal + "physics_rate_hz: 1e9\n", "physics_rate_hz", "must be <= 20000 Hz");
  // Seeds are read exactly: 2^64-1 became 0 through a double.
  EXPECT_EQ(load_scenario_from_string(kMinimal + "seed: 18446744073709551615\n", "scn.yaml", ".").seed,
            18446744073709551615ull);
  EXPECT_EQ(load_scenario_from_string(kMinimal + "seed: 9007199254740993\n", "scn.yaml", ".").seed,
            9007199254740993ull);  // 2^53 + 1: not a double
  expect_error(kMinimal + "seed: 18446744073709551616\n", "seed", "expected a whole number");
  expect_error(kMinimal + "seed: -1\n", "seed", "expected a whole number");
  expect_error(kMinimal + "seed: 2.5\n", "seed", "expected a whole number");
  expect_error(kMinimal + "faults:\n  - {type: nan, topic: /x, channel: 1.5}\n", "faults[0].channel",
               "expected a whole number");
}

TEST(Scenario, EveryLibraryScenarioLoads) {
  const std::filesystem::path dir = std::filesystem::path(TACTILE_CONFIG_DIR) / "scenarios";
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() != ".yaml") continue;
    SCOPED_TRACE(e.path().string());
    const auto s = load_scenario(e.path().string());
    EXPECT_FALSE(s.name.empty());
    EXPECT_FALSE(s.arena_yaml.empty());
    ++n;
  }
  EXPECT_GE(n, 10u);
}

TEST(Scenario, ADirectoryIsNotAScenarioFile) {
  const auto dir = std::filesystem::temp_directory_path() / "tactile_scenario_dir_test";
  std::filesystem::create_directories(dir);
  try {
    load_scenario(dir.string());
    ADD_FAILURE() << "a directory loaded as a scenario";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory, not a file"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}
