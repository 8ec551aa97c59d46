// Benchmarks of the GPIS explorer (000 eq. 31-46): one update (fit + grid
// prediction + contour + curvature + corners + target) for the onboard budget
// (50 points, 10 x 10 grid), 2000 points / 200 x 200 and 10000 / 400 x 400,
// and the incremental Cholesky update per added point. The numpy reference
// of the same steps: scripts/bench_numpy_compare.py (runs both, prints ratios).
#include <cmath>
#include <random>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>

#include "gpis_explorer/explorer.hpp"
#include "../test/room_points.hpp"

namespace {

using gpis_explorer::ExplorerParams;
using gpis_explorer::GpisExplorer;

/// The fixed training points of every benchmark (seed 42, the room rotated 0.3 rad).
void room_points(int n, Eigen::Matrix2Xd& X, Eigen::VectorXd& y) { gpis_explorer::test::room_points(n, 42, X, y); }

ExplorerParams params_for(int points, int cells, bool grid_variance = true, int variance_cells = 0,
                          bool local = false) {
  ExplorerParams p = ExplorerParams::ground();
  p.solver = local ? gpis_explorer::GpisSolver::kLocal : gpis_explorer::GpisSolver::kExact;
  p.grid_variance = grid_variance;
  p.variance_cells = static_cast<uint32_t>(variance_cells);
  p.gpis.max_points = static_cast<std::size_t>(points);
  p.grid_cells = static_cast<uint32_t>(cells);
  return p;
}

// One update from scratch. Args: points, grid nodes per side, grid variance
// (0/1), variance-map nodes per side (0: every grid node).
void BM_Update(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int cells = static_cast<int>(state.range(1));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, cells, state.range(2) != 0, static_cast<int>(state.range(3))));
  std::size_t contour_points = 0;
  for (auto _ : state) {
    ex.fit(X, y);                      // K + sigma^2 I, Cholesky (000 eq. 34-35)
    const auto& r = ex.update();       // grid, marching squares, eq. 40-46
    benchmark::DoNotOptimize(r.target);
    contour_points = 0;
    for (const auto& c : r.contours) contour_points += c.contour.points.size();
  }
  state.counters["contour_points"] = static_cast<double>(contour_points);
  state.counters["state_bytes"] = static_cast<double>(ex.state_bytes());
  state.SetLabel(gpis_explorer::Gpis::backend());
}
BENCHMARK(BM_Update)
    ->Args({50, 10, 1, 0})
    ->Args({2000, 200, 1, 0})
    ->Args({2000, 200, 1, 40})
    ->Args({2000, 200, 0, 0})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Update)->Args({10000, 400, 1, 40})->Iterations(1)->Unit(benchmark::kMillisecond);

// The update as the exploration runs it: the GPIS holds n - 5 points from the
// previous updates; a retreat adds 5 (4 surface, 1 interior: incremental
// Cholesky rows) and the update follows (grid mean, variance map extended by
// the 5 new rows, contour, curvature, contour variance, target). Args: points,
// grid nodes per side, variance-map nodes per side.
void BM_UpdateIncremental(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int cells = static_cast<int>(state.range(1));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, cells, true, static_cast<int>(state.range(2))));
  ex.fit(X.leftCols(n - 5), y.head(n - 5));
  ex.update();  // the state of the previous update (variance map up to date)
  for (auto _ : state) {
    for (int i = n - 5; i < n; ++i) ex.add_point(X.col(i), y(i));
    const auto& r = ex.update();
    benchmark::DoNotOptimize(r.target);
    state.PauseTiming();
    for (int i = 0; i < 5; ++i) ex.pop_back();
    state.ResumeTiming();
  }
  state.SetLabel(gpis_explorer::Gpis::backend());
}
BENCHMARK(BM_UpdateIncremental)->Args({50, 10, 0})->Args({2000, 200, 40})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateIncremental)->Args({10000, 400, 40})->Iterations(2)->Unit(benchmark::kMillisecond);

