// Cost of one 1 kHz physics step of the whiskered Crazyflie, whiskers in and
// out of contact, and of the whisker PRBM alone. Real-time factor at 1 kHz:
// 1 ms / (time per step).
#include <benchmark/benchmark.h>

#include "tactile_sim/crazyflie.hpp"

namespace {

using tactile_sim::Arena;
using tactile_sim::CrazyflieParams;
using tactile_sim::HoverSetpoint;
using tactile_sim::RigidBodyState;
using tactile_sim::StateEstimateMode;
using tactile_sim::Vec2;
using tactile_sim::Vec3;
using tactile_sim::WhiskerCrazyflie;

// A room of 4 walls plus a few extra obstacles, so culling is exercised.
Arena make_arena(double wall_x) {
  Arena a;
  const int room = a.add_obstacle("room");
  a.add_wall(Vec2(-2, -2), Vec2(2, -2), 0, room);
  a.add_wall(Vec2(2, -2), Vec2(2, 2), 0, room);
  a.add_wall(Vec2(2, 2), Vec2(-2, 2), 0, room);
  a.add_wall(Vec2(-2, 2), Vec2(-2, -2), 0, room);
  const int w = a.add_obstacle("front");
  a.add_wall(Vec2(wall_x, -1), Vec2(wall_x, 1), 0, w);
  const int c = a.add_obstacle("pipe");
  a.add_cylinder(Vec2(-1, 1), 0.1, 0, c);
  return a;
}

void step_bench(benchmark::State& st, bool contact, StateEstimateMode mode) {
  CrazyflieParams p;
  p.estimate_mode = mode;
  RigidBodyState s0;
  s0.position = Vec3(0, 0, 0.4);
  WhiskerCrazyflie cf(p, s0, 1);
  // Wall 0.12 m ahead of the whisker bases (in reach) or out of reach.
  const Arena arena = make_arena(contact ? p.whisker_base_x + 0.12 : 1.5);
  cf.set_setpoint(HoverSetpoint{0, 0, 0, 0.4, false});
  for (int i = 0; i < 3000; ++i) cf.step(1e-3, arena);
  if (contact != cf.whiskers()[0].contact) st.SkipWithError("unexpected contact state");
  for (auto _ : st) {
    cf.step(1e-3, arena);
    benchmark::DoNotOptimize(cf.state());
  }
  st.counters["rtf_1kHz"] = benchmark::Counter(
      static_cast<double>(st.iterations()) * 1e-3, benchmark::Counter::kIsRate);
}

void BM_StepWhiskersInContact(benchmark::State& st) { step_bench(st, true, StateEstimateMode::kMocap); }
void BM_StepWhiskersFree(benchmark::State& st) { step_bench(st, false, StateEstimateMode::kMocap); }
void BM_StepFlowDeckInContact(benchmark::State& st) { step_bench(st, true, StateEstimateMode::kFlowDeck); }

void BM_PrbmContact(benchmark::State& st) {
  tactile_sim::WhiskerParams p;
  double d = 0.01;
  for (auto _ : st) {
    benchmark::DoNotOptimize(tactile_sim::prbm_contact(p, d));
    d = d < 0.1 ? d + 1e-4 : 0.01;
  }
}

BENCHMARK(BM_StepWhiskersInContact);
BENCHMARK(BM_StepWhiskersFree);
BENCHMARK(BM_StepFlowDeckInContact);
BENCHMARK(BM_PrbmContact);

}  // namespace

BENCHMARK_MAIN();
