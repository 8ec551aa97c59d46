// One 50 Hz tick of the tactile depth estimator (2 MLP 3-32-32-32-1 + 2 KF +
// full process model), and the state / model sizes vs the paper's 9.6 kB
// (000 Fig. S6).
#include <benchmark/benchmark.h>

#include <cmath>

#include "tactile_depth/depth_estimator.hpp"
#include "test_models.hpp"

using namespace tactile_depth;

static void run(benchmark::State& state, EstimatorModel model) {
  Params p;
  p.model = model;
  TactileDepthEstimator est(p, test_models::onboard_shape_mlp(1), test_models::onboard_shape_mlp(2));
  TickInput in;
  in.contact_left = in.contact_right = true;
  int k = 0;
  for (auto _ : state) {
    in.sp_left = {{30.0 + std::sin(0.1 * k), 5.0, -3.0}};
    in.sp_right = {{28.0, 4.0 + std::cos(0.1 * k), -2.0}};
    in.pose = {0.004 * k, 0.001 * k, 0.01 * std::sin(0.05 * k)};
    benchmark::DoNotOptimize(est.update(in));
    ++k;
  }
  state.counters["state_bytes"] = static_cast<double>(est.state_size_bytes());
  state.counters["filter_state_bytes"] = static_cast<double>(est.filter_state_bytes());
  state.counters["model_bytes_double"] = static_cast<double>(est.model_bytes());
  state.counters["one_model_bytes_f32"] = static_cast<double>(est.model(0).parameter_bytes_float32());
  state.counters["paper_budget_bytes"] = static_cast<double>(TactileDepthEstimator::kPaperBudgetBytes);
}

static void BM_TickKfFull(benchmark::State& state) { run(state, EstimatorModel::kKfFull); }
static void BM_TickKfSimplified(benchmark::State& state) { run(state, EstimatorModel::kKfSimplified); }
static void BM_TickMlpOnly(benchmark::State& state) { run(state, EstimatorModel::kMlp); }

static void BM_MlpPredict(benchmark::State& state) {
  const MlpModel m = test_models::onboard_shape_mlp(1);
  std::array<double, 3> x{{30.0, 5.0, -3.0}};
  for (auto _ : state) {
    x[0] += 1e-3;
    benchmark::DoNotOptimize(m.predict(x));
  }
}

BENCHMARK(BM_TickKfFull);
BENCHMARK(BM_TickKfSimplified);
BENCHMARK(BM_TickMlpOnly);
BENCHMARK(BM_MlpPredict);
BENCHMARK_MAIN();
