// Scenario tests of `tactile sim`: every library scenario flies, the
// data-collection protocol reaches the wall and sweeps it, metrics carry the
// required keys, one seed gives identical outputs, trials aggregate, and bad
// scenario files stop with file, key and reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "tactile_bag/bag.hpp"
#include "tactile_cli/parallel.hpp"
#include "tactile_cli/sim_run.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kConfig = TACTILE_CONFIG_DIR;

fs::path fresh_dir(const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("tactile_sim_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

tactile_cli::SimOptions options(const std::string& scenario, const fs::path& out) {
  tactile_cli::SimOptions o;
  o.scenario = (kConfig / "scenarios" / scenario).string();
  o.out_dir = out.string();
  o.config_dir = kConfig.string();
  o.progress = false;
  return o;
}

}  // namespace

TEST(Sim, WhiskerSweepFollowsTheDataCollectionProtocol) {
  const fs::path dir = fresh_dir("sweep");
  const auto m = tactile_cli::run_sim(options("whisker_sweep.yaml", dir));
  for (const char* key : {"sim_time_s", "wall_time_s", "real_time_factor", "collisions", "ground_truth"}) {
    EXPECT_TRUE(m.contains(key)) << key;
  }
  EXPECT_NEAR(m["sim_time_s"].get<double>(), 16.0, 0.01);
  EXPECT_EQ(m["collisions"].get<int>(), 0);
  // The whiskers reached the wall (x = 1.0) and the pilot saw the contact
  // through the TDORC signal, then swept and landed.
  EXPECT_TRUE(m["pilot"]["finished"].get<bool>());
  EXPECT_EQ(m["pilot"]["steps_timed_out"].get<int>(), 0);
  EXPECT_TRUE(m["success"].get<bool>());
  const auto& gt = m["ground_truth"];
  EXPECT_GT(gt["whisker_contact_fraction_left"].get<double>(), 0.05);
  EXPECT_GT(gt["whisker_contact_fraction_right"].get<double>(), 0.05);
  EXPECT_GT(gt["max_true_depth_left_m"].get<double>(), 0.01);
  // The body never reached the wall: the whiskers touch, the guard does not.
  EXPECT_GT(gt["min_obstacle_distance_m"].get<double>(), 0.08);
  // Swept right (-y) along the wall for 2 s at 0.2 m/s.
  EXPECT_LT(gt["final_y_m"].get<double>(), -0.25);
  for (const char* f : {"bag/metadata.yaml", "trajectory.csv", "metrics.json", "topview.png"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  tactile_bag::Reader bag((dir / "bag").string());
  for (const char* topic : {"/whisker/left/pressure", "/whisker/right/pressure", "/whisker/left/signal",
                            "/ground_truth/odom", "/odom", "/imu", "/cmd_hover", "/ground_truth/external_force",
                            "/ground_truth/whisker/left/contact"}) {
    EXPECT_GT(bag.message_count(topic), 0u) << topic;
  }
  // Barometers at 50 Hz, ground-truth odometry and the Crazyflie's IMU at 100 Hz.
  EXPECT_NEAR(static_cast<double>(bag.message_count("/whisker/left/pressure")), 16.0 * 50, 2);
  EXPECT_NEAR(static_cast<double>(bag.message_count("/ground_truth/odom")), 16.0 * 100, 2);
  EXPECT_NEAR(static_cast<double>(bag.message_count("/imu")), 16.0 * 100, 2);
  fs::remove_all(dir);
}

TEST(Sim, EveryLibraryScenarioFlies) {
  // The scenarios are independent: flown on the parallel runner (all cores),
  // checked here in file-name order.
  const fs::path dir = fresh_dir("library");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kConfig / "scenarios")) {
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  const auto runs = tactile_cli::parallel_map(files.size(), 0, [&](size_t i) {
    auto o = options(files[i].filename().string(), dir / files[i].stem());
    o.write_bag = false;
    o.write_png = false;
    o.jobs = 1;
    return tactile_cli::run_sim(o);
  });
  for (size_t i = 0; i < files.size(); ++i) {
    SCOPED_TRACE(files[i].filename().string());
    const auto& m = runs[i];
    EXPECT_GT(m["sim_time_s"].get<double>(), 1.0);
    EXPECT_TRUE(m["ground_truth"].contains("path_length_m"));
    EXPECT_TRUE(fs::exists(dir / files[i].stem() / "trajectory.csv"));
  }
  fs::remove_all(dir);
}

TEST(Sim, SameSeedSameOutputsDifferentSeedDifferentNoise) {
  const fs::path dir = fresh_dir("determinism");
  auto run = [&](const char* name, uint64_t seed) {
    auto o = options("whisker_sweep_glass.yaml", dir / name);
    o.seed = seed;
    o.write_png = false;
    return tactile_cli::run_sim(o);
  };
  auto a = run("a", 3), b = run("b", 3), c = run("c", 4);
  for (auto* m : {&a, &b, &c}) {
    m->erase("wall_time_s");
    m->erase("real_time_factor");
  }
  EXPECT_EQ(a, b);
  EXPECT_NE(a["ground_truth"], c["ground_truth"]);
  tactile_bag::Reader ra((dir / "a" / "bag").string()), rb((dir / "b" / "bag").string());
  ASSERT_EQ(ra.message_count(), rb.message_count());
  tactile_bag::SerializedMessage ma, mb;
  while (ra.read_next(ma)) {
    ASSERT_TRUE(rb.read_next(mb));
    ASSERT_EQ(ma.topic, mb.topic);
    ASSERT_EQ(ma.timestamp_ns, mb.timestamp_ns);
    ASSERT_EQ(ma.data, mb.data) << ma.topic << " at " << ma.timestamp_ns;
  }
  fs::remove_all(dir);
}

TEST(Sim, TrialsAggregateWithRandomArenaRotation) {
  const fs::path dir = fresh_dir("trials");
  auto o = options("whisker_room_exit.yaml", dir);
  o.trials = 3;
  o.write_bag = false;
  const auto m = tactile_cli::run_sim(o);
  EXPECT_EQ(m["trials"].get<int>(), 3);
  ASSERT_EQ(m["per_trial"].size(), 3u);
  EXPECT_TRUE(m.contains("success_count"));
  EXPECT_TRUE(m["statistics"].contains("ground_truth.path_length_m"));
  EXPECT_EQ(m["statistics"]["ground_truth.path_length_m"]["n"].get<int>(), 3);
  // Each trial rotates the room differently.
  const double y0 = m["per_trial"][0]["arena_yaw_deg"], y1 = m["per_trial"][1]["arena_yaw_deg"];
  EXPECT_NE(y0, y1);
  EXPECT_GE(y0, -180.0);
  EXPECT_LE(y0, 180.0);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(fs::exists(dir / ("trial_" + std::to_string(k)) / "topview.png"));
  fs::remove_all(dir);
}

TEST(Sim, FaultsAreInjectedAndCounted) {
  const fs::path dir = fresh_dir("faults");
  fs::create_directories(dir);
  std::ifstream in(kConfig / "scenarios" / "whisker_sweep.yaml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string yaml = ss.str();
  yaml.replace(yaml.find("arena_file: arenas/"), 19, "arena_file: " + (kConfig / "scenarios" / "arenas").string() + "/");
  yaml +=
      "faults:\n"
      "  - {type: nan, topic: /whisker/left/pressure, probability: 0.05}\n"
      "  - {type: dropout, topic: /imu, start_s: 2.0, duration_s: 1.0}\n"
      "  - {type: latency, topic: /odom, delay_s: 0.05}\n";
  std::ofstream(dir / "faulty.yaml") << yaml;
  auto o = options("", dir / "out");
  o.scenario = (dir / "faulty.yaml").string();
  o.write_png = false;
  const auto m = tactile_cli::run_sim(o);
  EXPECT_GT(m["faults_injected"]["nan"].get<int>(), 10);
  EXPECT_NEAR(m["faults_injected"]["dropout"].get<double>(), 100.0, 2.0);  // 1 s of a 100 Hz IMU
  EXPECT_GT(m["faults_injected"]["latency"].get<int>(), 1000);
  // The TDORC node dropped (and counted) every NaN sample instead of passing it on.
  EXPECT_EQ(m["nodes"]["/whisker/left/tdorc_filter"]["dropped_nonfinite"].get<int>(),
            m["faults_injected"]["nan"].get<int>());
  EXPECT_NEAR(m["topics"]["/imu"].get<double>(), 16.0 * 100 - 100, 3);
  fs::remove_all(dir);
}

TEST(Sim, MalformedScenarioStopsWithFileKeyAndReason) {
  const fs::path dir = fresh_dir("bad");
  fs::create_directories(dir);
  auto error_of = [&](const std::string& yaml) -> std::string {
    std::ofstream(dir / "bad.yaml") << yaml;
    auto o = options("", dir / "out");
    o.scenario = (dir / "bad.yaml").string();
    try {
      tactile_cli::run_sim(o);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  const std::string head = "name: b\nduration_s: 2\nvehicle: {type: whisker_crazyflie}\ngraph: none\n";
  std::string msg = error_of(head + "arena:\n  walls:\n    - points: [[0, 0], [0, 0]]\n");
  EXPECT_NE(msg.find("bad.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("walls[0]"), std::string::npos) << msg;
  EXPECT_NE(msg.find("zero-length"), std::string::npos) << msg;
  msg = error_of(head + "arena:\n  walls:\n    - points: [[0, 0], [2, 0], [1, 1], [1, -1]]\n");
  EXPECT_NE(msg.find("walls[0]"), std::string::npos) << msg;
  EXPECT_NE(msg.find("self-intersect"), std::string::npos) << msg;
  msg = error_of(head + "arena:\n  walls:\n    - points: [[1, -1], [1, 1]]\nfaults:\n  - {type: loss, topic: /nope}\n");
  EXPECT_NE(msg.find("faults[0].topic"), std::string::npos) << msg;
  EXPECT_NE(msg.find("publishes no 'nope'"), std::string::npos) << msg;
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: xplorer, params: {mas: 1}}\ngraph: none\n"
                 "arena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n");
  EXPECT_NE(msg.find("vehicle.params.mas"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown parameter"), std::string::npos) << msg;
  // The graph registry: unknown graph, a graph that cannot fly the vehicle,
  // parameters of a node the graph does not have.
  const std::string walls = "arena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n";
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: whisker_crazyflie}\ngraph: no_such_graph\n" + walls);
  EXPECT_NE(msg.find("bad.yaml: graph: unknown graph 'no_such_graph'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("whisker_fsm"), std::string::npos) << msg;  // lists the known graphs
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: xplorer}\ngraph: whisker_fsm\n" + walls);
  EXPECT_NE(msg.find("'whisker_fsm' cannot fly the xplorer"), std::string::npos) << msg;
  msg = error_of(head + walls + "node_parameters:\n  whisker_fsm: {t_max: 0.1}\n");
  EXPECT_NE(msg.find("node_parameters.whisker_fsm: no such node in graph 'none'"), std::string::npos) << msg;
  // An integer an int would wrap (2^32 + 20 trials ran as 20) names the key and the value as given.
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: whisker_stage}\ngraph: whisker_stage\n" + walls +
                 "node_parameters:\n  whisker_stage_protocol: {protocol: table1, trials: 4294967316}\n");
  EXPECT_NE(msg.find("bad.yaml (node_parameters.whisker_stage_protocol): whisker_stage_protocol.ros__parameters.trials: "
                     "must be in [1, 2147483647], got 4294967316"),
            std::string::npos) << msg;
  // A node that fails to start leaves no bag behind (a rerun would stop on it).
  EXPECT_FALSE(fs::exists(dir / "out" / "bag"));
  // The protocols' own lower bounds are named at the key too (Table II needs 4 steps).
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: whisker_stage}\ngraph: whisker_stage\n" + walls +
                 "node_parameters:\n  whisker_stage_protocol: {protocol: table2, steps: 3}\n");
  EXPECT_NE(msg.find("whisker_stage_protocol.ros__parameters.steps: must be in [4, 2147483647], got 3"),
            std::string::npos) << msg;
  msg = error_of("name: b\nduration_s: 2\nvehicle: {type: whisker_stage}\ngraph: whisker_stage\n" + walls +
                 "node_parameters:\n  whisker_stage_protocol: {protocol: table1, trials: 0}\n");
  EXPECT_NE(msg.find("whisker_stage_protocol.ros__parameters.trials: must be in [1, 2147483647], got 0"),
            std::string::npos) << msg;
  msg = error_of("name: b\nduration_s: 2\n  bad indent: [\n");
  EXPECT_NE(msg.find("YAML syntax error"), std::string::npos) << msg;
  fs::remove_all(dir);
}
