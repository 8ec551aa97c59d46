// Cost of one 50 Hz tick of the whisker wall-following FSM (000 Fig. S4e),
// during wall following with noisy in-band depths (the busiest state).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "tactile_fsm/whisker_wall_follower.hpp"

namespace {

void BM_WallFollowingTick(benchmark::State& state) {
  tactile_fsm::WhiskerWallFollower fsm{tactile_fsm::WallFollowerParams{}};
  // Pre-generated depths around 80 mm with a slowly varying tilt.
  std::vector<std::pair<double, double>> depths(4096);
  for (std::size_t k = 0; k < depths.size(); ++k) {
    const double tilt = 0.004 * std::sin(0.01 * static_cast<double>(k));
    const double n = 0.001 * std::sin(1.7 * static_cast<double>(k));
    depths[k] = {0.08 + tilt + n, 0.08 - tilt - n};
  }
  tactile_fsm::WallFollowerInput in;
  in.has_target = true;
  in.target_x = 100.0;
  in.left_valid = in.right_valid = true;
  double t = 0.0;
  // Hover, then contact: wall following.
  for (int k = 0; k < 120; ++k, t += 0.02) {
    in.t = in.depth_stamp = in.odom_stamp = t;
    in.depth_left = depths[0].first;
    in.depth_right = depths[0].second;
    fsm.step(in);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    in.t = in.depth_stamp = in.odom_stamp = t;
    in.depth_left = depths[i].first;
    in.depth_right = depths[i].second;
    auto o = fsm.step(in);
    benchmark::DoNotOptimize(o);
    t += 0.02;
    i = (i + 1) & 4095;
  }
  state.counters["wall_following"] = fsm.state() == tactile_fsm::FsmState::kWallFollowing ? 1.0 : 0.0;
}
BENCHMARK(BM_WallFollowingTick);

}  // namespace

BENCHMARK_MAIN();
