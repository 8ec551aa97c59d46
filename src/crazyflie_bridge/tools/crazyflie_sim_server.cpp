// Simulated Crazyflie on UDP (see crazyflie_bridge/sitl_endpoint.hpp):
//   crazyflie_sim_server SCENARIO [--port 19850] [--seed N] [--duration S]
//                        [--speed X] [--loss P] [--spike-rate HZ] [--spike-latency S]
//                        [--protocol-version N] [--require-arming]  (motors off until an arming request, as a brushless Crazyflie)
//                        [--linger S]
// Prints "listening udp://127.0.0.1:PORT" once ready, then runs until the
// duration elapsed or SIGINT/SIGTERM; prints the final truth position and
// link counters on exit. With --linger S, a signal that comes while the motors
// run lets the vehicle land first: the server goes on until the motors have been
// off for 0.5 s, or S seconds passed, or a second signal 1 s or more after the
// first (a launch file's Ctrl-C reaches the simulator and the bridge together, the
// simulator twice: from the terminal and forwarded by ros2 launch; the bridge's
// shutdown landing needs a vehicle to land).
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "crazyflie_bridge/sitl_endpoint.hpp"

namespace {
std::atomic<int> g_signals{0};
void on_signal(int) { g_signals.fetch_add(1); }
}  // namespace

namespace {

/// A whole number in [lo, hi] written as digits only; anything else names the option.
uint64_t whole(const std::string& option, const std::string& text, uint64_t lo, uint64_t hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 19) {
    throw std::invalid_argument(option + ": expected a whole number in " + range + ", got '" + text + "'");
  }
  const uint64_t v = std::stoull(text);
  if (v < lo || v > hi) throw std::invalid_argument(option + ": must be in " + range + ", got " + text);
  return v;
}

/// A finite number in [lo, hi].
double number(const std::string& option, const std::string& text, double lo, double hi) {
  double v = 0.0;
  size_t pos = 0;
  try {
    v = std::stod(text, &pos);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos == 0 || pos != text.size() || !std::isfinite(v) || v < lo || v > hi) {
    throw std::invalid_argument(option + ": expected a finite number in [" + std::to_string(lo) + ", " +
                                std::to_string(hi) + "], got '" + text + "'");
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help")) {
    std::fprintf(stderr,
                 "usage: crazyflie_sim_server SCENARIO [--port 19850] [--seed N] [--duration S] [--speed X]\n"
                 "       [--loss P] [--spike-rate HZ] [--spike-latency S] [--bind ADDR] [--require-arming]\n"
                 "       [--protocol-version N]  (CRTP protocol reported; <= 8 emulates the legacy\n"
                 "                                setpoint generation: hover type 5, negated yaw rate)\n"
                 "       [--linger S]  (on SIGINT/SIGTERM with the motors on: run until they have been off\n"
                 "                      0.5 s, at most S seconds; a signal 1 s or more after the first\n"
                 "                      ends at once)\n");
    return argc < 2 ? 2 : 0;
  }
  try {
    const std::string scenario_path = argv[1];
    crazyflie_bridge::SitlEndpointOptions opt;
    int64_t seed = -1;
    double duration = 0.0;
    double linger_s = 0.0;
    for (int i = 2; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + ": missing value");
        return argv[++i];
      };
      // Every value is checked whole and in range (issue 32: --port 70000 listened on 4464,
      // std::stoi("5x") read 5).
      if (a == "--port") opt.port = static_cast<uint16_t>(whole(a, next(), 0, 65535));
      else if (a == "--seed") seed = static_cast<int64_t>(whole(a, next(), 0, std::numeric_limits<int64_t>::max()));
      else if (a == "--duration") duration = number(a, next(), 0.0, 86400.0);
      else if (a == "--speed") opt.speed = number(a, next(), 1e-3, 1e3);
      else if (a == "--loss") opt.loss_rate = number(a, next(), 0.0, 0.99);
      else if (a == "--spike-rate") opt.spike_rate_hz = number(a, next(), 0.0, 1e3);
      else if (a == "--spike-latency") opt.spike_latency_s = number(a, next(), 0.0, 10.0);
      else if (a == "--bind") opt.bind_address = next();
      else if (a == "--protocol-version") opt.protocol_version = static_cast<uint8_t>(whole(a, next(), 0, 255));
      else if (a == "--require-arming") opt.require_arming = true;  // motors off until an arming request
      else if (a == "--linger") linger_s = number(a, next(), 0.0, 600.0);
      else throw std::invalid_argument("unknown option " + a);
    }
    const auto scenario = tactile_sim::load_scenario(scenario_path);
    crazyflie_bridge::SitlEndpoint ep(scenario, seed >= 0 ? static_cast<uint64_t>(seed) : scenario.seed, opt);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::printf("listening udp://%s:%u\n", opt.bind_address.c_str(), ep.port());
    std::fflush(stdout);
    // The simulation stops on the first signal, or, lingering, once the motors have been
    // off 0.5 s after it (the vehicle landed), at most linger_s after it; on a second signal
    // at once.
    std::atomic<bool> stop{false};
    std::atomic<bool> done{false};
    std::thread watcher([&] {
      using Clock = std::chrono::steady_clock;
      Clock::time_point signalled{}, motors_off{};
      int seen = 0;
      while (!done) {
        const int n = g_signals.load();
        const auto now = Clock::now();
        if (n > seen && seen > 0) {
          // A terminal's Ctrl-C reaches every process of the group and `ros2 launch`
          // forwards it once more: signals within 1 s of the first are that same Ctrl-C.
          if (now - signalled >= std::chrono::seconds(1)) break;
        }
        if (n > 0 && seen == 0) {
          signalled = now;
          if (!(linger_s > 0.0 && ep.motors_on())) break;
          std::printf("signal: lingering until the motors stop (at most %.1f s)\n", linger_s);
          std::fflush(stdout);
        }
        seen = n;
        if (n > 0) {
          if (ep.motors_on()) motors_off = Clock::time_point{};
          else if (motors_off == Clock::time_point{}) motors_off = now;
          if (motors_off != Clock::time_point{} && now - motors_off >= std::chrono::milliseconds(500)) break;
          if (now - signalled >= std::chrono::duration<double>(linger_s)) break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      stop = true;
    });
    ep.run(duration, &stop);
    done = true;
    watcher.join();
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
