// Procedural scenario families (issue 17): draws are deterministic per seed,
// stay inside the documented distributions, pass their validity rules and load
// as standalone scenarios; the reachability check itself against hand cases;
// `tactile sweep` writes its table and summary (on a tiny hand scenario
// directory, seconds).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "sim_test_util.hpp"
#include "tactile_cli/scenario_family.hpp"
#include "tactile_cli/sweep.hpp"
#include "tactile_sim/scenario.hpp"

namespace fs = std::filesystem;
using tactile_cli::FamilyEnvironment;
using tactile_sim::Vec2;

namespace {

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("tactile_cli_families_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

}  // namespace

TEST(ScenarioFamilies, RegistryHasTheThreeFamiliesOfIssue17) {
  for (const char* name : {"baffles", "baffles_mocap", "baffles_flow_deck", "baffles_imu_tof", "rooms",
                           "xplorer_objects"}) {
    const auto* f = tactile_cli::find_scenario_family(name);
    ASSERT_NE(f, nullptr) << name;
    EXPECT_FALSE(f->table_metrics.empty()) << name;
    EXPECT_FALSE(f->distribution.empty()) << name;
  }
  EXPECT_EQ(tactile_cli::find_scenario_family("no_such_family"), nullptr);
  try {
    tactile_cli::scenario_family("no_such_family");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("baffles"), std::string::npos) << e.what();
  }
}

TEST(ScenarioFamilies, EveryFamilyDrawsDeterministicLoadableEnvironments) {
  for (const auto& family : tactile_cli::scenario_families()) {
    SCOPED_TRACE(family.name);
    std::set<std::string> distinct;
    for (uint64_t seed = 1; seed <= 15; ++seed) {
      const FamilyEnvironment a = tactile_cli::generate_environment(family, seed);
      const FamilyEnvironment b = tactile_cli::generate_environment(family, seed);
      EXPECT_EQ(a.yaml, b.yaml);
      EXPECT_EQ(a.name, family.name + "_" + std::to_string(seed));
      distinct.insert(a.yaml);
      const auto sc = tactile_sim::load_scenario_from_string(a.yaml, a.name + ".yaml", ".");
      EXPECT_EQ(sc.name, a.name);
      EXPECT_EQ(sc.seed, seed);
      EXPECT_NO_THROW(tactile_sim::Arena::from_yaml_text(sc.arena_yaml, sc.arena_source, sc.arena_key));
    }
    EXPECT_EQ(distinct.size(), 15u);
  }
}

TEST(ScenarioFamilies, BaffleDrawsStayInTheDocumentedDistribution) {
  const auto& family = tactile_cli::scenario_family("baffles");
  std::set<std::string> estimates, materials;
  std::set<int> counts;
  for (uint64_t seed = 100; seed < 200; ++seed) {
    const auto env = tactile_cli::generate_environment(family, seed);
    const auto& d = env.drawn;
    const int n = d["baffles"].get<int>();
    counts.insert(n);
    EXPECT_GE(n, 2);
    EXPECT_LE(n, 6);
    ASSERT_EQ(d["layout"].size(), static_cast<size_t>(n));
    double prev_stagger = 0.0;
    for (const auto& b : d["layout"]) {
      EXPECT_GE(b["spacing_m"].get<double>(), 0.8);
      EXPECT_LE(b["spacing_m"].get<double>(), 1.4);
      EXPECT_GE(b["angle_deg"].get<double>(), -115.0);
      EXPECT_LE(b["angle_deg"].get<double>(), -65.0);
      const double st = b["stagger_m"].get<double>();
      EXPECT_GE(std::abs(st), 0.2);
      EXPECT_LE(std::abs(st), 0.5);
      EXPECT_LT(st * prev_stagger, 1e-12);  // alternating sides
      prev_stagger = st;
      EXPECT_GE(b["length_m"].get<double>(), 0.8);
      EXPECT_LE(b["length_m"].get<double>(), 1.6);
      materials.insert(b["material"].get<std::string>());
    }
    estimates.insert(d["state_estimate"].get<std::string>());
    // The scenario flies what was drawn.
    const auto sc = tactile_sim::load_scenario_from_string(env.yaml, env.name + ".yaml", ".");
    EXPECT_EQ(sc.state_estimate, d["state_estimate"].get<std::string>());
    EXPECT_EQ(sc.graph, "whisker_fsm");
    const auto arena = tactile_sim::Arena::from_yaml_text(sc.arena_yaml, sc.arena_source, sc.arena_key);
    EXPECT_EQ(arena.walls().size(), static_cast<size_t>(n));
    EXPECT_GE(tactile_cli::clearance_at(arena, Vec2::Zero()), 0.5);
  }
  EXPECT_EQ(counts, (std::set<int>{2, 3, 4, 5, 6}));
  EXPECT_EQ(estimates, (std::set<std::string>{"mocap", "flow_deck", "imu_tof"}));
  EXPECT_EQ(materials, (std::set<std::string>{"rigid", "glass", "textile"}));
}

