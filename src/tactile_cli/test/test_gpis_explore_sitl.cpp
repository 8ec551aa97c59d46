// SITL scenario tests of GPIS active exploration (gpis_explorer, paper 000
// "Active aerial tactile exploration", Fig. 5) in the full whisker graph:
// simulator -> TDORC x2 -> tactile_depth -> gpis_explorer -> /cmd_hover.
//
// Paper: 5 trials in randomly rotated 2 m rooms with an 80 cm exit, 4/5 find
// the exit, reconstruction error 0.09 +- 0.01 m, travel 22.62 +- 6.26 m.
//
// What is asserted (and can fail): in every one of 5 seeded trials per budget
// the explorer reports the exit, the true final position is outside the room
// and the guard never touched a wall (`success`: the paper's 4/5, the issue's
// goal 5/5); the mean reconstruction error of the mapped contact points is
// <= 0.08 m; travel is below the paper's mean + 2 std.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sim_test_util.hpp"

namespace fs = std::filesystem;

namespace {

nlohmann::json run_trials(const std::string& scenario, int trials) { return tactile_cli::test::run_scenario(scenario, trials); }

void expect_collision_free_exits(const std::string& scenario, int budget_points) {
  SCOPED_TRACE(scenario);
  const auto m = run_trials(scenario, 5);
  int out = 0;
  double err = 0.0;
  int n_err = 0;
  for (const auto& r : m["per_trial"]) {
    const auto& g = r["gpis"];
    EXPECT_EQ(g["budget_max_points"].get<int>(), budget_points);
    EXPECT_LE(g["training_points"].get<int>(), budget_points);
    EXPECT_GE(g["gpis_updates"].get<int>(), 1);
    EXPECT_LT(g["travel_distance_m"].get<double>(), 22.62 + 2 * 6.26);
    if (g["exit_found"].get<bool>() && g["outside_room"].get<bool>()) ++out;
    EXPECT_GT(g["map_points"].get<int>(), 0);
    ASSERT_TRUE(g["map_reconstruction_error_m"].is_number());
    EXPECT_LE(g["map_reconstruction_error_m"].get<double>(), 0.08);
    if (g["reconstruction_error_m"].is_number()) {
      err += g["reconstruction_error_m"].get<double>();
      ++n_err;
    }
  }
  EXPECT_EQ(out, 5);
  // Paper-level acceptance: exit found, flown through and no guard collision.
  std::string phases;
  for (const auto& r : m["per_trial"]) phases += r["gpis"]["collision_phases"].dump() + " ";
  EXPECT_EQ(m["success_count"].get<int>(), 5) << "collisions by phase per trial: " << phases;
  ASSERT_GT(n_err, 0);
  EXPECT_LE(err / n_err, 0.08);
  // The aggregate's top-level summary (issue / 000 Fig. 5 names) is the mean over the trials.
  ASSERT_TRUE(m.contains("mean_reconstruction_error_m"));
  EXPECT_NEAR(m["mean_reconstruction_error_m"].get<double>(), err / n_err, 1e-12);
  EXPECT_GE(m["std_reconstruction_error_m"].get<double>(), 0.0);
  double travel = 0.0;
  for (const auto& r : m["per_trial"]) travel += r["gpis"]["travel_distance_m"].get<double>();
  EXPECT_NEAR(m["mean_travel_distance_m"].get<double>(), travel / 5.0, 1e-9);
  EXPECT_GE(m["mean_gpis_updates"].get<double>(), 1.0);
  // Inputs never stale in these trials: the fail-safe never fires (issue 33).
  for (const auto& r : m["per_trial"]) EXPECT_EQ(r["gpis"]["failsafe_hovers"].get<int>(), 0);
}

}  // namespace

TEST(GpisExploreSitl, RoomExitCollisionFreeOnboardBudget) {
  expect_collision_free_exits("whisker_room_exit_gpis.yaml", 50);
}

TEST(GpisExploreSitl, RoomExitCollisionFreeGroundBudget) {
  expect_collision_free_exits("whisker_room_exit_gpis_ground.yaml", 5000);
}

