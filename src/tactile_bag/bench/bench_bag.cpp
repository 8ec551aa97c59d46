// Write and read throughput for a WhiskerPressure-sized message (88 bytes of CDR:
// header with frame_id "whisker_left", whisker_id, 2 x float64[3], sequence).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "tactile_bag/bag.hpp"

namespace fs = std::filesystem;

namespace {

constexpr size_t kMsgSize = 88;

std::string fresh_dir(const char* tag) {
  std::random_device rd;
  return (fs::temp_directory_path() /
          ("tactile_bag_bench_" + std::to_string(::getpid()) + "_" + tag + "_" +
           std::to_string(rd())))
      .string();
}

tactile_bag::TopicInfo whisker_topic() {
  tactile_bag::TopicInfo t;
  t.name = "/whisker/left/pressure";
  t.type = "tactile_msgs/msg/WhiskerPressure";
  return t;
}

// Messages per iteration batch: a 50 Hz whisker stream for ~1.5 hours.
void BM_Write(benchmark::State& state) {
  const int64_t n = state.range(0);
  std::vector<uint8_t> msg(kMsgSize, 0x5a);
  for (auto _ : state) {
    const std::string dir = fresh_dir("w");
    {
      tactile_bag::Writer w;
      w.open(dir);
      w.create_topic(whisker_topic());
      for (int64_t i = 0; i < n; ++i) w.write("/whisker/left/pressure", i * 20000000, msg);
      w.close();
    }
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetBytesProcessed(state.iterations() * n * static_cast<int64_t>(kMsgSize));
}
BENCHMARK(BM_Write)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_Read(benchmark::State& state) {
  const int64_t n = state.range(0);
  const std::string dir = fresh_dir("r");
  {
    std::vector<uint8_t> msg(kMsgSize, 0x5a);
    tactile_bag::Writer w;
    w.open(dir);
    w.create_topic(whisker_topic());
    for (int64_t i = 0; i < n; ++i) w.write("/whisker/left/pressure", i * 20000000, msg);
  }
  for (auto _ : state) {
    tactile_bag::Reader r(dir);
    tactile_bag::SerializedMessage m;
    int64_t count = 0;
    while (r.read_next(m)) ++count;
    if (count != n) state.SkipWithError("wrong message count");
    benchmark::DoNotOptimize(m.data.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetBytesProcessed(state.iterations() * n * static_cast<int64_t>(kMsgSize));
  fs::remove_all(dir);
}
BENCHMARK(BM_Read)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
