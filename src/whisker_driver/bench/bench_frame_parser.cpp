#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "whisker_driver/frame_parser.hpp"

static void BM_TextParser(benchmark::State& state) {
  std::string s;
  for (int i = 0; i < 50; ++i) s += "P1:101325.52\nP2:101401.07\nP3:99000.25\nT1:25.51\nT2:26.02\nT3:24.93\n";
  whisker_driver::TextFrameParser p;
  std::vector<whisker_driver::WhiskerFrame> out;
  out.reserve(64);
  for (auto _ : state) {
    out.clear();
    p.feed(s.data(), s.size(), out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * s.size()));
  state.SetItemsProcessed(state.iterations() * 50);
}
BENCHMARK(BM_TextParser);

static void BM_CsvParser(benchmark::State& state) {
  std::string s;
  for (int i = 0; i < 50; ++i) s += "101325.52,101401.07,99000.25\n";
  whisker_driver::CsvFrameParser p;
  std::vector<whisker_driver::WhiskerFrame> out;
  out.reserve(64);
  for (auto _ : state) {
    out.clear();
    p.feed(s.data(), s.size(), out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * s.size()));
  state.SetItemsProcessed(state.iterations() * 50);
}
BENCHMARK(BM_CsvParser);

BENCHMARK_MAIN();
