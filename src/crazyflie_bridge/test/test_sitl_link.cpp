// The bridge flies the simulated Crazyflie over real UDP sockets: clean link,
// then 30 % packet loss and 200 ms latency spikes. No crash; when the
// setpoints stop the bridge hovers, lands and stops the motors; every log
// sample the client decoded reaches the sinks (nothing silently dropped).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/loopback_link.hpp"
#include "crazyflie_bridge/sim_firmware.hpp"
#include "crazyflie_bridge/sitl_endpoint.hpp"
#include "tactile_common/geometry.hpp"
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
  // gives one left and one right message, each state sample one odometry
  // (with the attitude sample of its tick), each attitude sample is kept.
  EXPECT_EQ(f.left, f.right);
  EXPECT_EQ(f.logic.log_samples + f.logic.status_samples, f.samples);
  EXPECT_EQ(f.left + f.odom + f.logic.attitude_samples + f.logic.odom_without_attitude + f.logic.status_samples, f.samples);
  EXPECT_GT(f.logic.status_samples, 20u);  // 10 Hz status block
  EXPECT_EQ(f.client.log_decode_errors, 0u);
  EXPECT_GT(f.odom, 100u);  // 50 Hz for > 3 s
  EXPECT_EQ(f.logic.odom_without_attitude, 0u);
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
  EXPECT_EQ(f.logic.log_samples + f.logic.status_samples, f.samples);
  EXPECT_EQ(f.left + f.odom + f.logic.attitude_samples + f.logic.odom_without_attitude + f.logic.status_samples, f.samples);
}

// ---- Firmware generations: the yaw direction over the wire ----

namespace {

struct YawFlight {
  double yaw_change = 0;  ///< truth yaw during the yaw phase [rad]
  double z_max = 0;
  uint8_t protocol = 0;
  uint64_t unknown_setpoint_types = 0;
};

/// Simulated Crazyflie speaking `protocol` on UDP; takes off to 0.4 m (1.5 s),
/// then commands +0.6 rad/s yaw rate (CCW, REP-103) for 1.5 s. With
/// `raw_type10` the packets are type-10 hovers sent through the client
/// directly (what the bridge sent to every firmware before), else the bridge
/// (BridgeRunner) chooses the packet from the protocol version.
YawFlight fly_yaw(uint8_t protocol, bool raw_type10) {
  const auto scenario = tactile_sim::load_scenario(TACTILE_CONFIG_DIR "/scenarios/whisker_hover.yaml");
  SitlEndpointOptions opt;
  opt.port = 0;
  opt.protocol_version = protocol;
  SitlEndpoint ep(scenario, 7, opt);
  std::atomic<bool> stop{false};
  std::thread sim([&] { ep.run(0.0, &stop); });
  YawFlight f;
  try {
    CrazyflieBridgeLogic::Params p;
    p.uri = "udp://127.0.0.1:" + std::to_string(ep.port());
    p.autostart = true;  // the behaviour's setpoints fly at once (what this test compares)
    std::unique_ptr<BridgeRunner> r;
    std::unique_ptr<Link> raw_link;
    std::unique_ptr<CrazyflieClient> raw;
    if (raw_type10) {
      raw_link = open_link(p.uri);
      raw = std::make_unique<CrazyflieClient>(*raw_link);
      raw->connect();
      f.protocol = raw->protocol_version();
    } else {
      r = std::make_unique<BridgeRunner>(p);
      f.protocol = r->client().protocol_version();
    }
    BridgeRunner::Sinks sinks;
    const auto t0 = Clock::now();
    auto now_ns = [&] { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count(); };
    auto next = t0;
    double yaw_start = 0;
    bool yawing = false;
    while (Clock::now() - t0 < std::chrono::milliseconds(3000)) {
      next += std::chrono::milliseconds(20);
      const double t = tactile_common::to_seconds(now_ns());
      const double yaw_rate = t > 1.5 ? 0.6 : 0.0;
      if (t > 1.5 && !yawing) {
        yawing = true;
        yaw_start = ep.truth_yaw();
      }
      if (raw) {
        raw->send(commander::hover(0.f, 0.f, static_cast<float>(yaw_rate * 180 / M_PI), 0.4f));
        while (raw->poll(std::chrono::milliseconds(0))) {
        }
        std::this_thread::sleep_until(next);
      } else {
        tactile_msgs::msg::HoverSetpoint sp;
        sp.height = 0.4;
        sp.yaw_rate = yaw_rate;
        r->on_hover_setpoint(sp, now_ns());
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now());
        r->pump(std::max(left, std::chrono::milliseconds(0)), now_ns, sinks);
        r->on_timer(now_ns());
      }
      f.z_max = std::max(f.z_max, ep.truth_position().z());
    }
    f.yaw_change = std::remainder(ep.truth_yaw() - yaw_start, 2 * M_PI);
    f.unknown_setpoint_types = ep.firmware().stats().unknown_setpoint_types;
  } catch (...) {
    stop = true;
    sim.join();
    throw;
  }
  stop = true;
  sim.join();
  return f;
}

}  // namespace

