// CrazyflieBridgeLogic: log samples -> messages, setpoint clamping, the
// stale -> hover -> land -> stop chain, parameters.
#include <gtest/gtest.h>

#include <cmath>

#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "crazyflie_bridge/protocol.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"

using namespace crazyflie_bridge;
using Mode = CrazyflieBridgeLogic::Mode;

namespace {
constexpr int64_t kMs = 1000000;

LogSample sample(uint8_t block, std::vector<double> v) {
  LogSample s;
  s.block_id = block;
  s.values = std::move(v);
  return s;
}

tactile_msgs::msg::HoverSetpoint hover(double vx, double vy, double yr, double z) {
  tactile_msgs::msg::HoverSetpoint h;
  h.vx = vx;
  h.vy = vy;
  h.yaw_rate = yr;
  h.height = z;
  return h;
}

commander::Setpoint decode(const std::optional<CrtpPacket>& pk) {
  EXPECT_TRUE(pk.has_value());
  return commander::decode(*pk);
}

CrazyflieBridgeLogic::Params autostart_params() {
  CrazyflieBridgeLogic::Params p;
  p.autostart = true;  // the forwarding chain without an operator (lockstep SITL)
  return p;
}

/// The old forwarding chain: autostart (forward from the first fresh setpoint).
struct Rig {
  CrazyflieBridgeLogic logic{autostart_params()};
  int64_t t = 0;
  Rig() { logic.set_block_ids(1, 2); }
  /// 20 ms tick: state sample at height z, optional setpoint, timer.
  std::optional<CrtpPacket> tick(bool log, bool setpoint, double z = 0.4,
                                 tactile_msgs::msg::HoverSetpoint sp = hover(0.2, 0, 0, 0.4)) {
    t += 20 * kMs;
    if (log) logic.on_log_sample(sample(2, {1, 2, z, 90, 0.1, 0.0}), t);
    if (setpoint) logic.on_hover_setpoint(sp, t);
    return logic.on_timer(t);
  }
};
}  // namespace

TEST(BridgeLogic, WhiskerSampleToPressureMessages) {
  CrazyflieBridgeLogic::Params p;
  p.pressure_scale = 100.0;  // e.g. a deck logging hPa
  CrazyflieBridgeLogic l(p);
  l.set_block_ids(1, 2);
  auto out = l.on_log_sample(sample(1, {1013.1, 1013.2, 1013.3, 1000.4, 1000.5, 1000.6}), 5 * kMs);
  ASSERT_TRUE(out.left && out.right);
  EXPECT_FALSE(out.odom);
  EXPECT_EQ(out.left->whisker_id, tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT);
  EXPECT_EQ(out.right->whisker_id, tactile_msgs::msg::WhiskerPressure::WHISKER_RIGHT);
  EXPECT_DOUBLE_EQ(out.left->pressure[2], 101330.0);
  EXPECT_DOUBLE_EQ(out.right->pressure[0], 100040.0);
  EXPECT_TRUE(std::isnan(out.left->temperature[0]));
  EXPECT_EQ(tactile_common::from_stamp(out.left->header.stamp), 5 * kMs);
  out = l.on_log_sample(sample(1, {1, 2, 3, 4, 5, 6}), 25 * kMs);
  EXPECT_EQ(out.left->sequence, 1u);
  EXPECT_EQ(l.whisker_block(), (std::vector<std::string>{"Whisker.Barometer1_1", "Whisker.Barometer1_2",
                                                          "Whisker.Barometer1_3", "Whisker1.Barometer2_1",
                                                          "Whisker1.Barometer2_2", "Whisker1.Barometer2_3"}));
}

