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
#include <sstream>
#include <tuple>

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

// Sharded sweeps (issue 36): the shards of a family sweep, merged, give the single-machine
// sweep's table, summary, scenarios and runs, timings and provenance aside.
namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// table.csv without its wall_time_s column (a timing).
std::string table_without_wall_time(const fs::path& p) {
  std::ifstream in(p);
  std::string out, line, header;
  std::getline(in, header);
  size_t col = 0;
  {
    std::stringstream h(header);
    std::string c;
    for (size_t i = 0; std::getline(h, c, ','); ++i) {
      if (c == "wall_time_s") col = i;
    }
  }
  EXPECT_GT(col, 0u) << header;
  out = header + "\n";
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string c;
    for (size_t i = 0; std::getline(s, c, ','); ++i) {
      if (i != col) out += c + ",";
    }
    out += "\n";
  }
  return out;
}

nlohmann::json summary_without_provenance(const fs::path& p) {
  auto j = nlohmann::json::parse(read_file(p));
  for (const char* k : {"date", "machine", "load_average_at_start", "jobs", "wall_time_s", "merged_shards", "shard"}) {
    j.erase(k);
  }
  return j;
}

/// summary.md without its second paragraph (date, machine, load, jobs, wall time).
std::string summary_md_without_provenance(const fs::path& p) {
  const std::string s = read_file(p);
  const size_t a = s.find("\n\n");
  const size_t b = s.find("\n\n", a + 2);
  if (a == std::string::npos || b == std::string::npos) return s;
  const std::string second = s.substr(a + 2, b - a - 2);
  return s.substr(0, a) + "|" + second.substr(0, second.find(';')) + "|" + s.substr(b);
}

tactile_cli::SweepOptions family_sweep(const fs::path& out, int count, uint64_t seed, int shard, int shards) {
  tactile_cli::SweepOptions o;
  o.what = "baffles_mocap";
  o.count = count;
  o.seed = seed;
  o.out_dir = out.string();
  o.config_dir = tactile_cli::test::config_dir().string();
  o.write_bags = false;
  o.progress = false;
  o.jobs = 2;
  o.shard = shard;
  o.shards = shards;
  return o;
}

std::set<std::string> entries(const fs::path& d) {
  std::set<std::string> s;
  if (!fs::is_directory(d)) return s;
  for (const auto& e : fs::directory_iterator(d)) s.insert(e.path().filename().string());
  return s;
}

}  // namespace

TEST(ShardedSweep, ShardsMergeIntoTheSingleRun) {
  const fs::path root = temp_dir("shards");
  const auto single = tactile_cli::run_sweep(family_sweep(root / "single", 5, 3000, 0, 0));
  ASSERT_EQ(single["flown"], 5);
  // Shard 1 of 2 flies environments 0, 2, 4 (seeds 3000, 3002, 3004); shard 2 the others.
  const auto s1 = tactile_cli::run_sweep(family_sweep(root / "s1", 5, 3000, 1, 2));
  const auto s2 = tactile_cli::run_sweep(family_sweep(root / "s2", 5, 3000, 2, 2));
  EXPECT_EQ(s1["environments"], 3);
  EXPECT_EQ(s2["environments"], 2);
  EXPECT_EQ(s1["shard"], "1/2");
  EXPECT_EQ(entries(root / "s1" / "runs"),
            (std::set<std::string>{"baffles_mocap_3000", "baffles_mocap_3002", "baffles_mocap_3004"}));
  EXPECT_EQ(entries(root / "s2" / "scenarios"),
            (std::set<std::string>{"baffles_mocap_3001.yaml", "baffles_mocap_3003.yaml", "index.json"}));
  EXPECT_TRUE(fs::exists(root / "s1" / "shard.json"));
  // The merge, shards given in any order.
  tactile_cli::SweepMergeOptions m;
  m.out_dir = (root / "merged").string();
  m.shard_dirs = {(root / "s2").string(), (root / "s1").string()};
  const auto merged = tactile_cli::merge_sweep(m);
  EXPECT_EQ(merged["merged_shards"].size(), 2u);
  const fs::path a = root / "single", b = root / "merged";
  EXPECT_EQ(table_without_wall_time(a / "table.csv"), table_without_wall_time(b / "table.csv"));
  EXPECT_EQ(read_file(a / "table.md"), read_file(b / "table.md"));
  EXPECT_EQ(summary_without_provenance(a / "summary.json"), summary_without_provenance(b / "summary.json"));
  EXPECT_EQ(summary_md_without_provenance(a / "summary.md"), summary_md_without_provenance(b / "summary.md"));
  EXPECT_EQ(read_file(a / "scenarios" / "index.json"), read_file(b / "scenarios" / "index.json"));
  EXPECT_EQ(entries(a / "scenarios"), entries(b / "scenarios"));
  for (const auto& f : entries(a / "scenarios")) EXPECT_EQ(read_file(a / "scenarios" / f), read_file(b / "scenarios" / f)) << f;
  EXPECT_EQ(entries(a / "runs"), entries(b / "runs"));
  EXPECT_EQ(entries(a / "failures"), entries(b / "failures"));
  for (const auto& r : entries(a / "runs")) EXPECT_EQ(entries(a / "runs" / r), entries(b / "runs" / r)) << r;
  fs::remove_all(root);
}

