// Replay throughput of the whisker chain in the standalone host: a recorded
// simulated bag (2 whiskers x 50 Hz) through bag source -> whisker_driver ->
// tdorc_filter (+ the three-mode evaluation) -> output bag + metrics.
// Reported as raw messages per second of wall time.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

#include "tactile_cli/whisker_demo.hpp"
#include "tactile_cli/whisker_replay.hpp"

namespace fs = std::filesystem;

static void BM_ReplayWhiskerBag(benchmark::State& state) {
  const fs::path dir = fs::temp_directory_path() / ("tactile_bench_replay_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string config = TACTILE_CONFIG_DIR;
  const double hover_s = static_cast<double>(state.range(0));
  tactile_cli::record_sim_whisker_bag((dir / "raw").string(), config, 1, hover_s, {}, {}, {});
  uint64_t messages = 0;
  int run = 0;
  for (auto _ : state) {
    const fs::path out = dir / ("out" + std::to_string(run++));
    const auto m = tactile_cli::run_replay({(dir / "raw").string(), out.string(), config, false});
    messages += m["raw_messages"].get<uint64_t>();
    state.PauseTiming();
    fs::remove_all(out);
    state.ResumeTiming();
  }
  state.counters["raw_messages_per_s"] = benchmark::Counter(static_cast<double>(messages), benchmark::Counter::kIsRate);
  fs::remove_all(dir);
}
BENCHMARK(BM_ReplayWhiskerBag)->Arg(60)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