TEST(ScenarioFamilies, FixedEstimateVariantsShareTheGeometryOfASeed) {
  const auto mixed = tactile_cli::generate_environment(tactile_cli::scenario_family("baffles"), 42);
  for (const char* est : {"mocap", "flow_deck", "imu_tof"}) {
    const auto fixed = tactile_cli::generate_environment(tactile_cli::scenario_family(std::string("baffles_") + est), 42);
    EXPECT_EQ(fixed.drawn["layout"], mixed.drawn["layout"]) << est;
    EXPECT_EQ(fixed.drawn["state_estimate"].get<std::string>(), est);
  }
}

TEST(ScenarioFamilies, RoomDrawsKeepTheirExitsClearAndReachable) {
  const auto& family = tactile_cli::scenario_family("rooms");
  std::set<size_t> exits, obstacles;
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    const auto env = tactile_cli::generate_environment(family, seed);
    const auto& d = env.drawn;
    for (double side : d["room_m"]) {
      EXPECT_GE(side, 1.5);
      EXPECT_LE(side, 3.5);
    }
    exits.insert(d["exits"].size());
    obstacles.insert(d["obstacles"].size());
    for (const auto& e : d["exits"]) {
      EXPECT_GE(e["width_m"].get<double>(), 0.6);
      EXPECT_LE(e["width_m"].get<double>(), 1.0);
    }
  }
  EXPECT_EQ(exits, (std::set<size_t>{1, 2}));
  EXPECT_EQ(obstacles, (std::set<size_t>{0, 1, 2}));
}

TEST(ScenarioFamilies, XplorerObjectsMeetTheRayAtTheNearFace) {
  const auto& family = tactile_cli::scenario_family("xplorer_objects");
  std::set<std::string> shapes;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const auto env = tactile_cli::generate_environment(family, seed);
    shapes.insert(env.drawn["shape"].get<std::string>());
    const auto sc = tactile_sim::load_scenario_from_string(env.yaml, env.name + ".yaml", ".");
    const auto arena = tactile_sim::Arena::from_yaml_text(sc.arena_yaml, sc.arena_source, sc.arena_key);
    const auto hit = arena.raycast(Vec2::Zero(), Vec2(1.0, 0.0), 5.0);
    ASSERT_TRUE(hit.hit);
    EXPECT_NEAR(hit.distance, 0.8, 2e-3) << env.name;
  }
  EXPECT_EQ(shapes, (std::set<std::string>{"box", "polygon", "cylinder"}));
}

TEST(ScenarioFamilies, DiscPathAgainstHandCases) {
  // A wall across x = 1 from y = -1 to 1: a 0.2 m disc passes round its end
  // inside a box reaching y = 1.5, not inside one ending at y = 1.1.
  const auto arena = tactile_sim::Arena::from_yaml_text("walls:\n  - points: [[1, -1], [1, 1]]\n", "hand.yaml");
  EXPECT_TRUE(tactile_cli::disc_path_exists(arena, Vec2(0, 0), Vec2(2, 0), 0.2, Vec2(-0.5, -1.5), Vec2(2.5, 1.5)));
  EXPECT_FALSE(tactile_cli::disc_path_exists(arena, Vec2(0, 0), Vec2(2, 0), 0.2, Vec2(-0.5, -1.1), Vec2(2.5, 1.1)));
  // A 0.3 m gap between two walls: a 0.1 m disc passes, a 0.2 m one does not.
  const auto gap = tactile_sim::Arena::from_yaml_text(
      "walls:\n  - points: [[1, -2], [1, -0.15]]\n  - points: [[1, 0.15], [1, 2]]\n", "gap.yaml");
  EXPECT_TRUE(tactile_cli::disc_path_exists(gap, Vec2(0, 0), Vec2(2, 0), 0.1, Vec2(-0.5, -2), Vec2(2.5, 2)));
  EXPECT_FALSE(tactile_cli::disc_path_exists(gap, Vec2(0, 0), Vec2(2, 0), 0.2, Vec2(-0.5, -2), Vec2(2.5, 2)));
  // Start inside the obstacle's clearance.
  EXPECT_FALSE(tactile_cli::disc_path_exists(gap, Vec2(0.95, 0.5), Vec2(2, 0), 0.1, Vec2(-0.5, -2), Vec2(2.5, 2)));
}

