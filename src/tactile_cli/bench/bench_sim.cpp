// Real-time factor of the SITL (issue target: >= 200x for the whiskered-drone
// scenarios on a 2-core machine), measured in process (no process start):
// the whole `tactile sim` run of a scenario -- physics at 1 kHz, barometer,
// IMU and odometry models, TDORC nodes, scenario pilot, fault-free -- with
// and without recording every topic to the bag.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

#include "tactile_cli/sim_run.hpp"

namespace fs = std::filesystem;

namespace {

void run(benchmark::State& state, const char* scenario, bool bag) {
  const fs::path config = TACTILE_CONFIG_DIR;
  const fs::path dir = fs::temp_directory_path() / ("tactile_bench_sim_" + std::to_string(::getpid()));
  double sim_s = 0.0;
  int k = 0;
  for (auto _ : state) {
    tactile_cli::SimOptions o;
    o.scenario = (config / "scenarios" / scenario).string();
    o.out_dir = (dir / std::to_string(k++)).string();
    o.config_dir = config.string();
    o.progress = false;
    o.write_bag = bag;
    o.write_png = false;
    const auto m = tactile_cli::run_sim(o);
    sim_s += m["sim_time_s"].get<double>();
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
  }
  // Simulated seconds per wall second = real-time factor.
  state.counters["real_time_factor"] = benchmark::Counter(sim_s, benchmark::Counter::kIsRate);
}

}  // namespace

static void BM_SimWhiskerSweep(benchmark::State& s) { run(s, "whisker_sweep.yaml", true); }
static void BM_SimWhiskerSweepNoBag(benchmark::State& s) { run(s, "whisker_sweep.yaml", false); }
static void BM_SimWhiskerHover(benchmark::State& s) { run(s, "whisker_hover.yaml", true); }
static void BM_SimWhiskerHoverNoBag(benchmark::State& s) { run(s, "whisker_hover.yaml", false); }
static void BM_SimThreeBaffles(benchmark::State& s) { run(s, "whisker_three_baffles.yaml", true); }
static void BM_SimDuctedWall(benchmark::State& s) { run(s, "ducted_wall.yaml", true); }
static void BM_SimXplorerBox(benchmark::State& s) { run(s, "xplorer_box.yaml", true); }
BENCHMARK(BM_SimWhiskerSweep)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimWhiskerSweepNoBag)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimWhiskerHover)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimWhiskerHoverNoBag)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimThreeBaffles)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimDuctedWall)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimXplorerBox)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
