#include <benchmark/benchmark.h>

#include "whisker_localization/elastica.hpp"

using namespace whisker_localization;

static void BM_ForceModeNormal(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_normal(0.005, 0.06));
}
BENCHMARK(BM_ForceModeNormal);

static void BM_ForceModeFixedDirection(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_fixed(0.005, 1.5707963, 0.06));
}
BENCHMARK(BM_ForceModeFixedDirection);

static void BM_PointMode(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_point(0.055, 0.008));
}
BENCHMARK(BM_PointMode);

BENCHMARK_MAIN();
