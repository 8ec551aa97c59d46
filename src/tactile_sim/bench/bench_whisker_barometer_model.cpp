#include <benchmark/benchmark.h>

#include "tactile_sim/whisker_barometer_model.hpp"

static void BM_WhiskerBarometerStep(benchmark::State& state) {
  tactile_sim::WhiskerBarometerModel m(tactile_sim::WhiskerBarometerParams{}, 1);
  int k = 0;
  for (auto _ : state) {
    const double load = (k++ % 500) < 100 ? 2e-4 : 0.0;
    benchmark::DoNotOptimize(m.step(0.02, load, true));
  }
}
BENCHMARK(BM_WhiskerBarometerStep);

BENCHMARK_MAIN();
