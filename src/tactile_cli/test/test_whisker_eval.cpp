// WallFollowingEvaluation against hand-counted samples: FSM transitions on
// /fsm_state and whisker truth added by stamp (as `tactile fly` fills it from
// the simulated Crazyflie), with and without an end of the run.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_cli/host.hpp"
#include "tactile_cli/whisker_eval.hpp"
#include "tactile_common/time.hpp"

namespace {

using tactile_cli::WallFollowingEvaluation;
using tactile_cli::WhiskerTruth;

constexpr int64_t kMs = 1000000;

void publish_state(tactile_cli::Host& host, int64_t t_ns, const std::string& state) {
  tactile_msgs::msg::FsmState m;
  tactile_common::to_stamp(t_ns, m.header.stamp);
  m.state = state;
  host.bus().publish("/fsm_state", m, t_ns);
}

/// A host with the evaluation (band [40, 100] mm, spacing 50 mm) on an
/// initially empty truth; the FSM flies forward from t = 0 and starts
/// following the wall at 1 s.
struct Fixture {
  tactile_cli::Host host{TACTILE_CONFIG_DIR};
  WhiskerTruth truth;
  WallFollowingEvaluation eval{host, truth, 0.040, 0.100, 0.05};
  Fixture() {
    publish_state(host, 0, "FLY_FORWARD");
    publish_state(host, 1000 * kMs, "WALL_FOLLOWING/FLY_SIDEWAYS");
  }
};

}  // namespace

TEST(WallFollowingEvaluation, CountsTruthSamplesOfTheFirstSweep) {
  Fixture f;
  tactile_cli::Host& host = f.host;
  WhiskerTruth& truth = f.truth;
  const WallFollowingEvaluation& eval = f.eval;
  publish_state(host, 1100 * kMs, "WALL_FOLLOWING/TURN_LEFT");  // same episode
  publish_state(host, 2000 * kMs, "RESUME_FORWARD");
  // 50 Hz truth from 0 to 2.98 s. Samples 1.00..1.98 s (50) are in the sweep:
  // the first 30 both in contact at 80 / 80 mm (in band, heading 0); the next
  // 10 at 110 / 60 mm (left out of band; |atan(0.05 / 0.05)| = 45 deg); the last
  // 10 without contact (not counted). Before and after: in band but not
  // wall following (not counted).
  for (int i = 0; i < 150; ++i) {
    const int64_t t = i * 20 * kMs;
    WhiskerTruth::Sample l{true, 0.080}, r{true, 0.080};
    if (t >= 1600 * kMs && t < 1800 * kMs) l.depth = 0.110, r.depth = 0.060;
    if (t >= 1800 * kMs && t < 2000 * kMs) l.contact = r.contact = false;
    truth.add(0, t, l);
    truth.add(1, t, r);
  }
  const auto m = eval.metrics();
  EXPECT_EQ(m["wall_following_contact_samples"].get<size_t>(), 40u);
  EXPECT_NEAR(m["depth_in_band_fraction"].get<double>(), 30.0 / 40.0, 1e-12);
  EXPECT_NEAR(m["first_sweep_in_band_fraction"].get<double>(), 30.0 / 40.0, 1e-12);
  EXPECT_NEAR(m["mean_abs_heading_error_deg"].get<double>(), 10.0 * 45.0 / 40.0, 1e-9);
  EXPECT_NEAR(m["first_sweep_start_s"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(m["first_sweep_s"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(m["wall_following_episodes"].get<size_t>(), 1u);
  EXPECT_EQ(m["final_state"], "RESUME_FORWARD");
}

TEST(WallFollowingEvaluation, EndOfRunCutsARunningSweepAndNoTruthGivesNull) {
  Fixture f;
  WhiskerTruth& truth = f.truth;
  const WallFollowingEvaluation& eval = f.eval;
  // Without truth (a real Crazyflie): the sweep lasts to the end of the run,
  // the truth-based fields are null.
  auto m = eval.metrics(3500 * kMs);
  EXPECT_NEAR(m["first_sweep_s"].get<double>(), 2.5, 1e-12);
  EXPECT_TRUE(m["first_sweep_in_band_fraction"].is_null());
  EXPECT_TRUE(m["mean_abs_heading_error_deg"].is_null());
  // Truth continues after the pipeline stopped (the vehicle lands): samples
  // after the end are not the FSM's and are not counted. 1.00..3.50 s: 126.
  for (int i = 0; i < 250; ++i) {
    truth.add(0, i * 20 * kMs, {true, 0.050});
    truth.add(1, i * 20 * kMs, {true, 0.050});
  }
  m = eval.metrics(3500 * kMs);
  EXPECT_EQ(m["wall_following_contact_samples"].get<size_t>(), 126u);
  EXPECT_NEAR(m["first_sweep_s"].get<double>(), 2.5, 1e-12);
  // The first 7 s window holds every sample of a 2.5 s sweep.
  EXPECT_NEAR(m["first_sweep_in_band_fraction"].get<double>(), 1.0, 1e-12);
  // A sample of one whisker without its partner is skipped, not paired wrongly.
  truth.add(0, 3510 * kMs, {true, 0.2});
  EXPECT_EQ(eval.metrics()["wall_following_contact_samples"].get<size_t>(), 200u);
}
