// The operator surface over CRTP: BridgeRunner against the simulated
// Crazyflie firmware (FirmwareEmulator with its supervisor and commander
// watchdog), every byte through encode/decode on a loopback wire, in lockstep
// on a 1 ms clock. A point-mass vehicle follows the commander's height
// (first order, 0.2 s) while the motors spin and falls to the floor when they
// stop. What the motors do is read from the firmware side, not the bridge.
#include <gtest/gtest.h>

#include <algorithm>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/loopback_link.hpp"
#include "crazyflie_bridge/sim_firmware.hpp"
#include "tactile_common/time.hpp"

using namespace crazyflie_bridge;
using Mode = CrazyflieBridgeLogic::Mode;

namespace {
constexpr int64_t kMs = 1'000'000;

struct Crtp {
  SimulatedCrazyflieFirmware fw;
  LoopbackLink* link = nullptr;
  std::unique_ptr<BridgeRunner> runner;
  int64_t t = 0;
  double z = 0.0;
  bool behaviour = true;    ///< the behaviour streams /cmd_hover at 50 Hz
  bool motors_ever = false;
  int64_t motors_on_ms = 0;

  explicit Crtp(SimulatedCrazyflieFirmware::Options fo = {}, CrazyflieBridgeLogic::Params p = {}, bool stream = true)
      : fw(fo) {
    auto l = std::make_unique<LoopbackLink>(fw.emulator(), 0.0, 1);
    link = l.get();
    ClientOptions co;
    co.retries = 3;
    runner = std::make_unique<BridgeRunner>(p, co, std::move(l), stream);
  }
  uint32_t ms() const { return static_cast<uint32_t>(t / kMs); }
  bool motors_on() const { return fw.emulator().motors_on(ms()); }
  /// One millisecond of firmware and vehicle; the bridge's 20 ms tick.
  void step() {
    t += kMs;
    link->set_time_ms(ms());
    nav_msgs::msg::Odometry o;
    o.pose.pose.position.z = z;
    o.pose.pose.orientation.w = 1.0;
    fw.on_estimate(o);
    const auto c = fw.command(t, 1e-3);
    if (motors_on()) {
      motors_ever = true;
      ++motors_on_ms;
      const double target = c.position ? c.position->pose.position.z : c.hover ? c.hover->height : z;
      z += (target - z) * 1e-3 / 0.2;
    } else {
      z = std::max(0.0, z - 1.0e-3);  // motors off: down at 1 m/s, then on the floor
    }
    link->tick();
    if (t % (20 * kMs) == 0) {
      runner->pump(std::chrono::milliseconds(0), [this] { return t; }, {});
      if (behaviour) {
        tactile_msgs::msg::HoverSetpoint sp;
        sp.vx = 0.1;
        sp.height = 0.5;
        runner->on_hover_setpoint(sp, t);
      }
      runner->on_timer(t);
    }
  }
  void run_s(double s) {
    const int64_t end = t + tactile_common::from_seconds(s);
    while (t < end) step();
  }
  template <class Pred>
  bool run_until(Pred p, double max_s) {
    const int64_t end = t + tactile_common::from_seconds(max_s);
    while (!p()) {
      if (t >= end) return false;
      step();
    }
    return true;
  }
  /// Drives the bridge into `m` with operator commands.
  void to(Mode m) {
    run_s(0.3);
    if (m == Mode::kGrounded) return;
    if (m == Mode::kEmergency) {
      ASSERT_TRUE(runner->emergency_stop(t).accepted);
      return;
    }
    ASSERT_TRUE(runner->takeoff(0.4, 1.0, t).accepted);
    run_s(0.1);
    if (m == Mode::kTakingOff) return;
    ASSERT_TRUE(run_until([&] { return runner->mode() == Mode::kHovering; }, 2.0));
    run_s(0.5);
    if (m == Mode::kHovering) return;
    if (m == Mode::kGoTo) {
      ASSERT_TRUE(runner->go_to(0.0, 0.0, 0.6, 0.0, 2.0, false, t).accepted);
      run_s(0.1);
      return;
    }
    if (m == Mode::kLanding || m == Mode::kStopped) {
      ASSERT_TRUE(runner->land(0.0, 2.0, t).accepted);
      run_s(0.1);
      if (m == Mode::kStopped) {
        ASSERT_TRUE(run_until([&] { return runner->mode() == Mode::kStopped; }, 5.0));
      }
      return;
    }
    ASSERT_TRUE(runner->start_behaviour(t).accepted);
    run_s(0.1);
    if (m == Mode::kForward) return;
    behaviour = false;  // the behaviour goes silent
    ASSERT_TRUE(run_until([&] { return runner->mode() == Mode::kHoverHold; }, 1.0));
  }
};

const std::vector<Mode> kAllModes{Mode::kGrounded, Mode::kTakingOff, Mode::kHovering, Mode::kGoTo, Mode::kForward,
                                  Mode::kHoverHold, Mode::kLanding, Mode::kStopped, Mode::kEmergency};
const std::vector<Mode> kAirborne{Mode::kTakingOff, Mode::kHovering, Mode::kGoTo, Mode::kForward, Mode::kHoverHold};

}  // namespace