TEST(SitlLink, BothFirmwareGenerationsYawCcwOnAPositiveYawRate) {
  // Protocol 8: cflib's legacy hover (type 5, yaw rate negated); 10: type 10.
  for (uint8_t v : {uint8_t{8}, uint8_t{10}}) {
    const auto f = fly_yaw(v, false);
    EXPECT_EQ(f.protocol, v);
    EXPECT_GT(f.z_max, 0.3) << "protocol " << int(v);
    // 0.6 rad/s for ~1.5 s: ~0.9 rad CCW (the attitude loop's lag aside).
    EXPECT_GT(f.yaw_change, 0.4) << "protocol " << int(v);
    EXPECT_EQ(f.unknown_setpoint_types, 0u);
  }
}

TEST(SitlLink, NewHoverPacketToOldFirmwareStopsItInsteadOfTurning) {
  // What the bridge did before it read the protocol version: type 10 to a
  // protocol-8 firmware, which has no decoder for it and takes the all-zero
  // (stop) setpoint: the vehicle never leaves the floor and does not turn.
  const auto f = fly_yaw(8, true);
  EXPECT_LT(f.z_max, 0.05);
  EXPECT_LT(std::fabs(f.yaw_change), 0.05);
  EXPECT_GT(f.unknown_setpoint_types, 100u);
}

// ---- Link truth in lockstep (LoopbackLink, seeded loss) ----

namespace {

nav_msgs::msg::Odometry estimate_at(int64_t t_ms) {
  const double t = static_cast<double>(t_ms) * 1e-3;
  const double roll = 0.15 * std::sin(2 * t), pitch = -0.1 * std::cos(3 * t), yaw = 0.5 * t - 1.0;
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2), cp = std::cos(pitch / 2), sp = std::sin(pitch / 2),
               cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  nav_msgs::msg::Odometry o;
  o.pose.pose.position.x = 0.1 * t;
  o.pose.pose.position.z = 0.4;
  o.pose.pose.orientation.x = sr * cp * cy - cr * sp * sy;
  o.pose.pose.orientation.y = cr * sp * cy + sr * cp * sy;
  o.pose.pose.orientation.z = cr * cp * sy - sr * sp * cy;
  o.pose.pose.orientation.w = cr * cp * cy + sr * sp * sy;
  o.twist.twist.angular.x = 0.3 * std::cos(2 * t);
  o.twist.twist.angular.y = 0.3 * std::sin(3 * t);
  o.twist.twist.angular.z = 0.5;
  return o;
}

struct Lockstep {
  std::vector<uint32_t> left_sequence;
  std::vector<nav_msgs::msg::Odometry> odom;
  uint64_t dropped_log = 0, missed = 0, samples = 0;
};

