// Scenario test of tactile depth in the SITL (paper 000 Table 1): the two
// tactile-depth datasets (whiteboard: rigid wall + mocap; glass: glass wall +
// flow deck) are flown with a few seeded trials, and the MLP + KF with the full
// process model (000 eq. 21-30) must estimate the depth of each whisker better
// than the MLP alone (eq. 12-14), against the simulator's true depth
// (tactile_cli/whisker_eval.cpp). Seeds 21.. are outside the flights the
// default model was trained/validated/tested on (seeds 1..12).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "sim_test_util.hpp"

namespace fs = std::filesystem;

namespace {

nlohmann::json fly(const std::string& scenario, int trials) {
  return tactile_cli::test::run_scenario("depth_" + scenario + ".yaml", trials, 21);
}

double stat(const nlohmann::json& m, const std::string& model, const std::string& key) {
  const auto& s = m.at("statistics").at("depth." + model + "." + key);
  return s.at("mean").get<double>();
}

void expect_full_kf_beats_mlp(const std::string& scenario) {
  const nlohmann::json m = fly(scenario, 12);
  for (const char* key : {"mae_left_mm", "mae_right_mm", "rmse_left_mm", "rmse_right_mm"}) {
    const double mlp = stat(m, "mlp", key), simplified = stat(m, "mlp_kf_simplified", key),
                 full = stat(m, "mlp_kf_full", key);
    std::cout << scenario << " " << key << ": mlp " << mlp << ", kf_simplified " << simplified << ", kf_full "
              << full << "\n";
    // The errors are of the order of 000 Table 1 (4-15 mm; ours up to ~23 mm
    // RMSE on the whiteboard, whose stick-slip scatters S_c), not a
    // degenerate run (no contact gives no samples and throws above).
    EXPECT_GT(mlp, 1.0) << scenario << " " << key;
    EXPECT_LT(mlp, 30.0) << scenario << " " << key;
    // Asserted on the MAE of each whisker; the RMSE is reported (measured
    // lower for the full KF too, see tactile_depth/README.md).
    if (std::string(key).rfind("mae", 0) == 0) {
      EXPECT_LT(full, mlp) << scenario << " " << key;
    }
  }
  for (const char* key : {"mae_orientation_deg", "mae_reconstruction_mm"}) {
    std::cout << scenario << " " << key << ": mlp " << stat(m, "mlp", key) << ", kf_full "
              << stat(m, "mlp_kf_full", key) << "\n";
  }
}

}  // namespace

TEST(DepthSitl, WhiteboardFullKfBeatsMlp) { expect_full_kf_beats_mlp("whiteboard"); }

TEST(DepthSitl, GlassFullKfBeatsMlp) { expect_full_kf_beats_mlp("glass"); }