// The local solver (local GPs over a quadtree with overlap blending, GPisMap;
// README "Local solver"): from scratch and the update as flown (+5 points:
// the local GPs they fall in take incremental Cholesky rows; the grid, the
// variance map, curvature and variance at the contour points as above, the
// grid recomputed only where a local GP changed). Args: points, grid nodes
// per side, variance-map nodes per side. Counters: leaves, largest local GP.
/// Untimed: the local solver's mean and variance against the exact GP (000
/// eq. 34-35, class Gpis) at the grid nodes within 5 cm of a surface point,
/// as counters (label units; the same measure as test_local_gpis).
void accuracy_counters(benchmark::State& state, const Eigen::Matrix2Xd& X, const Eigen::VectorXd& y,
                       const GpisExplorer& ex) {
  gpis_explorer::GpisParams gp = ex.params().gpis;
  gpis_explorer::Gpis exact(gp);
  exact.fit(X, y);
  // Surface points bucketed in 5 cm cells: a node is near when a surface point
  // of its 3 x 3 cells is within 5 cm.
  const double r = 0.05;
  std::unordered_map<long long, std::vector<int>> cells;
  const auto key = [](long long i, long long j) { return i * 1000003LL + j; };
  for (int i = 0; i < X.cols(); ++i) {
    if (y(i) != 0.0) continue;
    cells[key(static_cast<long long>(std::floor(X(0, i) / r)), static_cast<long long>(std::floor(X(1, i) / r)))]
        .push_back(i);
  }
  const Eigen::Matrix2Xd nodes = ex.grid().nodes();
  std::vector<Eigen::Index> near;
  for (Eigen::Index k = 0; k < nodes.cols(); ++k) {
    const auto ci = static_cast<long long>(std::floor(nodes(0, k) / r));
    const auto cj = static_cast<long long>(std::floor(nodes(1, k) / r));
    bool found = false;
    for (long long a = ci - 1; a <= ci + 1 && !found; ++a) {
      for (long long b = cj - 1; b <= cj + 1 && !found; ++b) {
        const auto it = cells.find(key(a, b));
        if (it == cells.end()) continue;
        for (int i : it->second) found = found || (X.col(i) - nodes.col(k)).norm() < r;
      }
    }
    if (found) near.push_back(k);
  }
  Eigen::Matrix2Xd Q(2, static_cast<Eigen::Index>(near.size()));
  for (std::size_t k = 0; k < near.size(); ++k) Q.col(static_cast<Eigen::Index>(k)) = nodes.col(near[k]);
  Eigen::VectorXd me, ve, ml, vl;
  exact.predict_batch(Q, me, ve);
  ex.local()->predict_batch(Q, ml, vl);
  const Eigen::ArrayXd em = (ml - me).array().abs(), ev = (vl - ve).array().abs();
  state.counters["near_nodes"] = static_cast<double>(near.size());
  state.counters["mean_err_max"] = em.maxCoeff();
  state.counters["mean_err_avg"] = em.mean();
  state.counters["var_err_max"] = ev.maxCoeff();
  state.counters["var_err_avg"] = ev.mean();
}

void BM_LocalUpdate(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int cells = static_cast<int>(state.range(1));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, cells, true, static_cast<int>(state.range(2)), true));
  for (auto _ : state) {
    ex.fit(X, y);
    const auto& r = ex.update();
    benchmark::DoNotOptimize(r.target);
  }
  state.counters["leaves"] = static_cast<double>(ex.local()->leaf_count());
  state.counters["largest_local"] = static_cast<double>(ex.local()->largest_local());
  accuracy_counters(state, X, y, ex);
  state.SetLabel(gpis_explorer::Gpis::backend());
}
BENCHMARK(BM_LocalUpdate)->Args({2000, 200, 40})->Args({10000, 400, 40})->Iterations(2)->Unit(benchmark::kMillisecond);

void BM_LocalUpdateIncremental(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int cells = static_cast<int>(state.range(1));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, cells, true, static_cast<int>(state.range(2)), true));
  // Successive batches of 5 of the last 50 points (4 surface, 1 interior, as a
  // retreat adds them) on top of the previous update; rebuilt untimed when used up.
  int next = n;
  for (auto _ : state) {
    if (next + 5 > n) {
      state.PauseTiming();
      ex.fit(X.leftCols(n - 50), y.head(n - 50));
      ex.update();
      next = n - 50;
      state.ResumeTiming();
    }
    for (int i = next; i < next + 5; ++i) ex.add_point(X.col(i), y(i));
    next += 5;
    const auto& r = ex.update();
    benchmark::DoNotOptimize(r.target);
  }
  state.counters["leaves"] = static_cast<double>(ex.local()->leaf_count());
  state.counters["largest_local"] = static_cast<double>(ex.local()->largest_local());
  state.SetLabel(gpis_explorer::Gpis::backend());
}
BENCHMARK(BM_LocalUpdateIncremental)
    ->Args({2000, 200, 40})
    ->Args({10000, 400, 40})
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond);

// Adding one point to a GPIS of n - 1 points: new factor row + alpha (O(n^2)).
void BM_IncrementalAdd(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, 10));
  ex.fit(X.leftCols(n - 1), y.head(n - 1));
  const Eigen::Vector2d x = X.col(n - 1);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ex.add_point(x, y(n - 1)));
    state.PauseTiming();
    ex.pop_back();
    state.ResumeTiming();
  }
}
BENCHMARK(BM_IncrementalAdd)->Arg(50)->Arg(2000)->Arg(10000)->Unit(benchmark::kMicrosecond);

// Refactorizing from scratch for comparison (what the incremental update avoids).
void BM_Refactorize(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(n, X, y);
  GpisExplorer ex(params_for(n, 10));
  ex.fit(X, y);
  for (auto _ : state) ex.refactorize();
}
BENCHMARK(BM_Refactorize)->Arg(50)->Arg(2000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
