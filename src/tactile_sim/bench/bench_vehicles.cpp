// One physics step of each vehicle (hovering near a wall, so the arena
// queries, wall effect and contact checks run), and one sample of each sensor.
#include <benchmark/benchmark.h>

#include "tactile_sim/ducted_quad.hpp"
#include "tactile_sim/sensors.hpp"
#include "tactile_sim/xplorer.hpp"

using namespace tactile_sim;

namespace {

Arena room() {
  // 4 x 4 m room plus a box and a pipe: 10 wall segments, 1 cylinder.
  Arena a;
  const int r = a.add_obstacle("room");
  a.add_wall(Vec2(-2, -2), Vec2(2, -2), 0, r);
  a.add_wall(Vec2(2, -2), Vec2(2, 2), 0, r);
  a.add_wall(Vec2(2, 2), Vec2(-2, 2), 0, r);
  a.add_wall(Vec2(-2, 2), Vec2(-2, -2), 0, r);
  const int b = a.add_obstacle("box");
  a.add_wall(Vec2(1, 1), Vec2(1.5, 1), 0, b);
  a.add_wall(Vec2(1.5, 1), Vec2(1.5, 1.5), 0, b);
  a.add_wall(Vec2(1.5, 1.5), Vec2(1, 1.5), 0, b);
  a.add_wall(Vec2(1, 1.5), Vec2(1, 1), 0, b);
  a.add_cylinder(Vec2(-1, 1), 0.1, 0, a.add_obstacle("pipe"));
  return a;
}

RigidBodyState near_wall() {
  RigidBodyState s;
  s.position = Vec3(0.0, -1.82, 0.8);  // 18 cm from the south wall (004 flight)
  return s;
}

}  // namespace

static void BM_DuctedQuadStep(benchmark::State& state) {
  const Arena a = room();
  DuctedQuad q(DuctedQuadParams{}, near_wall());
  PositionSetpoint sp;
  sp.position = near_wall().position;
  q.set_position_setpoint(sp);
  for (int k = 0; k < 1000; ++k) q.step(0.001, a);
  for (auto _ : state) {
    q.step(0.001, a);
    benchmark::DoNotOptimize(q.state());
  }
}
BENCHMARK(BM_DuctedQuadStep);

static void BM_XplorerStep(benchmark::State& state) {
  const Arena a = room();
  Xplorer v(XplorerParams{}, near_wall());
  PositionSetpoint sp;
  sp.position = near_wall().position;
  v.set_setpoint(sp);
  for (int k = 0; k < 1000; ++k) v.step(0.001, a);
  for (auto _ : state) {
    v.step(0.001, a);
    benchmark::DoNotOptimize(v.state());
  }
}
BENCHMARK(BM_XplorerStep);

static void BM_XplorerArmImus(benchmark::State& state) {
  const Arena a = room();
  Xplorer v(XplorerParams{}, near_wall());
  v.step(0.001, a);
  for (auto _ : state) {
    for (int i = 0; i < 4; ++i) benchmark::DoNotOptimize(v.arm_imu(i));
  }
}
BENCHMARK(BM_XplorerArmImus);

static void BM_SensorSamples(benchmark::State& state) {
  ImuModel imu(ImuParams{}, 1);
  RangeModel tof(RangeParams{}, 1);
  FlowModel flow(FlowParams{}, 1);
  const Quat q(Eigen::AngleAxisd(0.1, Vec3::UnitX()));
  for (auto _ : state) {
    benchmark::DoNotOptimize(imu.sample(Vec3(0.1, 0.0, 9.81), Vec3(0.01, 0.02, 0.0)));
    benchmark::DoNotOptimize(tof.sample(0.8, q));
    benchmark::DoNotOptimize(flow.sample(Vec3(0.2, 0.1, 0.0), q, Vec3(0.01, 0.02, 0.0), 0.8));
  }
}
BENCHMARK(BM_SensorSamples);

BENCHMARK_MAIN();