TEST(ScenarioFamilies, GenerateWritesFilesAndIndex) {
  const fs::path out = temp_dir("generate");
  const auto paths = tactile_cli::generate_family(tactile_cli::scenario_family("baffles"), 3, 7000, out.string());
  ASSERT_EQ(paths.size(), 3u);
  EXPECT_EQ(fs::path(paths[2]).filename(), "baffles_7002.yaml");
  for (const auto& p : paths) EXPECT_NO_THROW(tactile_sim::load_scenario(p));
  std::ifstream idx(out / "index.json");
  ASSERT_TRUE(idx);
  const auto j = nlohmann::json::parse(idx);
  EXPECT_EQ(j["family"], "baffles");
  EXPECT_EQ(j["environments"].size(), 3u);
  EXPECT_EQ(j["environments"][1]["seed"], 7001);
  // Environment 7001 alone is the same file.
  EXPECT_EQ(tactile_cli::generate_environment(tactile_cli::scenario_family("baffles"), 7001).yaml, [&] {
    std::ifstream f(paths[1]);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }());
  fs::remove_all(out);
}

TEST(Sweep, WritesTableAndSummaryWithFailuresAndErrors) {
  // Two tiny scenarios: a 3 s hover with the pilot (success) and a pilot
  // flying into a wall (collision: failure with a top view), plus a broken
  // file (error row).
  const fs::path dir = temp_dir("sweep_in");
  fs::create_directories(dir);
  const std::string common =
      "duration_s: 4.0\narena:\n  walls:\n    - points: [[0.5, -1], [0.5, 1]]\nvehicle:\n  type: whisker_crazyflie\n"
      "graph: pilot\n";
  std::ofstream(dir / "a_hover.yaml") << "name: a_hover\n" << common
                                      << "pilot:\n  - {takeoff: 0.4, duration: 2.0}\n  - {hover: 1.0}\n  - {land: true}\n";
  std::ofstream(dir / "b_crash.yaml") << "name: b_crash\n" << common
                                      << "pilot:\n  - {takeoff: 0.4, duration: 1.0}\n  - {velocity: [1.0, 0.0], duration: 3.0}\n";
  std::ofstream(dir / "c_broken.yaml") << "name: c_broken\nduration_s: -1\n";
  const fs::path out = temp_dir("sweep_out");
  tactile_cli::SweepOptions o;
  o.what = dir.string();
  o.count = 0;
  o.out_dir = out.string();
  o.config_dir = tactile_cli::test::config_dir().string();
  o.progress = false;
  const auto s = tactile_cli::run_sweep(o);
  EXPECT_EQ(s["environments"], 3);
  EXPECT_EQ(s["successes"], 1);
  EXPECT_EQ(s["errors"], 1);
  ASSERT_EQ(s["failures"].size(), 2u);
  EXPECT_EQ(s["failures"][0]["name"], "b_crash");
  EXPECT_NE(s["failures"][0]["outcome"].get<std::string>().find("collision"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "failures" / "b_crash.png"));
  EXPECT_FALSE(fs::exists(out / "failures" / "a_hover.png"));
  EXPECT_TRUE(fs::exists(out / "runs" / "b_crash" / "bag"));   // failures keep their bag
  EXPECT_FALSE(fs::exists(out / "runs" / "a_hover" / "bag"));  // successes do not
  EXPECT_TRUE(fs::exists(out / "runs" / "b_crash" / "trajectory.csv"));    // nor their trajectory
  EXPECT_FALSE(fs::exists(out / "runs" / "a_hover" / "trajectory.csv"));
  EXPECT_TRUE(fs::exists(out / "runs" / "a_hover" / "metrics.json"));
  EXPECT_TRUE(fs::exists(out / "runs" / "a_hover" / "topview.png"));
  EXPECT_EQ(s["failures"][1]["outcome"].get<std::string>().rfind("error: ", 0), 0u) << s["failures"][1]["outcome"];
  EXPECT_NE(s["failures"][1]["outcome"].get<std::string>().find("c_broken.yaml"), std::string::npos);
  EXPECT_EQ(s["by_state_estimate"]["mocap"]["environments"], 2);
  for (const char* f : {"table.csv", "table.md", "summary.json", "summary.md"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream csv(out / "table.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("name,seed,state_estimate,outcome,success,collisions,guard_collisions", 0), 0u) << header;
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 3);
  // --keep-success-files: the success keeps its trajectory too.
  fs::remove(dir / "b_crash.yaml");
  fs::remove(dir / "c_broken.yaml");
  fs::remove_all(out);
  o.keep_success_files = true;
  EXPECT_EQ(tactile_cli::run_sweep(o)["successes"], 1);
  EXPECT_TRUE(fs::exists(out / "runs" / "a_hover" / "trajectory.csv"));
  fs::remove_all(dir);
  fs::remove_all(out);
}
