// SITL scenario tests of the whisker stage (paper 002) in the graph
// `whisker_stage`: the simulator's whisker_stage vehicle produces the base
// moments of the nitinol whisker (elastica model, Hall noise), the stage
// controller runs the Table I / Table II protocols, the whisker_localization
// node localizes. Each run is seeded (the scenario's seed).
#include <gtest/gtest.h>

#include <string>

#include "sim_test_util.hpp"

namespace {

nlohmann::json run(const std::string& scenario) {
  nlohmann::json m = tactile_cli::test::run_scenario(scenario);
  if (m.contains("per_trial")) return m["per_trial"][0];
  return m;
}

}  // namespace

TEST(WhiskerStageSitl, TableTwoEverySweepLocalizesWithinFiveMillimetres) {
  const auto m = run("whisker_stage_table2.yaml");
  const auto& w = m["whisker_localization"];
  EXPECT_TRUE(w["finished"].get<bool>());
  EXPECT_EQ(w["variant"], "deterministic");
  ASSERT_EQ(w["sweeps"].size(), 5u);
  for (const auto& s : w["sweeps"]) {
    SCOPED_TRACE(s.dump());
    EXPECT_GE(s["localizing_steps"].get<int>(), 25);
    // 002 Table II: 2.79-7.30 mm; issue goal < 5 mm for every sweep.
    EXPECT_LT(s["mean_localization_error_mm"].get<double>(), 5.0);
    EXPECT_GE(s["truth_kept_fraction"].get<double>(), 0.95);
    EXPECT_LT(s["profile_max_error_mm"].get<double>(), 0.5);  // 002 Fig. 12: the swept profile on the boundary
  }
}

TEST(WhiskerStageSitl, PossibilisticKeepsTheTruthUnderBoundedFivePercentNoise) {
  const auto det = run("whisker_stage_table2_noise5.yaml")["whisker_localization"];
  const auto pos = run("whisker_stage_table2_noise5_possibilistic.yaml")["whisker_localization"];
  EXPECT_EQ(pos["variant"], "possibilistic");
  uint64_t det_resets = 0;
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_GE(pos["sweeps"][i]["truth_kept_fraction"].get<double>(), 0.99) << i;
    EXPECT_EQ(pos["sweeps"][i]["resets"].get<int>(), 0) << i;
    det_resets += det["sweeps"][i]["resets"].get<uint64_t>();
  }
  EXPECT_LT(det["truth_kept_fraction"].get<double>(), 0.9);  // the deterministic set loses the truth ...
  EXPECT_GE(det_resets, 10u);                                 // ... and empties repeatedly
}

TEST(WhiskerStageSitl, TableOneOursWithinOnePercentAndBetterThanEqFiveAtLargeDeflection) {
  const auto m = run("whisker_stage_table1.yaml");
  const auto& w = m["whisker_localization"];
  EXPECT_TRUE(w["finished"].get<bool>());
  ASSERT_EQ(w["table1"].size(), 15u);
  for (const auto& r : w["table1"]) {
    SCOPED_TRACE(r.dump());
    EXPECT_EQ(r["ours_failures"].get<int>(), 0);
    EXPECT_LE(r["ours_error_pct"].get<double>(), 1.0);  // issue goal: <= 1 % in SITL (002: 0.3-2.1 %)
    if (r["t_y_mm"].get<double>() > 4.0) {              // large deflection: eq. 5 breaks down
      EXPECT_LT(r["ours_error_pct"].get<double>(), r["baseline_error_pct"].get<double>());
    }
  }
}
