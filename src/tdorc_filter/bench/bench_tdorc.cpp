// TDORC update cost per sample per channel, for each mode (paper 000 eq. 4-11).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "tdorc_filter/tdorc.hpp"

namespace {

void run(benchmark::State& state, tdorc_filter::Mode mode) {
  tdorc_filter::Params p;
  p.mode = mode;
  tdorc_filter::TdorcWhisker w(p);
  // Pre-generated drifting free-flight samples (no contact: TDORC re-fits every sample).
  std::vector<std::array<double, 3>> samples(4096);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double d = 0.05 * static_cast<double>(k) + std::sin(0.3 * static_cast<double>(k));
    samples[k] = {{100000.0 + d, 99500.0 - d, 100800.0 + 0.5 * d}};
  }
  for (std::size_t k = 0; k < 200; ++k) w.update(samples[k]);  // fill the window
  std::size_t i = 0;
  for (auto _ : state) {
    auto o = w.update(samples[i]);
    benchmark::DoNotOptimize(o);
    i = (i + 1) & 4095;
  }
  // One whisker update = three channels; report per channel.
  state.SetItemsProcessed(state.iterations() * 3);
  state.counters["ns_per_channel"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * 3.0, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["state_bytes"] = static_cast<double>(w.state_size_bytes());
}

void BM_Tdorc(benchmark::State& s) { run(s, tdorc_filter::Mode::kTdorc); }
void BM_Tdoc(benchmark::State& s) { run(s, tdorc_filter::Mode::kTdoc); }
void BM_Bandpass(benchmark::State& s) { run(s, tdorc_filter::Mode::kBandpass); }

}  // namespace

BENCHMARK(BM_Tdorc);
BENCHMARK(BM_Tdoc);
BENCHMARK(BM_Bandpass);

int main(int argc, char** argv) {
  tdorc_filter::TdorcWhisker w{tdorc_filter::Params{}};
  std::printf("TdorcWhisker state (3 channels, n = 100): %zu bytes; paper 000: ~0.2 kB for TDORC onboard\n",
              w.state_size_bytes());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
