// CRTP encode/decode throughput and the bridge's per-sample cost; the
// end-to-end latency log packet in -> setpoint out over UDP against the
// simulated Crazyflie is measured by BM_EndToEndSitlLatency (wall clock).
#include <benchmark/benchmark.h>

#include <atomic>
#include <thread>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/protocol.hpp"
#include "crazyflie_bridge/sitl_endpoint.hpp"

using namespace crazyflie_bridge;

static void BM_EncodeHover(benchmark::State& st) {
  uint8_t buf[32];
  float v = 0.1f;
  for (auto _ : st) {
    const auto pk = commander::hover(v, -v, 10.f, 0.4f);
    benchmark::DoNotOptimize(pk.encode(buf));
    v += 1e-6f;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_EncodeHover);

static void BM_DecodeLogData6Floats(benchmark::State& st) {
  const std::vector<logp::Type> types(6, logp::Type::kFloat);
  const auto wire = logp::data_packet(1, 123456, types, {1, 2, 3, 4, 5, 6}).encode();
  std::vector<double> v;
  v.reserve(6);
  for (auto _ : st) {
    const auto pk = CrtpPacket::decode(wire.data(), wire.size());
    logp::decode_values(logp::decode_data(pk), types, v);
    benchmark::DoNotOptimize(v.data());
  }
  st.SetItemsProcessed(st.iterations());
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations() * wire.size()));
}
BENCHMARK(BM_DecodeLogData6Floats);

static void BM_FirmwareLogTick(benchmark::State& st) {
  FirmwareEmulator fw;
  for (int i = 0; i < 6; ++i) fw.add_log_variable("Whisker", "Barometer1_" + std::to_string(i), logp::Type::kFloat);
  std::vector<CrtpPacket> out;
  fw.on_packet(logp::create_block_v2(1, {{0, logp::Type::kFloat, logp::Type::kFloat}, {1, logp::Type::kFloat, logp::Type::kFloat},
                                         {2, logp::Type::kFloat, logp::Type::kFloat}, {3, logp::Type::kFloat, logp::Type::kFloat},
                                         {4, logp::Type::kFloat, logp::Type::kFloat}, {5, logp::Type::kFloat, logp::Type::kFloat}})[0],
               0, out);
  fw.on_packet(logp::start_block_v2(1, 1), 0, out);
  uint32_t t = 0;
  for (auto _ : st) {
    out.clear();
    fw.tick(++t, out);
    benchmark::DoNotOptimize(out.data());
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_FirmwareLogTick);

static void BM_BridgeLogicSample(benchmark::State& st) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});
  l.set_block_ids(1, 2);
  LogSample s;
  s.block_id = 1;
  s.values = {1, 2, 3, 4, 5, 6};
  int64_t t = 0;
  for (auto _ : st) {
    auto out = l.on_log_sample(s, t += 20000000);
    benchmark::DoNotOptimize(out.left);
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_BridgeLogicSample);

// Wall-clock latency from a state log packet arriving at the bridge to the
// next setpoint it sends, over UDP against the simulated Crazyflie; reported as
// counters (mean and max in ms) for a 3 s flight. The setpoints come from this
// loop every 20 ms (not from a pipeline reacting to the samples), so this is the
// link and the loop's phase; the pipeline's reaction time (whisker sample in ->
// the behaviour's setpoint out) is tactile fly's whisker_latency.
static void BM_EndToEndSitlLatency(benchmark::State& st) {
  const auto scenario = tactile_sim::load_scenario(TACTILE_CONFIG_DIR "/scenarios/whisker_hover.yaml");
  for (auto _ : st) {
    SitlEndpointOptions o;
    o.port = 0;
    SitlEndpoint ep(scenario, 1, o);
    std::atomic<bool> stop{false};
    std::thread sim([&] { ep.run(0.0, &stop); });
    CrazyflieBridgeLogic::Params p;
    p.uri = "udp://127.0.0.1:" + std::to_string(ep.port());
    p.autostart = true;  // measures state-in -> setpoint-out: setpoints flow from the connect
    BridgeRunner r(p);
    const auto t0 = std::chrono::steady_clock::now();
    auto now_ns = [&] { return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count(); };
    auto next = t0;
    BridgeRunner::Sinks sinks;
    while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(3)) {
      next += std::chrono::milliseconds(20);
      tactile_msgs::msg::HoverSetpoint sp;
      sp.height = 0.4;
      r.on_hover_setpoint(sp, now_ns());
      r.pump(std::max(std::chrono::duration_cast<std::chrono::milliseconds>(next - std::chrono::steady_clock::now()),
                      std::chrono::milliseconds(0)), now_ns, sinks);
      r.on_timer(now_ns());
    }
    stop = true;
    sim.join();
    const auto lat = r.latency();
    st.counters["latency_mean_ms"] = 1e3 * lat.sum_s / static_cast<double>(std::max<uint64_t>(lat.count, 1));
    st.counters["latency_max_ms"] = 1e3 * lat.max_s;
    st.counters["samples"] = static_cast<double>(lat.count);
  }
}
BENCHMARK(BM_EndToEndSitlLatency)->Iterations(1)->Unit(benchmark::kSecond);

BENCHMARK_MAIN();
