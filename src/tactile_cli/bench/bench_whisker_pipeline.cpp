// One 50 Hz tick of the whiskered drone's onboard pipeline (paper 000, Fig. S6
// budget): 6 TDORC channels (two tdorc_filter node logics), tactile depth (2
// MLP inferences + KF with the full process model) and the wall-following
// FSM, through the same node-logic classes the components and the host run.
// Also prints the state/model sizes against the paper's 9.6 KB depth budget.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>

#include "tactile_common/time.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"

namespace {

tactile_msgs::msg::WhiskerPressure pressure(uint8_t id, int64_t t_ns, double contact) {
  tactile_msgs::msg::WhiskerPressure m;
  tactile_common::to_stamp(t_ns, m.header.stamp);
  m.whisker_id = id;
  const double t = tactile_common::to_seconds(t_ns);
  for (size_t c = 0; c < 3; ++c) {
    m.pressure[c] = 101325.0 + 2000.0 * static_cast<double>(c) + 3.0 * t + contact * (150.0 - 40.0 * static_cast<double>(c)) +
                    std::sin(7.0 * t + static_cast<double>(c));
    m.temperature[c] = 25.0;
  }
  m.sequence = static_cast<uint32_t>(t_ns / 20000000);
  return m;
}

}  // namespace

static void BM_WhiskerPipelineTick(benchmark::State& state) {
  using tdorc_filter::TdorcFilterLogic;
  auto tp = TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters());
  TdorcFilterLogic left(tp), right(tp);
  using tactile_depth::TactileDepthLogic;
  TactileDepthLogic depth(TactileDepthLogic::params_from(TactileDepthLogic::default_parameters()));
  using tactile_fsm::WhiskerFsmLogic;
  WhiskerFsmLogic fsm(WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters()));
  nav_msgs::msg::Odometry odom;
  odom.pose.pose.orientation.w = 1.0;
  int64_t t = 0;
  // Fill the TDORC windows in free flight, then every tick is in contact.
  for (int k = 0; k < 150; ++k, t += 20000000) {
    left.on_pressure(pressure(0, t, 0.0));
    right.on_pressure(pressure(1, t, 0.0));
  }
  for (auto _ : state) {
    const double contact = 1.0;
    tactile_common::to_stamp(t, odom.header.stamp);
    depth.on_odometry(odom);
    fsm.on_odometry(odom);
    auto sl = left.on_pressure(pressure(0, t, contact));
    auto sr = right.on_pressure(pressure(1, t, contact));
    if (sl) {
      fsm.on_left_signal(*sl);
      depth.on_left_signal(*sl);
    }
    if (sr) {
      fsm.on_right_signal(*sr);
      if (auto d = depth.on_right_signal(*sr)) fsm.on_depth(*d);
    }
    benchmark::DoNotOptimize(fsm.on_timer(t));
    t += 20000000;
  }
  state.counters["tdorc_state_bytes_per_whisker"] = static_cast<double>(left.whisker().state_size_bytes());
  state.counters["depth_estimator_bytes"] = static_cast<double>(depth.estimator().state_size_bytes());
}
BENCHMARK(BM_WhiskerPipelineTick);

BENCHMARK_MAIN();