// Rooms the exploration was not tuned on (issue: sizes 1.5-3 m, exits on
// other walls, 60-100 cm wide): the paper's success rate, 4 of 5 seeded trials
// (seeds 11-15, random room yaw) find the exit, fly out and never touch a wall
// with the guard. Before whisking (straight probes at V_max) the 1.5 m room
// with its off-centre 60 cm exit was 2/5 and the 3 m room 3/5: an aligned
// probe crossed the exit with the jamb 2.5-8 cm beside its axis, outside the
// whiskers (+-2.5 cm) but inside the guard (8 cm).
void expect_untuned_room(const std::string& scenario) {
  SCOPED_TRACE(scenario);
  const auto m = run_trials(scenario, 5);
  std::string phases;
  int whisk_stops = 0;
  for (const auto& r : m["per_trial"]) {
    const auto& g = r["gpis"];
    phases += r["gpis"]["collision_phases"].dump() + " ";
    EXPECT_LE(g["training_points"].get<int>(), 50);
    whisk_stops += g["whisk_contacts"].get<int>();
  }
  EXPECT_GE(m["success_count"].get<int>(), 4) << "collisions by phase per trial: " << phases;
  EXPECT_GE(whisk_stops, 5 * 3);  // the probes were whisked: every trial met >= 3 walls while whisking
}

TEST(GpisExploreSitl, UntunedSmallRoomOffCentreExit) { expect_untuned_room("whisker_room_exit_gpis_small.yaml"); }

TEST(GpisExploreSitl, UntunedLargeRoom) { expect_untuned_room("whisker_room_exit_gpis_large.yaml"); }

// Issue 17's 2.2 m room with two 60 cm exits, here both beside a corner
// (seeds 101-105). The fit bends across each exit and puts a corner centroid
// in it; with every contour point near it excluded, trials 101 and 103 ended
// with `no_target` (3/5). corner_confirm_radius sets aside, when no target is
// left, the corners no touched point confirms: 103 flies out through an exit
// chosen so (4/5; 101 is still `no_target`). Seeds 101-150: exit 42 -> 44 of 50.
TEST(GpisExploreSitl, TwoExitsBesideCorners) {
  const auto m = run_trials("whisker_room_exit_gpis_two_exits.yaml", 5);
  EXPECT_GE(m["success_count"].get<int>(), 4);
  bool seen = false;
  for (const auto& r : m["per_trial"]) {
    if (r["seed"].get<uint64_t>() != 103) continue;
    seen = true;
    EXPECT_TRUE(r["success"].get<bool>()) << r["gpis"]["outcome"];
    EXPECT_GE(r["gpis"]["unconfirmed_corner_targets"].get<int>(), 1);
  }
  EXPECT_TRUE(seen);
}

// Issue 33: both whiskers' pressure drops out for 1 s (simulator fault) while
// the odometry goes on, 4 s into the exploration (the first probe). TDORC
// and tactile_depth stop, the depth goes stale, and gpis_explorer must hold
// in FAILSAFE_HOVER (it used to fly the probe on blind), then resume and
// still find and fly through the exit without touching a wall. Seeds 1-3.
TEST(GpisExploreSitl, WhiskerDropoutHoldsThenResumes) {
  const fs::path dir = fs::temp_directory_path() / ("tactile_gpis_dropout_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path scenarios = tactile_cli::test::config_dir() / "scenarios";
  std::ifstream in(scenarios / "whisker_room_exit_gpis.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string arena = "arena_file: arenas/room_exit.yaml";
  ASSERT_NE(yaml.find(arena), std::string::npos);
  yaml.replace(yaml.find(arena), arena.size(), "arena_file: " + (scenarios / "arenas" / "room_exit.yaml").string());
  yaml += "faults:\n"
          "  - {type: dropout, topic: /whisker/left/pressure, start_s: 6.0, duration_s: 1.0}\n"
          "  - {type: dropout, topic: /whisker/right/pressure, start_s: 6.0, duration_s: 1.0}\n";
  std::ofstream(dir / "gpis_dropout.yaml") << yaml;
  tactile_cli::SimOptions o;
  o.scenario = (dir / "gpis_dropout.yaml").string();
  o.out_dir = (dir / "out").string();
  o.config_dir = tactile_cli::test::config_dir().string();
  o.trials = 3;
  o.progress = false;
  o.write_bag = false;
  o.write_png = false;
  const nlohmann::json m = tactile_cli::run_sim(o);
  fs::remove_all(dir);
  for (const auto& r : m["per_trial"]) {
    SCOPED_TRACE("seed " + std::to_string(r["seed"].get<uint64_t>()));
    EXPECT_GE(r["gpis"]["failsafe_hovers"].get<int>(), 1);
    EXPECT_TRUE(r["success"].get<bool>()) << r["gpis"]["outcome"] << " " << r["gpis"]["collision_phases"].dump();
  }
}