TEST(BridgeLogic, StateSampleToOdometry) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});
  l.set_block_ids(1, 2);
  // x, y, z, yaw = 90 deg, world velocity (0.3, 0.1): body = (0.1, -0.3).
  const auto out = l.on_log_sample(sample(2, {1.0, 2.0, 0.4, 90.0, 0.3, 0.1}), 0);
  ASSERT_TRUE(out.odom);
  const auto& o = *out.odom;
  EXPECT_DOUBLE_EQ(o.pose.pose.position.z, 0.4);
  EXPECT_NEAR(o.pose.pose.orientation.z, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(o.pose.pose.orientation.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(o.twist.twist.linear.x, 0.1, 1e-12);
  EXPECT_NEAR(o.twist.twist.linear.y, -0.3, 1e-12);
}

TEST(BridgeLogic, BadSamplesCounted) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});
  l.set_block_ids(1, 2);
  EXPECT_FALSE(l.on_log_sample(sample(3, {1, 2, 3, 4, 5, 6}), 0).left);
  EXPECT_FALSE(l.on_log_sample(sample(1, {1, 2, 3}), 0).left);
  EXPECT_FALSE(l.on_log_sample(sample(1, {1, 2, NAN, 4, 5, 6}), 0).left);
  EXPECT_EQ(l.stats().dropped_unknown_block, 2u);
  EXPECT_EQ(l.stats().dropped_nonfinite, 1u);
  l.on_hover_setpoint(hover(NAN, 0, 0, 0.4), 0);
  EXPECT_EQ(l.stats().dropped_setpoint_nonfinite, 1u);
}

TEST(BridgeLogic, ForwardsClampedHoverSetpoints) {
  Rig r;
  EXPECT_FALSE(r.tick(false, true));  // no log data yet: nothing sent
  auto s = decode(r.tick(true, true, 0.4, hover(0.9, -0.2, 2.0, 3.0)));
  EXPECT_EQ(r.logic.mode(), Mode::kForward);
  EXPECT_EQ(s.kind, commander::Setpoint::Kind::kHover);
  EXPECT_FLOAT_EQ(s.a, 0.5f);                                   // max_velocity
  EXPECT_FLOAT_EQ(s.b, -0.2f);
  EXPECT_FLOAT_EQ(s.c, static_cast<float>(1.0 * 180 / M_PI));   // max_yaw_rate 1 rad/s in deg/s
  EXPECT_FLOAT_EQ(s.d, 1.5f);                                   // max_height
  EXPECT_EQ(r.logic.stats().setpoints_clamped, 1u);
  s = decode(r.tick(true, true, 0.4, hover(0.1, 0.0, -0.5, 0.4)));
  EXPECT_FLOAT_EQ(s.c, static_cast<float>(-0.5 * 180 / M_PI));  // CCW positive as in type 10
}

TEST(BridgeLogic, StaleSetpointsHoverThenLandThenStop) {
  Rig r;
  for (int i = 0; i < 10; ++i) r.tick(true, true);
  ASSERT_EQ(r.logic.mode(), Mode::kForward);
  // Setpoints stop; log data continues. 0.2 s later: hover in place.
  int i = 0;
  while (r.logic.mode() == Mode::kForward) {
    r.tick(true, false);
    ASSERT_LT(++i, 20);
  }
  EXPECT_EQ(i, 11);  // first tick with age > 0.2 s
  EXPECT_EQ(r.logic.mode(), Mode::kHoverHold);
  auto s = decode(r.tick(true, false));
  EXPECT_EQ(s.a, 0.f);
  EXPECT_EQ(s.b, 0.f);
  EXPECT_FLOAT_EQ(s.d, 0.4f);  // hold the last height
  // After hover_hold_s = 1 s: landing, height ramps down at 0.25 m/s.
  int hold = 1;
  while (r.logic.mode() == Mode::kHoverHold) {
    r.tick(true, false);
    ++hold;
  }
  EXPECT_NEAR(hold * 0.02, 1.0, 0.03);
  ASSERT_EQ(r.logic.mode(), Mode::kLanding);
  double z = 0.4, last_cmd = 0.4;
  int n = 0;
  std::optional<CrtpPacket> pk;
  while (r.logic.mode() == Mode::kLanding) {
    pk = r.tick(true, true, z);  // setpoints come back: landing is latched
    const auto sp = commander::decode(*pk);
    if (sp.kind == commander::Setpoint::Kind::kHover) {
      EXPECT_LT(sp.d, last_cmd + 1e-6);
      last_cmd = sp.d;
      z = sp.d;  // vehicle follows
    }
    ASSERT_LT(++n, 200);
  }
  EXPECT_NEAR(n * 0.02, (0.4 - 0.05) / 0.25, 0.1);
  EXPECT_EQ(commander::decode(*pk).kind, commander::Setpoint::Kind::kStop);
  EXPECT_EQ(r.logic.mode(), Mode::kStopped);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(decode(r.tick(true, true)).kind, commander::Setpoint::Kind::kStop);
  EXPECT_FALSE(r.tick(true, true));  // nothing after 5 stops
  EXPECT_EQ(r.logic.stats().stale_events, 1u);
  EXPECT_EQ(r.logic.stats().landings, 1u);
}

