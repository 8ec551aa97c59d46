// Benchmarks of the XPLORER force estimator: one arm-rate step (eq. 2-7) and
// one IMU-rate step (eq. 5 + yaw observer).
#include <benchmark/benchmark.h>

#include "xplorer_force_est/force_estimator.hpp"

using namespace xplorer_force_est;

static void BM_ArmStep(benchmark::State& state) {
  XplorerForceEstimator est{Params{}};
  est.set_thrust(11.0);
  est.update_imu(Vec3(0.1, 0, 9.81), Vec3::Zero(), Quat::Identity(), 0.002);
  std::array<double, 4> th{0.02, -0.02, 0.001, 0.0};
  for (auto _ : state) {
    th[0] += 1e-9;
    benchmark::DoNotOptimize(est.update_arms(th, 0.02));
  }
}
BENCHMARK(BM_ArmStep);

static void BM_ImuStep(benchmark::State& state) {
  XplorerForceEstimator est{Params{}};
  est.set_thrust(11.0);
  est.set_rotor_thrusts({2.7, 2.8, 2.7, 2.8});
  Vec3 a(0.1, 0, 9.81);
  for (auto _ : state) {
    a.x() += 1e-9;
    est.update_imu(a, Vec3(0, 0, 0.1), Quat::Identity(), 0.002);
    benchmark::DoNotOptimize(est.estimate());
  }
}
BENCHMARK(BM_ImuStep);

BENCHMARK_MAIN();
