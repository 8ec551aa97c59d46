// Serialization throughput of representative messages (never run by the tests).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"

namespace
{

tactile_msgs::msg::WhiskerPressure make_pressure()
{
  tactile_msgs::msg::WhiskerPressure m;
  m.header.stamp.sec = 12;
  m.header.stamp.nanosec = 345;
  m.header.frame_id = "whisker_left";
  m.pressure = {101325.0, 101326.5, 101324.25};
  m.temperature = {25.0, 25.1, 25.2};
  m.sequence = 42;
  return m;
}

tactile_msgs::msg::GpisMap make_map(uint32_t side)
{
  tactile_msgs::msg::GpisMap m;
  m.header.frame_id = "odom";
  m.width = side;
  m.height = side;
  m.mean.assign(static_cast<std::size_t>(side) * side, 0.5f);
  m.variance.assign(static_cast<std::size_t>(side) * side, 0.1f);
  m.contour.resize(200);
  m.training_points.resize(500);
  m.training_labels.assign(500, -1);
  return m;
}

void BM_SerializeWhiskerPressure(benchmark::State & state)
{
  const auto m = make_pressure();
  for (auto _ : state) {
    auto bytes = tactile_msgs::cdr::serialize(m);
    benchmark::DoNotOptimize(bytes.data());
  }
}
BENCHMARK(BM_SerializeWhiskerPressure);

void BM_DeserializeWhiskerPressure(benchmark::State & state)
{
  const auto bytes = tactile_msgs::cdr::serialize(make_pressure());
  tactile_msgs::msg::WhiskerPressure out;
  for (auto _ : state) {
    tactile_msgs::cdr::deserialize(bytes.data(), bytes.size(), out);
    benchmark::DoNotOptimize(out.sequence);
  }
}
BENCHMARK(BM_DeserializeWhiskerPressure);

void BM_SerializeGpisMap(benchmark::State & state)
{
  const auto m = make_map(static_cast<uint32_t>(state.range(0)));
  std::size_t n = 0;
  for (auto _ : state) {
    auto bytes = tactile_msgs::cdr::serialize(m);
    n = bytes.size();
    benchmark::DoNotOptimize(bytes.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}
BENCHMARK(BM_SerializeGpisMap)->Arg(100)->Arg(400);

void BM_DeserializeGpisMap(benchmark::State & state)
{
  const auto bytes = tactile_msgs::cdr::serialize(make_map(static_cast<uint32_t>(state.range(0))));
  tactile_msgs::msg::GpisMap out;
  for (auto _ : state) {
    tactile_msgs::cdr::deserialize(bytes.data(), bytes.size(), out);
    benchmark::DoNotOptimize(out.mean.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
    static_cast<int64_t>(bytes.size()));
}
BENCHMARK(BM_DeserializeGpisMap)->Arg(100)->Arg(400);

}  // namespace

BENCHMARK_MAIN();
