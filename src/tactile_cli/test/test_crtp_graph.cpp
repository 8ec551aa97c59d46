// Graph whisker_fsm_crtp: the whisker pipeline flown through crazyflie_bridge
// and a simulated Crazyflie firmware in lockstep. On a clean link it gives
// the in-process whisker_fsm outcome (the only difference on the wire is the
// float32 log encoding); with 30 % loss the link metrics count exactly what
// was dropped; runs are reproducible for a seed.
#include <gtest/gtest.h>

#include <filesystem>

#include "tactile_cli/sim_run.hpp"

namespace fs = std::filesystem;

namespace {
nlohmann::json run(const std::string& name, const std::string& tag) {
  tactile_cli::SimOptions o;
  o.scenario = std::string(TACTILE_CONFIG_DIR "/scenarios/") + name + ".yaml";
  o.out_dir = (fs::temp_directory_path() / ("tactile_crtp_graph_" + std::to_string(::getpid()) + "_" + tag)).string();
  fs::remove_all(o.out_dir);
  o.config_dir = TACTILE_CONFIG_DIR;
  o.write_bag = false;
  o.write_png = false;
  o.progress = false;
  auto m = tactile_cli::run_sim(o);
  fs::remove_all(o.out_dir);
  return m;
}
}  // namespace

TEST(CrtpGraph, CleanLinkGivesTheInProcessOutcome) {
  const auto ref = run("whisker_darkness_rigid_fsm", "ref");
  const auto m = run("whisker_darkness_rigid_crtp", "crtp");
  EXPECT_EQ(m["fsm"]["reached_target"], ref["fsm"]["reached_target"]);
  EXPECT_EQ(m["fsm"]["final_state"], ref["fsm"]["final_state"]);
  EXPECT_EQ(m["collisions"], ref["collisions"]);
  EXPECT_EQ(m["fsm"]["wall_following_episodes"], ref["fsm"]["wall_following_episodes"]);
  EXPECT_NEAR(m["fsm"]["depth_in_band_fraction"].get<double>(), ref["fsm"]["depth_in_band_fraction"].get<double>(), 0.02);
  EXPECT_NEAR(m["fsm"]["mean_abs_heading_error_deg"].get<double>(), ref["fsm"]["mean_abs_heading_error_deg"].get<double>(), 0.5);
  // Link: nothing lost; both log blocks (50 Hz whiskers, 100 Hz state) complete
  // for the 30 s flight; every setpoint the bridge sent reached the firmware.
  EXPECT_EQ(m["fsm"]["link_packets_lost"].get<uint64_t>(), 0u);
  EXPECT_EQ(m["fsm"]["link_log_missed"].get<uint64_t>(), 0u);
  EXPECT_EQ(m["fsm"]["bridge_log_samples_missed"].get<uint64_t>(), 0u);
  EXPECT_EQ(m["fsm"]["tdorc_samples_missing"].get<uint64_t>(), 0u);
  EXPECT_GE(m["fsm"]["link_packets_received"].get<uint64_t>(), 1500u + 3000u);
  EXPECT_EQ(m["fsm"]["bridge_stale_events"].get<uint64_t>(), 0u);
  EXPECT_GT(m["fsm"]["firmware_setpoints"].get<uint64_t>(), 1000u);
  EXPECT_GT(m["fsm"]["link_packets_sent"].get<uint64_t>(), m["fsm"]["firmware_setpoints"].get<uint64_t>());
}

TEST(CrtpGraph, LossyLinkCountsLossAndIsReproducible) {
  const auto a = run("whisker_darkness_rigid_crtp_loss30", "a");
  const auto b = run("whisker_darkness_rigid_crtp_loss30", "b");
  EXPECT_EQ(a["fsm"], b["fsm"]);  // same seed, same everything (lockstep, seeded loss)
  const auto& f = a["fsm"];
  const auto dropped = f["link_log_dropped"].get<uint64_t>();
  const auto missed = f["link_log_missed"].get<uint64_t>();
  // 30 % of the ~7500 log packets (whiskers 50 Hz, attitude and state 100 Hz,
  // 30 s; ~4500 before the attitude block); the client's timestamp-gap count
  // and the bridge logic's sequence gaps match the injected drops except
  // packets lost before a block's first or after its last received sample.
  EXPECT_GT(dropped, 1900u);
  EXPECT_LT(dropped, 2600u);
  EXPECT_LE(missed, dropped);
  EXPECT_GE(missed + 10, dropped);
  const auto seq_missed = f["bridge_log_samples_missed"].get<uint64_t>();
  EXPECT_LE(seq_missed, dropped);
  EXPECT_GE(seq_missed + 10, dropped);
  // The lost whisker packets are sequence gaps that both tdorc_filters bridge
  // (~30 % of 2 x 1500 samples; a gap longer than max_sample_gap_s resets instead).
  EXPECT_GT(f["tdorc_samples_missing"].get<uint64_t>(), 600u);
  EXPECT_GT(f["tdorc_gaps_bridged"].get<uint64_t>(), 300u);
  EXPECT_GT(f["link_resends"].get<uint64_t>(), 0u);  // connect survived lost requests
  // Lost setpoints: the firmware received about 70 % of what the bridge sent.
  const double ratio = static_cast<double>(f["firmware_setpoints"].get<uint64_t>()) /
                       static_cast<double>(f["link_packets_sent"].get<uint64_t>());
  EXPECT_GT(ratio, 0.6);
  EXPECT_LT(ratio, 0.8);
}
