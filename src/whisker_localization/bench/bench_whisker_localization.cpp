// Benchmarks of paper 002's building blocks: force-mode and point-mode
// solves, a moment-sensor contact set, one preimage over a 1 m boundary, one
// localization step. Never run by the tests.
#include <benchmark/benchmark.h>

#include <cmath>

#include "whisker_localization/contact_estimation.hpp"
#include "whisker_localization/elastica.hpp"
#include "whisker_localization/preimage.hpp"
#include "whisker_localization/stage_sim.hpp"

using namespace whisker_localization;

static void BM_ForceModeNormal(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_normal(0.05, 0.06));
}
BENCHMARK(BM_ForceModeNormal);

static void BM_ForceModeFixedDirection(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_fixed(0.05, 1.5707963, 0.06));
}
BENCHMARK(BM_ForceModeFixedDirection);

static void BM_PointMode(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  for (auto _ : st) benchmark::DoNotOptimize(solver.solve_point(0.055, 0.008));
}
BENCHMARK(BM_PointMode);

static void BM_MomentContactSet(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  const VirtualSensors sensors(solver, ContactSetParams{});
  for (auto _ : st) benchmark::DoNotOptimize(sensors.moment(2e-3));
  st.counters["points"] = static_cast<double>(sensors.moment(2e-3).size());
}
BENCHMARK(BM_MomentContactSet)->Unit(benchmark::kMillisecond);

static void BM_Preimage1mBoundary(benchmark::State& st) {
  // Floor + 50 mm fillet + wall, 1.03 m of boundary at 1 mm.
  const BoundaryMap map({concave_corner_polyline(0.05, 0.475, 0.001)}, 0.001);
  const ContactGeometry g{0.0744, 0.0085, 0.9};
  PoseSet set;
  for (auto _ : st) {
    set.poses.clear();
    preimage(map, g, 0.002, set);
    benchmark::DoNotOptimize(set.poses.data());
  }
  st.counters["boundary_points"] = static_cast<double>(map.size());
  st.counters["poses"] = static_cast<double>(set.size());
}
BENCHMARK(BM_Preimage1mBoundary)->Unit(benchmark::kMicrosecond);

static void BM_TipWallContactSitl(benchmark::State& st) {
  const ElasticaSolver solver{BeamParams{}};
  const BoundaryMap world({concave_corner_polyline(0.05, 0.15, 0.00005)}, 0.001);
  const Pose2 base{-0.06, 0.0555, -0.9};
  for (auto _ : st) benchmark::DoNotOptimize(tip_wall_contact(solver, world, base));
}
BENCHMARK(BM_TipWallContactSitl)->Unit(benchmark::kMicrosecond);

// One localization step (geometry with 2 refinement passes over 5 history
// samples, forward projection, intersection) on a Table II sweep, for the
// deterministic and the possibilistic variant.
static void localization_step(benchmark::State& st, bool possibilistic) {
  const ElasticaSolver solver{BeamParams{}};
  const BoundaryMap map({concave_corner_polyline(0.05, 0.15, 0.001)}, 0.001);
  const BoundaryMap world({concave_corner_polyline(0.05, 0.15, 0.00005)}, 0.001);
  LocalizerParams lp;
  lp.possibilistic = possibilistic;
  const double heading = -3.14159265358979 / 2 + 40.0 * 3.14159265358979 / 180.0;
  const double reach = 0.075 - 0.004 / std::cos(40.0 * 3.14159265358979 / 180.0);
  const Pose2 start{-0.012 - reach * std::cos(heading), -reach * std::sin(heading), heading};
  const Pose2 motion{0.0005 * std::cos(-heading), 0.0005 * std::sin(-heading), 0.0};
  // Moments of 12 steps, precomputed.
  std::vector<double> m;
  Pose2 b = start;
  for (int k = 0; k < 12; ++k) {
    if (k > 0) b = compose(b, motion);
    m.push_back(tip_wall_contact(solver, world, b).m0);
  }
  std::size_t set_size = 0;
  for (auto _ : st) {
    st.PauseTiming();
    PreimageLocalizer loc(map, solver, lp);
    loc.set_prior(start);
    for (int k = 0; k < 11; ++k) loc.step(k == 0 ? Pose2{} : motion, m[k]);
    st.ResumeTiming();
    benchmark::DoNotOptimize(loc.step(motion, m[11]));
    set_size = loc.set().size();
  }
  st.counters["set_size"] = static_cast<double>(set_size);
}
static void BM_LocalizationStepDeterministic(benchmark::State& st) { localization_step(st, false); }
static void BM_LocalizationStepPossibilistic(benchmark::State& st) { localization_step(st, true); }
BENCHMARK(BM_LocalizationStepDeterministic)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LocalizationStepPossibilistic)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