// Link up, log streaming, the behaviour publishing setpoints: not one
// setpoint packet reaches the firmware and its motors never spin, until
// take-off; then they spin within one setpoint period.
TEST(OperatorCrtp, NothingReachesTheMotorsUntilTakeoff) {
  Crtp c;
  c.run_s(3.0);
  EXPECT_EQ(c.runner->mode(), Mode::kGrounded);
  EXPECT_GT(c.runner->client_stats().log_samples, 400u);  // sensors stream
  EXPECT_EQ(c.fw.emulator().stats().setpoints, 0u);
  EXPECT_FALSE(c.motors_ever);
  EXPECT_EQ(c.z, 0.0);
  ASSERT_TRUE(c.runner->takeoff(0.4, 1.0, c.t).accepted);
  c.run_s(0.02);
  EXPECT_TRUE(c.motors_on());
  c.run_s(2.0);
  EXPECT_EQ(c.runner->mode(), Mode::kHovering);
  EXPECT_NEAR(c.z, 0.4, 0.02);
}

// Emergency from every mode: the stop packet goes out with the command (the
// motors are off at the same millisecond, within one setpoint period), the
// bridge keeps sending stop while the behaviour streams setpoints, and only
// arm(true) on the ground clears it.
TEST(OperatorCrtp, EmergencyStopsTheMotorsWithinOneSetpointPeriodFromEveryMode) {
  for (Mode m : kAllModes) {
    SCOPED_TRACE(to_string(m));
    Crtp c;
    c.to(m);
    ASSERT_EQ(c.runner->mode(), m);
    ASSERT_TRUE(c.runner->emergency_stop(c.t).accepted);
    EXPECT_FALSE(c.motors_on());  // same millisecond
    EXPECT_EQ(c.runner->mode(), Mode::kEmergency);
    c.behaviour = true;
    for (int i = 0; i < 2000; ++i) {
      c.step();
      ASSERT_FALSE(c.motors_on()) << "motors on " << i << " ms after the emergency stop";
    }
    EXPECT_EQ(c.z, 0.0);
    EXPECT_FALSE(c.runner->takeoff(0.4, 1.0, c.t).accepted);
    const auto a = c.runner->arm(true, c.t);
    ASSERT_TRUE(a.accepted) << a.reason;
    EXPECT_EQ(c.runner->mode(), Mode::kGrounded);
    const uint64_t setpoints = c.fw.emulator().stats().setpoints;
    c.run_s(1.0);
    EXPECT_FALSE(c.motors_on());
    EXPECT_EQ(c.fw.emulator().stats().setpoints, setpoints);  // grounded again: nothing sent
  }
}

TEST(OperatorCrtp, LandFromEveryAirborneMode) {
  for (Mode m : kAirborne) {
    SCOPED_TRACE(to_string(m));
    Crtp c;
    c.to(m);
    ASSERT_EQ(c.runner->mode(), m);
    EXPECT_TRUE(c.motors_on());
    const auto r = c.runner->land(0.0, 1.5, c.t);
    ASSERT_TRUE(r.accepted) << r.reason;
    ASSERT_TRUE(c.run_until([&] { return c.runner->mode() == Mode::kStopped; }, 3.0));
    c.run_s(0.5);
    EXPECT_FALSE(c.motors_on());
    EXPECT_LT(c.z, 0.01);
    EXPECT_EQ(c.runner->logic_stats().landings, 1u);
  }
}

// The simulated battery drops below low_battery_v during the behaviour's
// flight: the bridge lands on its own, counted.
TEST(OperatorCrtp, LowBatteryLands) {
  Crtp c;
  c.to(Mode::kForward);
  c.run_s(1.0);
  EXPECT_NEAR(c.runner->status(c.t).battery_v, 4.1, 0.01);
  c.fw.set_battery_voltage(3.05);
  c.run_s(1.5);
  EXPECT_EQ(c.runner->mode(), Mode::kForward);  // below 3.2 V for less than low_battery_hold_s (2 s)
  ASSERT_TRUE(c.run_until([&] { return c.runner->mode() == Mode::kLanding; }, 1.0));
  ASSERT_TRUE(c.run_until([&] { return c.runner->mode() == Mode::kStopped; }, 4.0));
  c.run_s(0.5);
  EXPECT_FALSE(c.motors_on());
  EXPECT_LT(c.z, 0.01);
  const auto st = c.runner->status(c.t);
  EXPECT_EQ(st.low_battery_events, 1u);
  EXPECT_EQ(st.pm_state, 3);  // the firmware's low-power state
  const auto h = c.runner->history();
  EXPECT_TRUE(std::any_of(h.begin(), h.end(), [](const auto& tr) { return tr.guard == "low_battery"; }));
  EXPECT_FALSE(c.runner->takeoff(0.4, 1.0, c.t).accepted);  // not again on a flat battery
}

