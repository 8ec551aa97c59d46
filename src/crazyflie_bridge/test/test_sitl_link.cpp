// The bridge flies the simulated Crazyflie over real UDP sockets: clean link,
// then 30 % packet loss and 200 ms latency spikes. No crash; when the
// setpoints stop the bridge hovers, lands and stops the motors; every log
// sample the client decoded reaches the sinks (nothing silently dropped).
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/sitl_endpoint.hpp"
#include "tactile_common/time.hpp"

using namespace crazyflie_bridge;
using Mode = CrazyflieBridgeLogic::Mode;
using Clock = std::chrono::steady_clock;

namespace {

struct Flight {
  std::vector<Mode> modes;  ///< distinct modes in order
  uint64_t left = 0, right = 0, odom = 0, samples = 0;
  double z_max = 0, z_end = 1, x_after_cruise = 0;
  BridgeRunner::LatencyStats latency;
  LinkStatistics link;
  CrazyflieClient::Stats client;
  SitlEndpoint::Stats endpoint;
  CrazyflieBridgeLogic::Stats logic;
};

/// Takes off to 0.4 m (1.5 s), cruises at 0.2 m/s (1 s), then the "pipeline"
/// goes silent; runs until the bridge stopped the motors (or 8 s).
Flight fly(const SitlEndpointOptions& faults, double connect_timeout_ms) {
  const auto scenario = tactile_sim::load_scenario(TACTILE_CONFIG_DIR "/scenarios/whisker_hover.yaml");
  SitlEndpointOptions opt = faults;
  opt.port = 0;
  const double loss = opt.loss_rate;
  opt.loss_rate = 0.0;
  SitlEndpoint ep(scenario, 7, opt);
  std::atomic<bool> stop{false};
  std::thread sim([&] { ep.run(0.0, &stop); });
  Flight f;
  try {
    CrazyflieBridgeLogic::Params p;
    p.uri = "udp://127.0.0.1:" + std::to_string(ep.port());
    p.autostart = true;  // this "pipeline" flies without an operator
    ClientOptions co;
    co.reply_timeout = std::chrono::milliseconds(static_cast<int>(connect_timeout_ms));
    co.retries = 40;
    ep.set_loss_rate(loss);  // faults from the first packet on
    BridgeRunner r(p, co);
    BridgeRunner::Sinks sinks;
    sinks.left = [&](const auto&) { ++f.left; };
    sinks.right = [&](const auto&) { ++f.right; };
    sinks.odom = [&](const auto&) { ++f.odom; };
    const auto t0 = Clock::now();
    auto now_ns = [&] { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count(); };
    auto next = t0;
    while (Clock::now() - t0 < std::chrono::seconds(9)) {
      next += std::chrono::milliseconds(20);
      const double t = tactile_common::to_seconds(now_ns());
      if (t < 2.5) {
        tactile_msgs::msg::HoverSetpoint sp;
        sp.height = 0.4;
        sp.vx = t > 1.5 ? 0.2 : 0.0;
        r.on_hover_setpoint(sp, now_ns());
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now());
      r.pump(std::max(left, std::chrono::milliseconds(0)), now_ns, sinks);
      r.on_timer(now_ns());
      const Mode m = r.mode();
      if (f.modes.empty() || f.modes.back() != m) f.modes.push_back(m);
      const auto truth = ep.truth_position();
      f.z_max = std::max(f.z_max, truth.z());
      if (t < 2.6) f.x_after_cruise = truth.x();
      if (m == Mode::kStopped && r.logic_stats().packets_out > 0 && truth.z() < 0.03) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    f.z_end = ep.truth_position().z();
    f.latency = r.latency();
    f.link = r.link_stats();
    f.client = r.client_stats();
    f.logic = r.logic_stats();
    f.samples = f.client.log_samples;
  } catch (...) {
    stop = true;
    sim.join();
    throw;
  }
  stop = true;
  sim.join();
  f.endpoint = ep.stats();
  return f;
}

}  // namespace

TEST(SitlLink, CleanLinkHoverThenLandThenStop) {
  const auto f = fly(SitlEndpointOptions{}, 200);
  // Forward, then hover hold (possibly back to forward if a loaded machine
  // delays the log stream > 0.2 s), landing, stopped.
  ASSERT_GE(f.modes.size(), 4u);
  EXPECT_EQ(f.modes.front(), Mode::kForward);
  EXPECT_EQ(f.modes[f.modes.size() - 3], Mode::kHoverHold);
  EXPECT_EQ(f.modes[f.modes.size() - 2], Mode::kLanding);
  EXPECT_EQ(f.modes.back(), Mode::kStopped);
  EXPECT_GT(f.z_max, 0.33);
  EXPECT_LT(f.z_end, 0.03);
  EXPECT_GT(f.x_after_cruise, 0.05);  // the cruise setpoint moved it forward
  // Nothing dropped between the client and the sinks: each whisker sample
  // gives one left and one right message, each state sample one odometry.
  EXPECT_EQ(f.left, f.right);
  EXPECT_EQ(f.left + f.odom + f.logic.status_samples, f.samples);
  EXPECT_GT(f.logic.status_samples, 20u);  // 10 Hz status block
  EXPECT_EQ(f.client.log_decode_errors, 0u);
  EXPECT_GT(f.odom, 100u);  // 50 Hz for > 3 s
  EXPECT_GE(f.logic.stale_events, 1u);
  EXPECT_EQ(f.logic.landings, 1u);
  EXPECT_GT(f.latency.count, 50u);
  // About one 20 ms tick at most, with margin for a loaded machine.
  EXPECT_LT(f.latency.sum_s / static_cast<double>(f.latency.count), 0.05);
}

TEST(SitlLink, LossAndLatencySpikesNoCrashStillLands) {
  SitlEndpointOptions faults;
  faults.loss_rate = 0.30;
  faults.spike_rate_hz = 0.5;
  faults.spike_latency_s = 0.2;
  faults.spike_duration_s = 0.2;
  faults.fault_seed = 3;
  const auto f = fly(faults, 40);
  EXPECT_GT(f.endpoint.dropped_in + f.endpoint.dropped_out, 50u);
  EXPECT_GT(f.client.resends, 0u);  // connect survived lost requests
  // Stale detection: hover, then land, then stop; the vehicle is down.
  ASSERT_GE(f.modes.size(), 4u);
  EXPECT_EQ(f.modes.back(), Mode::kStopped);
  EXPECT_NE(std::find(f.modes.begin(), f.modes.end(), Mode::kHoverHold), f.modes.end());
  EXPECT_NE(std::find(f.modes.begin(), f.modes.end(), Mode::kLanding), f.modes.end());
  EXPECT_GT(f.z_max, 0.25);
  EXPECT_LT(f.z_end, 0.03);
  // Every decoded sample reached a sink (or the status).
  EXPECT_EQ(f.left, f.right);
  EXPECT_EQ(f.left + f.odom + f.logic.status_samples, f.samples);
}

// The operator's flight over real UDP sockets against the simulated Crazyflie
// (wall-clock physics): on the ground nothing reaches the motors although the
// "behaviour" publishes; take-off, hand-over, then the blocking shutdown
// landing (what Ctrl-C and the component's destructor use) lands and stops.
TEST(SitlLink, OperatorTakeoffHandOverThenLandAndStop) {
  const auto scenario = tactile_sim::load_scenario(TACTILE_CONFIG_DIR "/scenarios/whisker_hover.yaml");
  SitlEndpointOptions opt;
  opt.port = 0;
  SitlEndpoint ep(scenario, 7, opt);
  std::atomic<bool> stop{false};
  std::thread sim([&] { ep.run(0.0, &stop); });
  struct Join {
    std::atomic<bool>& stop;
    std::thread& t;
    ~Join() {
      stop = true;
      t.join();
    }
  } join{stop, sim};
  CrazyflieBridgeLogic::Params p;
  p.uri = "udp://127.0.0.1:" + std::to_string(ep.port());
  ClientOptions co;
  co.reply_timeout = std::chrono::milliseconds(100);
  co.retries = 40;
  BridgeRunner r(p, co);
  const auto t0 = Clock::now();
  auto now_ns = [&] { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count(); };
  auto run = [&](double seconds) {
    const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    auto next = Clock::now();
    while (Clock::now() < end) {
      next += std::chrono::milliseconds(20);
      tactile_msgs::msg::HoverSetpoint sp;
      sp.height = 0.4;
      sp.vx = 0.1;
      r.on_hover_setpoint(sp, now_ns());
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now());
      r.pump(std::max(left, std::chrono::milliseconds(0)), now_ns, {});
      r.on_timer(now_ns());
    }
  };
  run(1.5);
  EXPECT_EQ(r.mode(), Mode::kGrounded);
  EXPECT_EQ(ep.first_motors_on_ns(), -1);  // never spun
  EXPECT_LT(ep.truth_position().z(), 0.005);
  const auto st = r.status(now_ns());
  EXPECT_EQ(st.supervisor_info & CrazyflieBridgeLogic::kIsArmed, CrazyflieBridgeLogic::kIsArmed);  // auto-arm
  EXPECT_NEAR(st.battery_v, 4.1, 0.01);
  EXPECT_EQ(st.rssi_dbm, 35);
  ASSERT_TRUE(r.takeoff(0.4, 1.5, now_ns()).accepted);
  run(2.0);
  EXPECT_EQ(r.mode(), Mode::kHovering);
  EXPECT_GT(ep.truth_position().z(), 0.3);
  ASSERT_TRUE(r.start_behaviour(now_ns()).accepted);
  run(1.0);
  EXPECT_EQ(r.mode(), Mode::kForward);
  EXPECT_TRUE(ep.motors_on());
  EXPECT_TRUE(r.land_and_stop(std::chrono::milliseconds(8000), now_ns));
  EXPECT_EQ(r.mode(), Mode::kStopped);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(ep.motors_on());
  EXPECT_LT(ep.truth_position().z(), 0.03);
  const auto h = r.history();
  ASSERT_GE(h.size(), 5u);
  EXPECT_EQ(h[3].guard, "land");
  EXPECT_EQ(h[4].guard, "touchdown");
}
