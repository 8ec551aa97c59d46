// Write and read throughput for a WhiskerPressure-sized message (88 bytes of CDR:
// header with frame_id "whisker_left", whisker_id, 2 x float64[3], sequence).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "tactile_bag/bag.hpp"
#include "tactile_bag/typed.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"

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

// Storage comparison on realistic payloads: WhiskerPressure messages of a 50 Hz stream with
// barometer-like values (101325 Pa + noise), so compression sees real entropy.
// Arg: 0 sqlite3, 1 mcap, 2 mcap + zstd chunks, 3 mcap + lz4 chunks.
const char* kStorageNames[] = {"sqlite3", "mcap", "mcap+zstd", "mcap+lz4"};

tactile_bag::WriterOptions storage_options(int64_t which) {
  tactile_bag::WriterOptions o;
  o.storage = which == 0 ? "sqlite3" : "mcap";
  o.compression = which == 2 ? "zstd" : which == 3 ? "lz4" : "";
  o.ros_distro = "kilted";
  return o;
}

std::vector<std::vector<uint8_t>> whisker_payloads(int64_t n) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 2.0);
  std::vector<std::vector<uint8_t>> out;
  out.reserve(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) {
    tactile_msgs::msg::WhiskerPressure m;
    const int64_t t = i * 20000000;
    m.header.stamp.sec = static_cast<int32_t>(t / 1000000000);
    m.header.stamp.nanosec = static_cast<uint32_t>(t % 1000000000);
    m.header.frame_id = "whisker_left";
    for (size_t k = 0; k < 3; ++k) {
      m.pressure[k] = 101325.0 + noise(rng);
      m.temperature[k] = 25.0 + 0.01 * noise(rng);
    }
    m.sequence = static_cast<uint32_t>(i);
    out.push_back(tactile_msgs::cdr::serialize(m));
  }
  return out;
}

uint64_t dir_bytes(const std::string& dir) {
  uint64_t total = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename() != "metadata.yaml") total += fs::file_size(e.path());
  }
  return total;
}

void write_bag(const std::string& dir, int64_t which, const std::vector<std::vector<uint8_t>>& msgs) {
  tactile_bag::Writer w(storage_options(which));
  w.open(dir);
  w.create_topic(tactile_bag::topic_info_for<tactile_msgs::msg::WhiskerPressure>("/whisker/left/pressure"));
  int64_t i = 0;
  for (const auto& m : msgs) w.write("/whisker/left/pressure", (i++) * 20000000, m);
  w.close();
}

void BM_WriteStorage(benchmark::State& state) {
  const int64_t n = 100000;
  const auto msgs = whisker_payloads(n);
  uint64_t bytes = 0;
  for (auto _ : state) {
    const std::string dir = fresh_dir("ws");
    write_bag(dir, state.range(0), msgs);
    state.PauseTiming();
    bytes = dir_bytes(dir);
    fs::remove_all(dir);
    state.ResumeTiming();
  }
  state.SetLabel(kStorageNames[state.range(0)]);
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["bytes_per_msg"] = static_cast<double>(bytes) / static_cast<double>(n);
}
BENCHMARK(BM_WriteStorage)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

void BM_ReadStorage(benchmark::State& state) {
  const int64_t n = 100000;
  const std::string dir = fresh_dir("rs");
  write_bag(dir, state.range(0), whisker_payloads(n));
  for (auto _ : state) {
    tactile_bag::Reader r(dir);
    tactile_bag::SerializedMessage m;
    int64_t count = 0;
    while (r.read_next(m)) ++count;
    if (count != n) state.SkipWithError("wrong message count");
    benchmark::DoNotOptimize(m.data.data());
  }
  state.SetLabel(kStorageNames[state.range(0)]);
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["bytes_per_msg"] = static_cast<double>(dir_bytes(dir)) / static_cast<double>(n);
  fs::remove_all(dir);
}
BENCHMARK(BM_ReadStorage)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