TEST(ShardedSweep, MergeRefusesMissingRepeatedForeignAndIncompleteShards) {
  const fs::path root = temp_dir("shard_errors");
  tactile_cli::run_sweep(family_sweep(root / "s1", 3, 4000, 1, 2));
  tactile_cli::run_sweep(family_sweep(root / "s2", 3, 4000, 2, 2));
  tactile_cli::run_sweep(family_sweep(root / "other2", 3, 4100, 2, 2));  // another sweep's shard 2
  const auto expect_refused = [&](std::vector<std::string> dirs, const std::string& what) {
    tactile_cli::SweepMergeOptions m;
    m.out_dir = (root / "merged").string();
    for (const auto& d : dirs) m.shard_dirs.push_back((root / d).string());
    try {
      tactile_cli::merge_sweep(m);
      ADD_FAILURE() << "merged: " << what;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(root / "merged")) << what;  // nothing written
  };
  expect_refused({"s1"}, "shard(s) 2 of 2 not given");
  expect_refused({"s1", "s1"}, "given twice");
  expect_refused({"s1", "other2"}, "seed 4100 differs");
  fs::create_directories(root / "empty");
  expect_refused({"s1", "empty"}, "shard.json: cannot read");
  // An interrupted shard, and one whose record is damaged.
  fs::copy(root / "s2", root / "s2_interrupted", fs::copy_options::recursive);
  auto rec = nlohmann::json::parse(read_file(root / "s2_interrupted" / "shard.json"));
  rec["interrupted"] = true;
  std::ofstream(root / "s2_interrupted" / "shard.json") << rec.dump();
  expect_refused({"s1", "s2_interrupted"}, "is incomplete (1 of 1 environments flown, interrupted)");
  fs::copy(root / "s2", root / "s2_damaged", fs::copy_options::recursive);
  std::ofstream(root / "s2_damaged" / "shard.json") << read_file(root / "s2" / "shard.json").substr(0, 100);
  expect_refused({"s1", "s2_damaged"}, (root / "s2_damaged" / "shard.json").string() + ": ");
  for (const auto& [key, value, what] : std::vector<std::tuple<std::string, nlohmann::json, std::string>>{
           {"environments_all", 1e18, "environments_all: wrong type (number)"},
           {"environments_all", uint64_t{1} << 60, "expected a whole number in 1..10000000"},
           {"shard", "2", "shard: wrong type (string)"},
           {"shard", (uint64_t{1} << 32) + 1, "outside 1..2"},
           {"rows", nlohmann::json::object(), "rows: wrong type (object)"}}) {
    fs::remove_all(root / "s2_bad");
    fs::copy(root / "s2", root / "s2_bad", fs::copy_options::recursive);
    auto bad = nlohmann::json::parse(read_file(root / "s2" / "shard.json"));
    bad[key] = value;
    std::ofstream(root / "s2_bad" / "shard.json") << bad.dump();
    expect_refused(key == "shard" || key == "rows" ? std::vector<std::string>{"s1", "s2_bad"}
                                                   : std::vector<std::string>{"s2_bad", "s1"},
                   what);
  }
  // More shards than environments, and bad K/M texts.
  EXPECT_THROW(tactile_cli::run_sweep(family_sweep(root / "s9", 3, 4000, 1, 4)), std::invalid_argument);
  int k = 0, n = 0;
  for (const char* bad : {"0/2", "3/2", "1/0", "a/b", "2", "1/100001", "-1/2", "1/2/3", ""}) {
    EXPECT_THROW(tactile_cli::parse_shard(bad, k, n), std::invalid_argument) << bad;
  }
  tactile_cli::parse_shard("2/3", k, n);
  EXPECT_EQ(k, 2);
  EXPECT_EQ(n, 3);
  fs::remove_all(root);
}