/// The bridge against the simulated firmware over the in-process loopback
/// link (every packet encoded and decoded), 10 ms firmware ticks, 4 s; the
/// firmware logs estimate_at(t) at each tick.
Lockstep run_lockstep(double loss, uint64_t seed) {
  SimulatedCrazyflieFirmware fw(loss);
  auto link = std::make_unique<LoopbackLink>(fw.emulator(), loss, seed);
  LoopbackLink* l = link.get();
  ClientOptions co;
  co.retries = 50;
  BridgeRunner r(CrazyflieBridgeLogic::Params{}, co, std::move(link));
  Lockstep out;
  int64_t now_ns = 0;
  BridgeRunner::Sinks sinks;
  sinks.left = [&](const auto& m) { out.left_sequence.push_back(m.sequence); };
  sinks.odom = [&](const auto& m) { out.odom.push_back(m); };
  for (int64_t ms = 10; ms <= 4000; ms += 10) {
    now_ns = ms * 1000000;
    fw.on_estimate(estimate_at(ms));
    l->set_time_ms(static_cast<uint32_t>(ms));
    l->tick();
    r.pump(std::chrono::milliseconds(0), [&] { return now_ns; }, sinks);
  }
  out.dropped_log = l->dropped_log_packets();
  out.missed = r.logic_stats().log_samples_missed;
  out.samples = r.client_stats().log_samples;
  return out;
}

}  // namespace

TEST(SitlLink, LostLogPacketsAreSequenceGaps) {
  const auto clean = run_lockstep(0.0, 1);
  ASSERT_GT(clean.left_sequence.size(), 190u);  // 50 Hz for 4 s
  for (size_t i = 1; i < clean.left_sequence.size(); ++i) EXPECT_EQ(clean.left_sequence[i], clean.left_sequence[i - 1] + 1);
  EXPECT_EQ(clean.missed, 0u);

  const auto lossy = run_lockstep(0.3, 11);
  uint64_t gaps = 0, missing = 0;
  for (size_t i = 1; i < lossy.left_sequence.size(); ++i) {
    ASSERT_GT(lossy.left_sequence[i], lossy.left_sequence[i - 1]);
    const uint32_t step = lossy.left_sequence[i] - lossy.left_sequence[i - 1];
    if (step > 1) {
      ++gaps;
      missing += step - 1;
    }
  }
  // ~30 % of ~200 whisker packets lost: they are gaps in the sequence (what
  // tdorc_filter's clock classifies as missing samples and bridges).
  EXPECT_GT(gaps, 20u);
  EXPECT_EQ(lossy.left_sequence.size() + missing, lossy.left_sequence.back() - lossy.left_sequence.front() + 1);
  // Every block: the gaps account for the injected log-packet drops, except
  // drops before a block's first or after its last received sample.
  EXPECT_LE(lossy.missed, lossy.dropped_log);
  EXPECT_GE(lossy.missed + 10, lossy.dropped_log);
}

TEST(SitlLink, OdometryAttitudeAndRatesMatchTheSimulatedEstimate) {
  const auto run = run_lockstep(0.0, 1);
  ASSERT_GT(run.odom.size(), 390u);  // 100 Hz for 4 s
  for (const auto& o : run.odom) {
    // Lockstep: received in the tick it was logged: stamp = firmware time.
    const int64_t t_ns = tactile_common::from_stamp(o.header.stamp);
    ASSERT_EQ(t_ns % 1000000, 0);
    const auto e = estimate_at(t_ns / 1000000);
    const auto& q = o.pose.pose.orientation;
    const auto& qe = e.pose.pose.orientation;
    const double dot = std::fabs(q.x * qe.x + q.y * qe.y + q.z * qe.z + q.w * qe.w);
    EXPECT_GT(dot, std::cos(0.25 * M_PI / 180 / 2));  // quatcompress resolution (9 bits)
    EXPECT_NEAR(tactile_common::yaw_of(q), tactile_common::yaw_of(qe), 1e-6);  // float32 stateEstimate.yaw
    // int16 mrad/s, truncated by the firmware: within 1 mrad/s.
    EXPECT_NEAR(o.twist.twist.angular.x, e.twist.twist.angular.x, 1e-3);
    EXPECT_NEAR(o.twist.twist.angular.y, e.twist.twist.angular.y, 1e-3);
    EXPECT_NEAR(o.twist.twist.angular.z, e.twist.twist.angular.z, 1e-3);
    EXPECT_NEAR(o.pose.pose.position.x, e.pose.pose.position.x, 1e-6);
  }
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