// A firmware that requires arming (brushless): take-off is refused while the
// supervisor reports not armed; the arming request arms it.
TEST(OperatorCrtp, ArmingRequiredByTheFirmware) {
  SimulatedCrazyflieFirmware::Options fo;
  fo.require_arming = true;
  Crtp c(fo);
  c.run_s(0.5);
  auto st = c.runner->status(c.t);
  EXPECT_FALSE(st.armed);
  EXPECT_EQ(st.supervisor_info & CrazyflieBridgeLogic::kIsArmed, 0);
  auto r = c.runner->takeoff(0.4, 1.0, c.t);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("not armed"), std::string::npos) << r.reason;
  r = c.runner->arm(true, c.t);
  ASSERT_TRUE(r.accepted) << r.reason;
  EXPECT_TRUE(c.fw.emulator().armed());
  EXPECT_EQ(c.fw.emulator().stats().arming_requests, 1u);
  c.run_s(0.3);  // next status sample
  EXPECT_TRUE(c.runner->status(c.t).armed);
  ASSERT_TRUE(c.runner->takeoff(0.4, 1.0, c.t).accepted);
  c.run_s(1.5);
  EXPECT_NEAR(c.z, 0.4, 0.05);
  EXPECT_EQ(c.runner->status(c.t).supervisor_info & CrazyflieBridgeLogic::kIsFlying, CrazyflieBridgeLogic::kIsFlying);
}

