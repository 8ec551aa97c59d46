// Arena query cost per call (closest, raycast, first_hit, contact step) on the
// paper arenas and on a synthetic large arena (bounding-box culling). One
// physics step of the whiskered Crazyflie needs about 2 whisker first_hit +
// 1 body contact + 1-5 ToF raycasts.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/contact.hpp"

using namespace tactile_sim;

namespace {

Arena paper_arena(int which) {
  static const char* kFiles[] = {"wall", "room_exit", "three_baffles", "xplorer_box"};
  return Arena::load(std::string(TACTILE_CONFIG_DIR) + "/scenarios/arenas/" + kFiles[which] + ".yaml");
}

// n x n grid of 0.4 m boxes (4 walls each), 1 m apart.
Arena large_arena(int n) {
  Arena a;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int id = a.add_obstacle("b");
      const Vec2 c(i * 1.0, j * 1.0);
      const Vec2 p[4] = {c + Vec2(-0.2, -0.2), c + Vec2(0.2, -0.2), c + Vec2(0.2, 0.2), c + Vec2(-0.2, 0.2)};
      for (int k = 0; k < 4; ++k) a.add_wall(p[k], p[(k + 1) % 4], 0, id);
    }
  }
  return a;
}

// Deterministic query points sweeping the arena.
Vec2 query_point(int i, const Bounds& b) {
  const double u = 0.5 + 0.5 * std::sin(0.37 * i), v = 0.5 + 0.5 * std::cos(0.23 * i);
  return b.min + Vec2(u * (b.max.x() - b.min.x() + 0.4) - 0.2, v * (b.max.y() - b.min.y() + 0.4) - 0.2);
}

template <class Q>
void run(benchmark::State& state, const Arena& a, Q&& q) {
  const Bounds b = a.bounds();
  int i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(q(query_point(i, b), i));
    i = (i + 1) & 1023;
  }
  state.counters["walls"] = static_cast<double>(a.walls().size());
}

Arena make(const benchmark::State& state) {
  return state.range(0) < 4 ? paper_arena(static_cast<int>(state.range(0)))
                            : large_arena(static_cast<int>(state.range(0)));
}

}  // namespace

static void BM_Closest(benchmark::State& state) {
  const Arena a = make(state);
  run(state, a, [&](const Vec2& p, int) { return a.closest(p, 0.15); });
}
static void BM_Raycast(benchmark::State& state) {
  const Arena a = make(state);
  run(state, a, [&](const Vec2& p, int i) {
    return a.raycast(p, Vec2(std::cos(0.1 * i), std::sin(0.1 * i)), 4.0);  // VL53L1x range 4 m
  });
}
static void BM_FirstHitWhisker(benchmark::State& state) {
  const Arena a = make(state);
  run(state, a, [&](const Vec2& p, int i) {
    return a.first_hit(p, p + 0.12 * Vec2(std::cos(0.1 * i), std::sin(0.1 * i)));  // ~12 cm shaft
  });
}
static void BM_ContactStep(benchmark::State& state) {
  const Arena a = make(state);
  CircleContact c;
  run(state, a, [&](const Vec2& p, int) { return c.step(a, p, 0.06, Vec2(0.2, 0.0)); });
}

// Args: 0 wall, 1 room_exit, 2 three_baffles, 3 xplorer_box, >= 4: n x n boxes.
#define ARENAS Arg(0)->Arg(1)->Arg(2)->Arg(3)->Arg(10)->Arg(30)
BENCHMARK(BM_Closest)->ARENAS;
BENCHMARK(BM_Raycast)->ARENAS;
BENCHMARK(BM_FirstHitWhisker)->ARENAS;
BENCHMARK(BM_ContactStep)->ARENAS;

BENCHMARK_MAIN();