TEST(BridgeLogic, LinkLossAlsoTriggersHoverAndShortGlitchRecovers) {
  Rig r;
  for (int i = 0; i < 10; ++i) r.tick(true, true);
  // Log data missing for 0.3 s: hover hold; data back within hover_hold_s: forward again.
  for (int i = 0; i < 15; ++i) r.tick(false, true);
  EXPECT_EQ(r.logic.mode(), Mode::kHoverHold);
  r.tick(true, true);
  EXPECT_EQ(r.logic.mode(), Mode::kForward);
  EXPECT_EQ(r.logic.stats().stale_events, 1u);
}

TEST(BridgeLogic, LandRequestFromPipeline) {
  Rig r;
  for (int i = 0; i < 5; ++i) r.tick(true, true);
  auto land = hover(0, 0, 0, 0);
  land.land = true;
  const auto s = decode(r.tick(true, true, 0.4, land));
  EXPECT_EQ(r.logic.mode(), Mode::kLanding);
  EXPECT_LT(s.d, 0.4f);
}

TEST(BridgeLogic, ParametersDefaultsAndValidation) {
  const auto m = CrazyflieBridgeLogic::default_parameters();
  const auto p = CrazyflieBridgeLogic::params_from(m);
  EXPECT_EQ(p.whisker_period_ms, 20);
  EXPECT_EQ(p.state_period_ms, 10);
  EXPECT_EQ(p.uri, "radio://0/80/2M/E7E7E7E7E7?safelink=1");
  auto bad = m;
  bad.set("setpoint_rate_hz", 1.0);
  EXPECT_THROW(CrazyflieBridgeLogic::params_from(bad), tactile_common::ParamError);
  bad = m;
  bad.set("uri", std::string("radio://0/200"));
  try {
    CrazyflieBridgeLogic::params_from(bad);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("channel"), std::string::npos) << e.what();
  }
  bad = m;
  bad.set("state_vars", std::vector<std::string>{"stateEstimate.x"});
  EXPECT_THROW(CrazyflieBridgeLogic::params_from(bad), tactile_common::ParamError);
}

// The log periods are u16 on the link (start_block_v2): every integer
// parameter set to its default + 2^32 (65536 + 20 would be 20 as a u16 too) is
// rejected with its key and the value as given, not a message for both keys.
TEST(BridgeLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(CrazyflieBridgeLogic::default_parameters(),
                                                        [](const tactile_common::ParamMap& m) { CrazyflieBridgeLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 3u);  // whisker_period_ms, state_period_ms, status_period_ms
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
  auto m = CrazyflieBridgeLogic::default_parameters();
  m.set("state_period_ms", int64_t{65536 + 10});
  try {
    CrazyflieBridgeLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("crazyflie_bridge.ros__parameters.state_period_ms: must be in [1, 65535], got 65546"),
              std::string::npos) << e.what();
  }
}

TEST(BridgeLogic, RepositoryConfigEqualsDefaults) {
  const auto loaded = tactile_common::load_node_parameters(TACTILE_CONFIG_DIR "/crazyflie_bridge.yaml",
                                                           CrazyflieBridgeLogic::kNodeName,
                                                           CrazyflieBridgeLogic::default_parameters());
  EXPECT_EQ(loaded.values(), CrazyflieBridgeLogic::default_parameters().values());
}
