// Simulated Crazyflie on UDP (see crazyflie_bridge/sitl_endpoint.hpp):
//   crazyflie_sim_server SCENARIO [--port 19850] [--seed N] [--duration S]
//                        [--speed X] [--loss P] [--spike-rate HZ] [--spike-latency S]
//                        [--require-arming]  (motors off until an arming request, as a brushless Crazyflie)
// Prints "listening udp://127.0.0.1:PORT" once ready, then runs until the
// duration elapsed or SIGINT/SIGTERM; prints the final truth position and
// link counters on exit.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>

#include "crazyflie_bridge/sitl_endpoint.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help")) {
    std::fprintf(stderr,
                 "usage: crazyflie_sim_server SCENARIO [--port 19850] [--seed N] [--duration S] [--speed X]\n"
                 "       [--loss P] [--spike-rate HZ] [--spike-latency S] [--bind ADDR] [--require-arming]\n");
    return argc < 2 ? 2 : 0;
  }
  try {
    const std::string scenario_path = argv[1];
    crazyflie_bridge::SitlEndpointOptions opt;
    int64_t seed = -1;
    double duration = 0.0;
    for (int i = 2; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + ": missing value");
        return argv[++i];
      };
      if (a == "--port") opt.port = static_cast<uint16_t>(std::stoi(next()));
      else if (a == "--seed") seed = std::stoll(next());
      else if (a == "--duration") duration = std::stod(next());
      else if (a == "--speed") opt.speed = std::stod(next());
      else if (a == "--loss") opt.loss_rate = std::stod(next());
      else if (a == "--spike-rate") opt.spike_rate_hz = std::stod(next());
      else if (a == "--spike-latency") opt.spike_latency_s = std::stod(next());
      else if (a == "--bind") opt.bind_address = next();
      else if (a == "--require-arming") opt.require_arming = true;  // motors off until an arming request
      else throw std::invalid_argument("unknown option " + a);
    }
    const auto scenario = tactile_sim::load_scenario(scenario_path);
    crazyflie_bridge::SitlEndpoint ep(scenario, seed >= 0 ? static_cast<uint64_t>(seed) : scenario.seed, opt);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::printf("listening udp://%s:%u\n", opt.bind_address.c_str(), ep.port());
    std::fflush(stdout);
    ep.run(duration, &g_stop);
    const auto p = ep.truth_position();
    const auto& fs = ep.firmware().stats();
    std::printf("done t=%.3f truth=%.4f,%.4f,%.4f packets_in=%llu log_packets=%llu setpoints=%llu dropped_in=%llu dropped_out=%llu\n",
                static_cast<double>(ep.sim_time_ns()) * 1e-9, p.x(), p.y(), p.z(),
                static_cast<unsigned long long>(fs.packets_in), static_cast<unsigned long long>(fs.log_packets),
                static_cast<unsigned long long>(fs.setpoints), static_cast<unsigned long long>(ep.stats().dropped_in),
                static_cast<unsigned long long>(ep.stats().dropped_out));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "crazyflie_sim_server: %s\n", e.what());
    return 1;
  }
}
