// One 100 Hz EKF step (004 eq. 21-25: predict + accel, gyro, flow, ToF
// updates) and one INDI step (eq. 26-36: outer loop + inner loop/allocation).
#include <benchmark/benchmark.h>

#include "wall_effect_ekf/indi_controller.hpp"
#include "wall_effect_ekf/wall_ekf.hpp"

using namespace wall_effect_ekf;

static void BM_EkfPredictUpdate(benchmark::State& state) {
  WallEkf ekf(EkfParams{});
  WallState x;
  x.y = 0.17;
  x.z = 1.0;
  ErrMat P = ErrMat::Identity() * 1e-3;
  ekf.reset(x, P);
  const Vec4 T(0.69, 0.68, 0.68, 0.69);
  const Vec3 a = predict_accel(x, T, EkfParams{}.vehicle);
  double s = 0.0;
  for (auto _ : state) {
    ekf.predict(T);
    ekf.update_accel(a);
    ekf.update_gyro(Vec3::Zero());
    ekf.update_flow(Vec2::Zero());
    ekf.update_tof(1.0);
    s += ekf.state().y;
  }
  benchmark::DoNotOptimize(s);
}
BENCHMARK(BM_EkfPredictUpdate);

static void BM_EkfPredictOnly(benchmark::State& state) {
  WallEkf ekf(EkfParams{});
  WallState x;
  x.y = 0.17;
  x.z = 1.0;
  ekf.reset(x, ErrMat::Identity() * 1e-3);
  const Vec4 T(0.69, 0.68, 0.68, 0.69);
  for (auto _ : state) {
    ekf.predict(T);
    benchmark::DoNotOptimize(ekf.state().y);
  }
}
BENCHMARK(BM_EkfPredictOnly);

static void BM_IndiStep(benchmark::State& state) {
  IndiController c(IndiParams{});
  IndiSetpoint sp;
  sp.position = Vec3(0.0, 0.17, 1.0);
  IndiFeedback fb;
  fb.position = Vec3(0.01, 0.18, 0.99);
  AllocationWall wall;
  wall.present = state.range(0) != 0;
  wall.y = 0.18;
  double s = 0.0;
  for (auto _ : state) {
    c.outer(sp, fb, 0.01);
    const auto f = c.inner(Vec3(0.01, -0.02, 0.0), 0.0, 0.0, wall);
    s += f[0];
  }
  benchmark::DoNotOptimize(s);
}
BENCHMARK(BM_IndiStep)->Arg(0)->Arg(1);

BENCHMARK_MAIN();