// A firmware without supervisor.info / pm.state / radio.rssi: the connect
// succeeds, the missing variables are named in warnings, pm.vbat is logged.
TEST(OperatorCrtp, MissingStatusVariablesWarnButConnect) {
  SimulatedCrazyflieFirmware::Options fo;
  fo.status_log = false;
  Crtp c(fo);
  const auto& w = c.runner->warnings();
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NE(w[0].find("pm.state"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("supervisor.info"), std::string::npos) << w[1];
  EXPECT_NE(w[2].find("radio.rssi"), std::string::npos) << w[2];
  c.run_s(0.5);
  const auto st = c.runner->status(c.t);
  EXPECT_NEAR(st.battery_v, 4.1, 0.01);
  EXPECT_EQ(st.supervisor_info, -1);
  EXPECT_TRUE(c.runner->takeoff(0.4, 1.0, c.t).accepted);  // nothing to check: allowed
}

// The lifecycle component's split (crazyflie_bridge README "Lifecycle"): configure
// connects and creates the log blocks, activate starts them, deactivate stops them
// -- never while airborne.
TEST(OperatorCrtp, LogBlocksStreamOnlyBetweenStartAndStopStreaming) {
  Crtp c({}, {}, /*stream=*/false);
  EXPECT_FALSE(c.runner->streaming());
  c.run_s(1.0);
  EXPECT_EQ(c.runner->client_stats().log_samples, 0u) << "created blocks must not stream before start_streaming";
  EXPECT_FALSE(c.motors_ever);
  c.runner->start_streaming();
  EXPECT_TRUE(c.runner->streaming());
  c.run_s(1.0);
  const auto streamed = c.runner->client_stats().log_samples;
  // whiskers 50 Hz + attitude 100 Hz + state 100 Hz + status 10 Hz over 1 s
  EXPECT_GT(streamed, 200u);
  EXPECT_FALSE(c.motors_ever) << "streaming alone must not start the motors";
  EXPECT_EQ(c.runner->mode(), Mode::kGrounded);

  // Airborne: refused, nothing stopped.
  ASSERT_TRUE(c.runner->takeoff(0.4, 1.0, c.t).accepted);
  c.run_s(0.1);
  EXPECT_FALSE(c.runner->stop_streaming());
  EXPECT_TRUE(c.runner->streaming());
  ASSERT_TRUE(c.run_until([&] { return c.runner->mode() == Mode::kHovering; }, 2.0));
  EXPECT_FALSE(c.runner->stop_streaming());
  // Landed: stopped; no sample after the firmware's answer.
  ASSERT_TRUE(c.runner->land(0.0, 1.0, c.t).accepted);
  ASSERT_TRUE(c.run_until([&] { return c.runner->mode() == Mode::kStopped; }, 5.0));
  ASSERT_TRUE(c.runner->stop_streaming());
  EXPECT_FALSE(c.runner->streaming());
  c.run_s(0.1);  // what was in flight
  const auto at_stop = c.runner->client_stats().log_samples;
  c.run_s(1.0);
  EXPECT_EQ(c.runner->client_stats().log_samples, at_stop);
  // Restarted: streams again, and the pause is not counted as lost packets.
  const auto missed = c.runner->client_stats().log_missed;
  c.runner->start_streaming();
  c.run_s(1.0);
  EXPECT_GT(c.runner->client_stats().log_samples, at_stop + 200u);
  EXPECT_EQ(c.runner->client_stats().log_missed, missed);
}

// Event driven (issue 36): while the behaviour flies (forward mode) its setpoint leaves
// on arrival, between the 20 ms ticks, and the watchdog adds nothing while setpoints
// flow; in every other mode an arriving setpoint sends nothing (the operator's mode
// is paced by the watchdog), and once the behaviour goes silent the watchdog sends
// every period again (hover hold).
TEST(OperatorCrtp, InForwardModeTheBehavioursSetpointLeavesOnArrivalAndTheWatchdogOnlyFillsGaps) {
  Crtp c;
  c.to(Mode::kHovering);
  // Hovering: an arriving setpoint is not sent; the firmware keeps the operator's hover.
  c.run_s(0.007);
  uint64_t before = c.fw.emulator().stats().setpoints;
  tactile_msgs::msg::HoverSetpoint sp;
  sp.vx = 0.3;
  sp.height = 0.45;
  EXPECT_FALSE(c.runner->on_hover_setpoint(sp, c.t));
  EXPECT_EQ(c.fw.emulator().stats().setpoints, before);

  ASSERT_TRUE(c.runner->start_behaviour(c.t).accepted);
  c.run_s(0.2);
  ASSERT_EQ(c.runner->mode(), Mode::kForward);
  // Off the 20 ms grid: the setpoint reaches the firmware before on_timer runs.
  c.run_s(0.007);
  ASSERT_NE(c.t % (20 * kMs), 0);
  before = c.fw.emulator().stats().setpoints;
  sp.vx = 0.25;
  EXPECT_TRUE(c.runner->on_hover_setpoint(sp, c.t));
  EXPECT_EQ(c.fw.emulator().stats().setpoints, before + 1);
  const auto cmd = c.fw.emulator().commander(c.ms());
  EXPECT_EQ(cmd.setpoint.kind, commander::Setpoint::Kind::kHover);
  EXPECT_FLOAT_EQ(cmd.setpoint.a, 0.25f);

  // Setpoints every 20 ms (Crtp::step): 50 packets a second, not 100 -- the watchdog
  // stays quiet while they arrive.
  c.run_s(0.013);  // back on the grid
  before = c.fw.emulator().stats().setpoints;
  const auto ticks = c.runner->tick_stats();
  c.run_s(1.0);
  EXPECT_EQ(c.fw.emulator().stats().setpoints - before, 50u);
  EXPECT_EQ(c.runner->tick_stats().event_steps - ticks.event_steps, 50u);
  EXPECT_EQ(c.runner->tick_stats().watchdog_steps - ticks.watchdog_steps, 0u);

  // The behaviour goes silent: the watchdog steps every period (forward -> hover hold).
  c.behaviour = false;
  before = c.fw.emulator().stats().setpoints;
  c.run_s(0.4);
  EXPECT_EQ(c.runner->mode(), Mode::kHoverHold);
  EXPECT_EQ(c.fw.emulator().stats().setpoints - before, 20u);
}

// The watchdog is quiet only in forward mode: right after a setpoint stepped the logic,
// an emergency stop's repeat (land_and_stop's abort path) and a land's first setpoint go
// out on the very next on_timer call, not one period later.
TEST(OperatorCrtp, LeavingForwardTheNextWatchdogCallSendsAtOnce) {
  for (const bool emergency : {true, false}) {
    SCOPED_TRACE(emergency ? "emergency stop" : "land");
    Crtp c;
    c.to(Mode::kForward);
    c.run_s(0.1);
    ASSERT_TRUE(c.run_until([&] { return c.t % (20 * kMs) == 0; }, 0.02));
    c.run_s(0.013);  // between two 20 ms ticks, more than half a period after the last setpoint
    tactile_msgs::msg::HoverSetpoint sp;
    sp.height = 0.5;
    ASSERT_TRUE(c.runner->on_hover_setpoint(sp, c.t));  // a setpoint stepped the logic now
    ASSERT_TRUE((emergency ? c.runner->emergency_stop(c.t) : c.runner->land(0.0, 1.0, c.t)).accepted);
    const uint64_t before = c.fw.emulator().stats().setpoints;
    EXPECT_TRUE(c.runner->on_timer(c.t));
    EXPECT_EQ(c.fw.emulator().stats().setpoints, before + 1);
  }
}
