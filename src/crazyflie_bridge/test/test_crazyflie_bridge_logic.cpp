// CrazyflieBridgeLogic: log samples -> messages, setpoint clamping, the
// stale -> hover -> land -> stop chain, parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "crazyflie_bridge/protocol.hpp"
#include "tactile_common/geometry.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"

using namespace crazyflie_bridge;
using Mode = CrazyflieBridgeLogic::Mode;

namespace {
constexpr int64_t kMs = 1000000;

LogSample sample(uint8_t block, std::vector<double> v, uint32_t timestamp_ms = 0) {
  LogSample s;
  s.block_id = block;
  s.timestamp_ms = timestamp_ms;
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
    if (log) logic.on_log_sample(sample(2, {1, 2, z, 90, 0.1, 0.0}, static_cast<uint32_t>(t / kMs)), t);
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
  auto out = l.on_log_sample(sample(1, {1013.1, 1013.2, 1013.3, 1000.4, 1000.5, 1000.6}, 5), 5 * kMs);
  ASSERT_TRUE(out.left && out.right);
  EXPECT_FALSE(out.odom);
  EXPECT_EQ(out.left->whisker_id, tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT);
  EXPECT_EQ(out.right->whisker_id, tactile_msgs::msg::WhiskerPressure::WHISKER_RIGHT);
  EXPECT_DOUBLE_EQ(out.left->pressure[2], 101330.0);
  EXPECT_DOUBLE_EQ(out.right->pressure[0], 100040.0);
  EXPECT_TRUE(std::isnan(out.left->temperature[0]));
  EXPECT_EQ(tactile_common::from_stamp(out.left->header.stamp), 5 * kMs);
  out = l.on_log_sample(sample(1, {1, 2, 3, 4, 5, 6}, 25), 25 * kMs);
  EXPECT_EQ(out.left->sequence, 1u);
  EXPECT_EQ(out.right->sequence, 1u);
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

// REP 105 frames behind frame_prefix: the odometry is odom -> base_link, the pressures
// are in the whisker frames, and the static transforms and the URDF carry the
// whiskered Crazyflie's geometry (tactile_sim's, 000's whiskers) under the same names.
// initial_position (a robots file's) is the map -> odom translation, identity by default;
// anything but 3 finite values is refused naming the key.
TEST(BridgeLogic, InitialPositionIsTheMapToOdomTranslation) {
  const auto map_to_odom = [](const CrazyflieBridgeLogic& l) {
    for (const auto& f : l.static_frames()) {
      if (f.parent == "map") return f;
    }
    ADD_FAILURE() << "no map -> odom";
    return tactile_common::StaticFrame{};
  };
  {
    const auto f = map_to_odom(CrazyflieBridgeLogic(CrazyflieBridgeLogic::Params{}));
    EXPECT_EQ(f.child, "odom");
    EXPECT_EQ(f.transform.xyz, (std::array<double, 3>{0.0, 0.0, 0.0}));
  }
  auto m = CrazyflieBridgeLogic::default_parameters();
  m.set("frame_prefix", std::string("cf2/"));
  m.set("initial_position", std::vector<double>{1.5, -0.5, 0.0});
  const auto f = map_to_odom(CrazyflieBridgeLogic(CrazyflieBridgeLogic::params_from(m)));
  EXPECT_EQ(f.child, "cf2/odom");
  EXPECT_EQ(f.transform.xyz, (std::array<double, 3>{1.5, -0.5, 0.0}));
  EXPECT_EQ(f.transform.rpy, (std::array<double, 3>{0.0, 0.0, 0.0}));
  for (const auto& bad : {std::vector<double>{1.0, 2.0}, std::vector<double>{0.0, std::nan(""), 0.0}}) {
    m.set("initial_position", bad);
    try {
      CrazyflieBridgeLogic::params_from(m);
      FAIL() << "accepted initial_position of " << bad.size() << " values";
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find("initial_position: must be [x, y, z], 3 finite values in m"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(BridgeLogic, FramesArePrefixedAndMatchTheStaticTree) {
  CrazyflieBridgeLogic::Params p;
  p.frame_prefix = "cf1/";
  CrazyflieBridgeLogic l(p);
  l.set_block_ids(1, 2);
  const auto w = l.on_log_sample(sample(1, {1, 2, 3, 4, 5, 6}, 5), 5 * kMs);
  ASSERT_TRUE(w.left && w.right);
  EXPECT_EQ(w.left->header.frame_id, "cf1/whisker_left");
  EXPECT_EQ(w.right->header.frame_id, "cf1/whisker_right");
  const auto o = l.on_log_sample(sample(2, {1.0, 2.0, 0.4, 90.0, 0.3, 0.1}), 0).odom;
  ASSERT_TRUE(o);
  EXPECT_EQ(o->header.frame_id, "cf1/odom");
  EXPECT_EQ(o->child_frame_id, "cf1/base_link");
  std::map<std::string, std::string> parent;
  for (const auto& f : l.static_frames()) parent[f.child] = f.parent;
  EXPECT_EQ(parent["cf1/odom"], "map");
  for (const char* child : {"cf1/whisker_left", "cf1/whisker_right", "cf1/imu_link", "cf1/flow", "cf1/tof_down"}) {
    EXPECT_EQ(parent[child], "cf1/base_link") << child;
  }
  const std::string urdf = l.robot_description();
  EXPECT_NE(urdf.find("<child link=\"cf1/whisker_left\"/>"), std::string::npos) << urdf;
  // A bad prefix is refused with the key and the reason.
  auto m = CrazyflieBridgeLogic::default_parameters();
  m.set("frame_prefix", std::string("cf1"));
  try {
    CrazyflieBridgeLogic::params_from(m);
    FAIL() << "accepted frame_prefix cf1";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("frame_prefix: must end with '/'"), std::string::npos) << e.what();
  }
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

// The flight parameters' spec: every key described, no described range wider than what
// params_from()/validate() accept, none live.
TEST(BridgeLogic, EveryParameterIsDescribedWithTheRangeValidateAcceptsAndNoneIsLive) {
  const tactile_common::ParamMap d = CrazyflieBridgeLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak : tactile_common::range_leaks(
           d, [](const tactile_common::ParamMap& m) { CrazyflieBridgeLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
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

// ---- Link truth: sequence and stamps from the firmware clock ----

TEST(BridgeLogic, SequenceFromFirmwareTimestampsShowsLostPackets) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});  // whisker block 20 ms
  l.set_block_ids(1, 2);
  const std::vector<double> v{1, 2, 3, 4, 5, 6};
  std::vector<uint32_t> seq;
  // Firmware times 1000, 1020, (1040 lost), 1061 (1 ms jitter), 1080, then across
  // the 24-bit wrap: 0xFFFFF0 + 20 k.
  for (uint32_t ts : {1000u, 1020u, 1061u, 1080u}) seq.push_back(l.on_log_sample(sample(1, v, ts), (ts + 3) * kMs).left->sequence);
  EXPECT_EQ(seq, (std::vector<uint32_t>{0, 1, 3, 4}));
  EXPECT_EQ(l.stats().log_samples_missed, 1u);

  CrazyflieBridgeLogic w(CrazyflieBridgeLogic::Params{});
  w.set_block_ids(1, 2);
  seq.clear();
  const uint32_t t0 = 0xFFFFF0;
  for (uint32_t k : {0u, 1u, 3u}) {
    const uint32_t ts = (t0 + 20 * k) & 0xFFFFFF;  // 0xFFFFF0, 0x000004, 0x00002C
    seq.push_back(w.on_log_sample(sample(1, v, ts), (int64_t{t0} + 20 * k + 2) * kMs).left->sequence);
  }
  EXPECT_EQ(seq, (std::vector<uint32_t>{0, 1, 3}));
  EXPECT_EQ(w.stats().log_samples_missed, 1u);
}

TEST(BridgeLogic, StampsAreFirmwareTimeOnTheHostClock) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});
  l.set_block_ids(1, 2);
  const std::vector<double> v{1, 2, 3, 4, 5, 6};
  // Host clock = firmware clock + 50 s; one-way delays 9, 4, 12, 4 ms: after
  // the 4-ms packet the offset is 50.004 s (the minimum receive - firmware).
  const int64_t host = 50000 * kMs;
  auto stamp = [&](uint32_t ts, int64_t delay_ms) {
    const auto o = l.on_log_sample(sample(1, v, ts), host + (ts + delay_ms) * kMs);
    return tactile_common::from_stamp(o.left->header.stamp);
  };
  EXPECT_EQ(stamp(1000, 9), host + 1009 * kMs);  // first: its own delay
  EXPECT_EQ(stamp(1020, 4), host + 1024 * kMs);
  // Late packet: still firmware time + 4 ms (+ the 200 ppm drift allowance: 4 us).
  EXPECT_NEAR(static_cast<double>(stamp(1040, 12)), static_cast<double>(host + 1044 * kMs), 10e3);
  EXPECT_EQ(stamp(1060, 4), host + 1064 * kMs);
  EXPECT_NEAR(static_cast<double>(l.log_clock().offset_ns()), static_cast<double>(host + 4 * kMs), 1e3);
}

TEST(BridgeLogic, FirmwareRestartRebasesTheSequence) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});
  l.set_block_ids(1, 2);
  const std::vector<double> v{1, 2, 3, 4, 5, 6};
  l.on_log_sample(sample(1, v, 500000), 1 * kMs);
  EXPECT_EQ(l.on_log_sample(sample(1, v, 500020), 21 * kMs).left->sequence, 1u);
  EXPECT_EQ(l.on_log_sample(sample(1, v, 100), 40 * kMs).left->sequence, 0u);  // rebooted
  EXPECT_EQ(l.stats().log_clock_restarts, 1u);
}

// ---- Odometry: full attitude, body rates, covariances ----

namespace {
struct Euler {
  double roll, pitch, yaw;
};
quatz::Quat from_euler(const Euler& e) {  // Z-Y-X
  const double cr = std::cos(e.roll / 2), sr = std::sin(e.roll / 2), cp = std::cos(e.pitch / 2),
               sp = std::sin(e.pitch / 2), cy = std::cos(e.yaw / 2), sy = std::sin(e.yaw / 2);
  return {sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
          cr * cp * cy + sr * sp * sy};
}
double dot(const geometry_msgs::msg::Quaternion& a, const quatz::Quat& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
}
}  // namespace

TEST(BridgeLogic, OdometryAttitudeRatesAndCovariancesFromTheEstimate) {
  CrazyflieBridgeLogic::Params p;
  CrazyflieBridgeLogic l(p);
  l.set_block_ids(1, 3);
  l.set_attitude_block_id(2);
  EXPECT_EQ(l.attitude_block(false), AttitudeBlock::compressed_vars());
  EXPECT_EQ(l.attitude_block(true).size(), 7u);
  const Euler e{10 * M_PI / 180, -5 * M_PI / 180, 30 * M_PI / 180};
  const auto q = from_euler(e);
  // Firmware: quat compressed, rates in mrad/s with the pitch rate negated.
  l.on_log_sample(sample(2, {double(quatz::compress(q)), 120, 340, -560}, 1000), 1001 * kMs);
  const auto out = l.on_log_sample(sample(3, {1.0, 2.0, 0.4, 30.0, 0.3, 0.1}, 1000), 1001 * kMs);
  ASSERT_TRUE(out.odom);
  const auto& o = *out.odom;
  // 9-bit components: within 0.2 deg of the true attitude; yaw exactly the float yaw.
  EXPECT_GT(std::fabs(dot(o.pose.pose.orientation, q)), std::cos(0.2 * M_PI / 180 / 2));
  EXPECT_NEAR(tactile_common::yaw_of(o.pose.pose.orientation), e.yaw, 1e-12);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.x, 0.120);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.y, -0.340);  // REP-103 pitch rate: firmware sign restored
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.z, -0.560);
  EXPECT_DOUBLE_EQ(o.pose.covariance[0], p.position_variance);
  EXPECT_DOUBLE_EQ(o.pose.covariance[14], p.position_variance);
  EXPECT_DOUBLE_EQ(o.pose.covariance[21], p.orientation_variance);
  EXPECT_DOUBLE_EQ(o.pose.covariance[35], p.orientation_variance);
  EXPECT_DOUBLE_EQ(o.twist.covariance[7], p.linear_velocity_variance);
  EXPECT_DOUBLE_EQ(o.twist.covariance[28], p.angular_velocity_variance);
  EXPECT_DOUBLE_EQ(o.pose.covariance[1], 0.0);
  EXPECT_EQ(tactile_common::from_stamp(o.header.stamp), 1001 * kMs);

  // With kalman.varX/Y/Z in the block: the estimate's position variances.
  l.on_log_sample(sample(2, {double(quatz::compress(q)), 0, 0, 0, 0.04, 0.09, 0.0025}, 1010), 1011 * kMs);
  const auto o2 = l.on_log_sample(sample(3, {1.0, 2.0, 0.4, 30.0, 0.3, 0.1}, 1010), 1011 * kMs).odom;
  ASSERT_TRUE(o2);
  EXPECT_FLOAT_EQ(static_cast<float>(o2->pose.covariance[0]), 0.04f);
  EXPECT_FLOAT_EQ(static_cast<float>(o2->pose.covariance[7]), 0.09f);
  EXPECT_FLOAT_EQ(static_cast<float>(o2->pose.covariance[14]), 0.0025f);
}

TEST(BridgeLogic, OdometryNeedsAnAttitudeSampleLessThanTwoPeriodsAway) {
  CrazyflieBridgeLogic l(CrazyflieBridgeLogic::Params{});  // state period 10 ms
  l.set_block_ids(1, 3);
  l.set_attitude_block_id(2);
  const std::vector<double> st{1.0, 2.0, 0.4, 0.0, 0.0, 0.0};
  EXPECT_FALSE(l.on_log_sample(sample(3, st, 1000), 1001 * kMs).odom);  // none yet
  l.on_log_sample(sample(2, {double(0xC0000000u), 0, 0, 0}, 1000), 1001 * kMs);
  EXPECT_TRUE(l.on_log_sample(sample(3, st, 1010), 1011 * kMs).odom);   // this tick's lost: previous one
  EXPECT_FALSE(l.on_log_sample(sample(3, st, 1020), 1021 * kMs).odom);  // two lost: not published
  EXPECT_EQ(l.stats().odom_without_attitude, 2u);
  // Blocks 7 ms out of phase: the previous attitude sample (17 ms) still pairs.
  l.on_log_sample(sample(2, {double(0xC0000000u), 0, 0, 0}, 1023), 1024 * kMs);
  EXPECT_TRUE(l.on_log_sample(sample(3, st, 1030), 1031 * kMs).odom);
  EXPECT_TRUE(l.on_log_sample(sample(3, st, 1040), 1041 * kMs).odom);  // 1033 lost: 1023 is 17 ms back
  EXPECT_FALSE(l.on_log_sample(sample(3, st, 1050), 1051 * kMs).odom);
  // A pattern quatcompress never produces (three components at full 9-bit
  // magnitude: squares sum to 1.5) is rejected, not used.
  l.on_log_sample(sample(2, {double((3u << 30) | (511u << 20) | (511u << 10) | 511u), 0, 0, 0}, 1060), 1061 * kMs);
  EXPECT_EQ(l.stats().dropped_attitude_invalid, 1u);
  EXPECT_FALSE(l.on_log_sample(sample(3, st, 1060), 1061 * kMs).odom);
}

// ---- Firmware generations: the packet the timer sends ----

TEST(BridgeLogic, TimerSendsCflibsHoverPacketForTheProtocolVersion) {
  for (int version : {4, 8, 9, 10}) {
    Rig r;
    r.logic.set_protocol_version(static_cast<uint8_t>(version));
    r.tick(true, true, 0.4, hover(0.1, 0.0, 0.5, 0.4));
    const auto pk = r.tick(true, true, 0.4, hover(0.1, 0.0, 0.5, 0.4));
    ASSERT_TRUE(pk);
    PayloadReader rd(*pk, "test");
    const uint8_t type = rd.u8();
    rd.f32();
    rd.f32();
    const float yaw_field = rd.f32();
    const float yr = static_cast<float>(0.5 * 180 / M_PI);
    if (version <= 8) {  // cflib commander.py: get_protocol_version() <= 8 -> TYPE_HOVER_LEGACY, -yawrate
      EXPECT_EQ(type, commander::kTypeHoverLegacy) << version;
      EXPECT_FLOAT_EQ(yaw_field, -yr) << version;
    } else {
      EXPECT_EQ(type, commander::kTypeHover) << version;
      EXPECT_FLOAT_EQ(yaw_field, yr) << version;
    }
    // The stop and hover-in-place packets go the same way.
    for (int i = 0; i < 20; ++i) r.tick(true, false);
    EXPECT_EQ(r.logic.mode(), Mode::kHoverHold);
    const auto hold = r.tick(true, false);
    ASSERT_TRUE(hold);
    EXPECT_EQ(hold->data[0], version <= 8 ? commander::kTypeHoverLegacy : commander::kTypeHover);
  }
}

// ---------------------------------------------------------------------------
// Operator surface: the logic is put into each mode and every guard tested.

namespace {

/// Default parameters (autostart off); a vehicle whose measured height
/// follows the commanded one (motors off: on the floor); status block 3.
struct Op {
  CrazyflieBridgeLogic logic;
  int64_t t = 0;
  double z = 0.0;
  double x = 0.0;
  bool follow = true;
  std::vector<commander::Setpoint> sent;
  explicit Op(CrazyflieBridgeLogic::Params p = {}) : logic(p) {
    logic.set_block_ids(1, 2);
    logic.set_status_block(3, {"pm.vbat", "pm.state", "supervisor.info"});
  }
  std::optional<CrtpPacket> tick(bool setpoint = false, tactile_msgs::msg::HoverSetpoint sp = hover(0.2, 0, 0, 0.4),
                                 bool log = true) {
    t += 20 * kMs;
    if (log) logic.on_log_sample(sample(2, {x, 0, z, 0, 0, 0}), t);
    if (setpoint) logic.on_hover_setpoint(sp, t);
    auto pk = logic.on_timer(t);
    if (pk) {
      const auto s = commander::decode(*pk);
      sent.push_back(s);
      if (follow) {
        if (s.kind == commander::Setpoint::Kind::kHover) z = s.d;
        if (s.kind == commander::Setpoint::Kind::kPosition) {
          x = s.a;
          z = s.c;
        }
        if (s.kind == commander::Setpoint::Kind::kStop) z = 0.0;
      }
    }
    return pk;
  }
  void status(double vbat, int supervisor) { logic.on_log_sample(sample(3, {vbat, 0, static_cast<double>(supervisor)}), t); }
  template <class Pred>
  int tick_until(Pred done, bool setpoint = false, int max = 1000) {
    int n = 0;
    while (!done()) {
      tick(setpoint);
      if (++n > max) {
        ADD_FAILURE() << "still in " << to_string(logic.mode());
        break;
      }
    }
    return n;
  }
  /// Drives the logic into `m` the way an operator would.
  void to(Mode m) {
    for (int i = 0; i < 5; ++i) tick();
    if (m == Mode::kGrounded) return;
    if (m == Mode::kEmergency) {
      ASSERT_TRUE(logic.emergency_stop(t).accepted);
      return;
    }
    ASSERT_TRUE(logic.takeoff(0.4, 1.0, t).accepted);
    tick();
    if (m == Mode::kTakingOff) return;
    tick_until([&] { return logic.mode() == Mode::kHovering; });
    if (m == Mode::kHovering) return;
    if (m == Mode::kGoTo) {
      ASSERT_TRUE(logic.go_to(0.3, 0.0, 0.5, 0.0, 2.0, false, t).accepted);
      tick();
      return;
    }
    if (m == Mode::kLanding || m == Mode::kStopped) {
      ASSERT_TRUE(logic.land(0.0, 2.0, t).accepted);
      tick();
      if (m == Mode::kStopped) tick_until([&] { return logic.mode() == Mode::kStopped; });
      return;
    }
    tick(true);
    ASSERT_TRUE(logic.start_behaviour(t).accepted);
    tick(true);
    if (m == Mode::kForward) return;
    tick_until([&] { return logic.mode() == Mode::kHoverHold; });  // setpoints stop
  }
};

const std::vector<Mode> kAllModes{Mode::kGrounded, Mode::kTakingOff, Mode::kHovering, Mode::kGoTo, Mode::kForward,
                                  Mode::kHoverHold, Mode::kLanding, Mode::kStopped, Mode::kEmergency};
const std::vector<Mode> kAirborne{Mode::kTakingOff, Mode::kHovering, Mode::kGoTo, Mode::kForward, Mode::kHoverHold};

}  // namespace

TEST(BridgeOperator, EachModeReachable) {
  for (Mode m : kAllModes) {
    Op op;
    op.to(m);
    EXPECT_EQ(op.logic.mode(), m) << to_string(m);
  }
}

// Autostart off: fresh setpoints and log data do not start a flight; nothing
// is sent (not even a stop) until take-off.
TEST(BridgeOperator, GroundedSendsNothingUntilTakeoff) {
  Op op;
  for (int i = 0; i < 200; ++i) EXPECT_FALSE(op.tick(true)) << i;
  EXPECT_EQ(op.logic.mode(), Mode::kGrounded);
  EXPECT_EQ(op.logic.stats().packets_out, 0u);
  EXPECT_TRUE(op.logic.take_outbox().empty());
  EXPECT_EQ(op.logic.stats().transitions_total, 0u);
}

TEST(BridgeOperator, TakeoffRampsFromMeasuredHeightThenHovers) {
  Op op;
  op.z = 0.02;
  for (int i = 0; i < 3; ++i) op.tick();
  const auto r = op.logic.takeoff(0.5, 1.0, op.t);
  ASSERT_TRUE(r.accepted) << r.reason;
  EXPECT_EQ(op.logic.mode(), Mode::kTakingOff);
  double last = 0.0;
  int n = op.tick_until([&] { return op.logic.mode() == Mode::kHovering; });
  EXPECT_NEAR(n * 0.02, 1.02, 0.03);  // the ramp's last setpoint, then hovering
  for (const auto& s : op.sent) {
    EXPECT_EQ(s.kind, commander::Setpoint::Kind::kHover);
    EXPECT_EQ(s.a, 0.f);
    EXPECT_EQ(s.b, 0.f);
    EXPECT_EQ(s.c, 0.f);
    EXPECT_GE(s.d, last - 1e-6);
    last = s.d;
  }
  EXPECT_NEAR(op.sent.front().d, 0.02 + 0.48 * 0.02, 1e-3);  // first tick: 20 ms into the ramp from 0.02 m
  EXPECT_FLOAT_EQ(op.sent.back().d, 0.5f);
  const auto s = decode(op.tick(true));  // hovering: the behaviour's setpoints are not forwarded
  EXPECT_EQ(s.a, 0.f);
  EXPECT_FLOAT_EQ(s.d, 0.5f);
  EXPECT_EQ(op.logic.stats().transitions.at("grounded->taking_off:takeoff"), 1u);
  EXPECT_EQ(op.logic.stats().transitions.at("taking_off->hovering:takeoff_done"), 1u);
}

TEST(BridgeOperator, TakeoffGuards) {
  {
    Op op;  // no state estimate yet
    const auto r = op.logic.takeoff(0.4, 2.0, 0);
    EXPECT_FALSE(r.accepted);
    EXPECT_NE(r.reason.find("no fresh state estimate"), std::string::npos) << r.reason;
  }
  Op op;
  op.to(Mode::kGrounded);
  auto refused = [&](double h, double d, const char* why) {
    const auto r = op.logic.takeoff(h, d, op.t);
    EXPECT_FALSE(r.accepted) << why;
    EXPECT_NE(r.reason.find(why), std::string::npos) << r.reason;
  };
  refused(2.0, 3.0, "outside");           // > max_height
  refused(0.03, 1.0, "outside");          // <= land_height
  refused(NAN, 1.0, "outside");
  refused(0.4, 0.0, "duration");
  refused(1.2, 0.5, "max_vertical_speed");  // 2.4 m/s
  op.status(3.1, 0x0F);
  refused(0.4, 2.0, "battery 3.10 V");
  op.status(3.9, 0x01);                   // can be armed, not armed (brushless, no arming request)
  refused(0.4, 2.0, "not armed");
  op.status(3.9, 0x0B | 0x20);            // armed but tumbled
  refused(0.4, 2.0, "tumbled");
  op.status(3.9, 0x0B);                   // armed, can fly
  EXPECT_TRUE(op.logic.takeoff(0.4, 2.0, op.t).accepted);
  const auto again = op.logic.takeoff(0.4, 2.0, op.t);
  EXPECT_FALSE(again.accepted);
  EXPECT_EQ(again.reason, "takeoff refused: mode is taking_off");
  EXPECT_EQ(op.logic.stats().commands_refused, 9u);
  EXPECT_EQ(op.logic.stats().commands_accepted, 1u);
}

TEST(BridgeOperator, HandOverForwardsThenHandBackHovers) {
  Op op;
  op.to(Mode::kHovering);
  auto r = op.logic.start_behaviour(op.t);  // no setpoint yet
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("no fresh cmd_hover setpoint"), std::string::npos) << r.reason;
  op.tick(true, hover(0.3, 0.1, 0.2, 0.6));
  ASSERT_TRUE(op.logic.start_behaviour(op.t).accepted);
  auto s = decode(op.tick(true, hover(0.9, 0.1, 0.2, 0.6)));  // forwarded, clamped
  EXPECT_EQ(op.logic.mode(), Mode::kForward);
  EXPECT_FLOAT_EQ(s.a, 0.5f);
  EXPECT_FLOAT_EQ(s.d, 0.6f);
  // Hand-back: the last setpoint stays valid 100 ms (zero velocity), new ones are not forwarded.
  r = op.logic.notify_setpoints_stop(100, op.t);
  ASSERT_TRUE(r.accepted) << r.reason;
  EXPECT_FALSE(op.logic.notify_setpoints_stop(100, op.t).accepted);  // already pending
  for (int i = 0; i < 4; ++i) {
    s = decode(op.tick(true, hover(0.2, 0, 0, 1.0)));
    EXPECT_EQ(op.logic.mode(), Mode::kForward);
    EXPECT_EQ(s.a, 0.f);
    EXPECT_FLOAT_EQ(s.d, 0.6f);
  }
  s = decode(op.tick(true, hover(0.2, 0, 0, 1.0)));
  EXPECT_EQ(op.logic.mode(), Mode::kHovering);
  EXPECT_FLOAT_EQ(s.d, 0.6f);  // holds the height it was handed back at
  EXPECT_EQ(s.a, 0.f);
  EXPECT_EQ(op.logic.stats().transitions.at("forward->hovering:notify_setpoints_stop"), 1u);
}

TEST(BridgeOperator, StartBehaviourOnlyFromHovering) {
  for (Mode m : kAllModes) {
    if (m == Mode::kHovering) continue;
    Op op;
    op.to(m);
    op.tick(true);
    if (op.logic.mode() != m) continue;  // a mode that ends by itself after one tick
    const auto r = op.logic.start_behaviour(op.t);
    EXPECT_FALSE(r.accepted) << to_string(m);
    EXPECT_NE(r.reason.find(std::string("mode is ") + to_string(m)), std::string::npos) << r.reason;
  }
}

TEST(BridgeOperator, NotifySetpointsStopOnlyWhileForwarding) {
  Op op;
  op.to(Mode::kHovering);
  EXPECT_FALSE(op.logic.notify_setpoints_stop(0, op.t).accepted);
  Op hold;
  hold.to(Mode::kHoverHold);
  EXPECT_TRUE(hold.logic.notify_setpoints_stop(0, hold.t).accepted);
  EXPECT_EQ(hold.logic.mode(), Mode::kHovering);
}

TEST(BridgeOperator, GoToSendsInterpolatedPositionSetpoints) {
  Op op;
  op.to(Mode::kHovering);
  EXPECT_FALSE(op.logic.go_to(2.0, 0, 0.4, 0, 1.0, false, op.t).accepted);  // 2 m/s > max_velocity
  EXPECT_FALSE(op.logic.go_to(0.5, 0, 1.6, 0, 5.0, false, op.t).accepted);  // above max_height
  ASSERT_TRUE(op.logic.go_to(0.5, 0.0, 0.6, 0.2, 2.0, false, op.t).accepted);
  EXPECT_EQ(op.logic.mode(), Mode::kGoTo);
  for (int i = 0; i < 50; ++i) op.tick();
  auto s = op.sent.back();
  EXPECT_EQ(s.kind, commander::Setpoint::Kind::kPosition);
  EXPECT_NEAR(s.a, 0.25, 0.01);  // halfway
  EXPECT_NEAR(s.c, 0.5, 0.01);
  EXPECT_NEAR(s.d, 0.1 * 180 / M_PI, 0.1);
  op.tick_until([&] { return op.logic.mode() == Mode::kHovering; });
  s = op.sent.back();
  EXPECT_NEAR(op.x, 0.5, 1e-6);
  // Relative: 0.1 m further from where it is.
  ASSERT_TRUE(op.logic.go_to(0.1, 0.0, 0.0, 0.0, 1.0, true, op.t).accepted);
  op.tick_until([&] { return op.logic.mode() == Mode::kHovering; });
  EXPECT_NEAR(op.x, 0.6, 1e-5);
  EXPECT_EQ(op.logic.stats().transitions.at("go_to->hovering:goto_done"), 2u);
  Op ground;
  ground.to(Mode::kGrounded);
  EXPECT_FALSE(ground.logic.go_to(0.1, 0, 0.4, 0, 2.0, false, ground.t).accepted);
}

// land() from every airborne mode: descends, stops the motors, then sends nothing.
TEST(BridgeOperator, LandFromEveryAirborneMode) {
  for (Mode m : kAirborne) {
    Op op;
    op.to(m);
    ASSERT_EQ(op.logic.mode(), m);
    const auto r = op.logic.land(0.0, 1.0, op.t);
    ASSERT_TRUE(r.accepted) << to_string(m) << ": " << r.reason;
    EXPECT_EQ(op.logic.mode(), Mode::kLanding);
    EXPECT_FALSE(op.logic.land(0.0, 1.0, op.t).accepted);  // already landing
    op.sent.clear();
    const int n = op.tick_until([&] { return op.logic.mode() == Mode::kStopped; }, true);
    EXPECT_LT(n * 0.02, 1.5) << to_string(m);
    ASSERT_FALSE(op.sent.empty());
    EXPECT_EQ(op.sent.back().kind, commander::Setpoint::Kind::kStop);
    for (size_t i = 0; i + 1 < op.sent.size(); ++i) EXPECT_EQ(op.sent[i].kind, commander::Setpoint::Kind::kHover);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(decode(op.tick(true)).kind, commander::Setpoint::Kind::kStop);
    EXPECT_FALSE(op.tick(true)) << to_string(m);
    EXPECT_EQ(op.logic.stats().transitions.at(std::string(to_string(m)) + "->landing:land"), 1u);
    // Take-off is allowed again after the landing.
    EXPECT_TRUE(op.logic.takeoff(0.4, 2.0, op.t).accepted) << to_string(m);
  }
}

// Touchdown waits for the measured height. The vehicle below follows the commanded height
// with a first-order lag of 0.5 s (0.1 m behind the 0.2 m/s ramp; the SITL's: 0.13 m): the motors stop only once it is at
// land_height, not when the command gets there (before: stopped at a measured 0.18 m, a
// drop). An estimate held above land_height (on an object) is stopped after
// touchdown_timeout_s at the floor; with no fresh log the command decides, as before.
TEST(BridgeOperator, TouchdownWaitsForTheMeasuredHeight) {
  auto land_with = [](double tau, double stuck_at, bool log_after_floor) {
    Op op;
    op.to(Mode::kHovering);
    op.follow = false;
    op.z = 0.4;
    EXPECT_TRUE(op.logic.land(0.0, 2.0, op.t).accepted);
    double cmd = 0.4, z_at_stop = -1.0;
    int ticks_at_floor = 0;
    for (int i = 0; i < 500 && op.logic.mode() == Mode::kLanding; ++i) {
      const bool log = log_after_floor || cmd > op.logic.params().land_height;
      const auto pk = op.tick(false, hover(0.2, 0, 0, 0.4), log);
      const auto s = commander::decode(*pk);
      if (s.kind == commander::Setpoint::Kind::kHover) cmd = s.d;
      if (s.kind == commander::Setpoint::Kind::kStop) z_at_stop = op.z;
      if (cmd <= op.logic.params().land_height) ++ticks_at_floor;
      op.z += (std::max(stuck_at, cmd) - op.z) * 0.02 / tau;  // the measured height trails the command
    }
    EXPECT_EQ(op.logic.mode(), Mode::kStopped);
    return std::make_tuple(z_at_stop, ticks_at_floor, op.logic.history().back().reason);
  };
  {  // trailing: stops when the measured height reaches land_height
    const auto [z, floor_ticks, why] = land_with(0.5, 0.0, true);
    EXPECT_LE(z, 0.05 + 1e-9);
    EXPECT_GT(floor_ticks, 10);  // the command sat at its floor while the vehicle came down
    EXPECT_EQ(why, "measured height at land_height");
  }
  {  // held at 0.12 m: stopped after touchdown_timeout_s = 1 s at the floor
    const auto [z, floor_ticks, why] = land_with(0.1, 0.12, true);
    EXPECT_NEAR(z, 0.12, 1e-3);
    EXPECT_NEAR(floor_ticks * 0.02, 1.0, 0.05);
    EXPECT_NE(why.find("touchdown_timeout_s"), std::string::npos) << why;
  }
  {  // no log once the command is at the floor: stopped on the command
    const auto [z, floor_ticks, why] = land_with(0.5, 0.0, false);
    EXPECT_GT(z, 0.05);
    EXPECT_LE(floor_ticks * 0.02, 0.25);  // log_timeout_s after the last sample
    EXPECT_NE(why.find("no fresh log"), std::string::npos) << why;
  }
  auto bad = CrazyflieBridgeLogic::Params{};
  bad.touchdown_timeout_s = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// Lost telemetry in the operator's modes (the link's downlink dead, uplink alive): a go-to
// stops where it is at once, and after log_timeout_s + hover_hold_s of silence the vehicle
// lands from taking off, hovering or the stopped go-to. Before, these modes held or flew
// on until a command came, blind.
TEST(BridgeOperator, LostTelemetryInTheOperatorModesLands) {
  for (Mode m : {Mode::kTakingOff, Mode::kHovering, Mode::kGoTo}) {
    SCOPED_TRACE(to_string(m));
    Op op;
    op.to(m);
    ASSERT_EQ(op.logic.mode(), m);
    // 0.2 s of silence: fresh until log_timeout_s; a go-to then stops (hover in place).
    for (int i = 0; i < 11; ++i) op.tick(false, hover(0.2, 0, 0, 0.4), false);
    const Mode expected = m == Mode::kTakingOff ? Mode::kTakingOff : Mode::kHovering;
    EXPECT_EQ(op.logic.mode(), expected);
    // log_timeout_s + hover_hold_s = 1.2 s after the last sample: landing.
    int n = 0;
    while (op.logic.mode() != Mode::kLanding && n < 100) op.tick(false, hover(0.2, 0, 0, 0.4), false), ++n;
    ASSERT_EQ(op.logic.mode(), Mode::kLanding);
    EXPECT_NEAR(n * 0.02 + 11 * 0.02, 1.2, 0.05);
    EXPECT_EQ(op.logic.history().back().guard, "log_lost");
  }
  // Log data back within the window: no landing.
  Op op;
  op.to(Mode::kHovering);
  for (int i = 0; i < 40; ++i) op.tick(false, hover(0.2, 0, 0, 0.4), false);
  op.tick();
  for (int i = 0; i < 100; ++i) op.tick();
  EXPECT_EQ(op.logic.mode(), Mode::kHovering);
}

TEST(BridgeOperator, LandRefusedOnTheGroundAndBadArguments) {
  for (Mode m : {Mode::kGrounded, Mode::kStopped, Mode::kEmergency}) {
    Op op;
    op.to(m);
    const auto r = op.logic.land(0.0, 1.0, op.t);
    EXPECT_FALSE(r.accepted) << to_string(m);
    EXPECT_NE(r.reason.find("not airborne"), std::string::npos) << r.reason;
  }
  Op op;
  op.to(Mode::kHovering);
  EXPECT_FALSE(op.logic.land(0.3, 1.0, op.t).accepted);  // the motors stop at land_height: not mid-air
  EXPECT_FALSE(op.logic.land(0.0, -1.0, op.t).accepted);
}

// emergency_stop() from every mode: a stop packet at once (outbox), one
// every tick after, latched: take-off refused, fresh setpoints ignored,
// arm(true) refused until the vehicle is on the ground.
TEST(BridgeOperator, EmergencyFromEveryModeLatchedUntilArmedOnTheGround) {
  for (Mode m : kAllModes) {
    Op op;
    op.to(m);
    const auto r = op.logic.emergency_stop(op.t);
    ASSERT_TRUE(r.accepted) << to_string(m);
    EXPECT_EQ(op.logic.mode(), Mode::kEmergency);
    const auto out = op.logic.take_outbox();
    ASSERT_FALSE(out.empty()) << to_string(m);
    EXPECT_EQ(commander::decode(out.back()).kind, commander::Setpoint::Kind::kStop);
    op.follow = false;
    op.z = 0.4;  // still falling
    for (int i = 0; i < 60; ++i) EXPECT_EQ(decode(op.tick(true)).kind, commander::Setpoint::Kind::kStop) << to_string(m);
    EXPECT_FALSE(op.logic.takeoff(0.4, 2.0, op.t).accepted);
    EXPECT_FALSE(op.logic.start_behaviour(op.t).accepted);
    auto a = op.logic.arm(true, op.t);
    EXPECT_FALSE(a.accepted) << to_string(m);
    EXPECT_NE(a.reason.find("not confirmed on the ground"), std::string::npos) << a.reason;
    EXPECT_TRUE(op.logic.status(op.t).emergency_latched);
    op.z = 0.0;
    op.tick();
    a = op.logic.arm(true, op.t);
    ASSERT_TRUE(a.accepted) << a.reason;
    EXPECT_EQ(op.logic.mode(), Mode::kGrounded);
    EXPECT_FALSE(op.logic.status(op.t).emergency_latched);
    EXPECT_FALSE(op.tick(true));  // grounded: nothing sent
    EXPECT_TRUE(op.logic.takeoff(0.4, 2.0, op.t).accepted);
  }
}

TEST(BridgeOperator, EmergencyNotClearedWhileTheSupervisorSaysFlying) {
  Op op;
  op.to(Mode::kHovering);
  op.logic.emergency_stop(op.t);
  op.follow = false;
  op.z = 0.0;
  op.tick();
  op.status(3.9, 0x1B);  // is flying
  EXPECT_FALSE(op.logic.arm(true, op.t).accepted);
  op.status(3.9, 0x0B);
  EXPECT_TRUE(op.logic.arm(true, op.t).accepted);
}

TEST(BridgeOperator, LowBatteryInFlightLands) {
  Op op;
  op.to(Mode::kForward);
  op.status(3.1, 0x1B);  // below 3.2 V
  const int64_t t0 = op.t;
  while (tactile_common::to_seconds(op.t - t0) < 1.9) {
    op.tick(true);
    ASSERT_EQ(op.logic.mode(), Mode::kForward);
  }
  op.status(3.3, 0x1B);  // a sag that recovers resets the hold
  op.tick(true);
  op.status(3.1, 0x1B);
  for (int i = 0; i < 90; ++i) op.tick(true);
  EXPECT_EQ(op.logic.mode(), Mode::kForward);  // 1.8 s since the recovery
  op.tick_until([&] { return op.logic.mode() != Mode::kForward; }, true);
  EXPECT_EQ(op.logic.mode(), Mode::kLanding);
  EXPECT_EQ(op.logic.stats().low_battery_events, 1u);
  EXPECT_EQ(op.logic.status(op.t).low_battery_events, 1u);
  EXPECT_EQ(op.logic.history().back().guard, "low_battery");
  EXPECT_NE(op.logic.history().back().reason.find("battery 3.10 V"), std::string::npos);
  op.tick_until([&] { return op.logic.mode() == Mode::kStopped; }, true);
  EXPECT_EQ(op.logic.stats().low_battery_events, 1u);  // not counted again on the ground
}

TEST(BridgeOperator, LowBatteryLandsFromEveryFlyingMode) {
  for (Mode m : kAirborne) {
    CrazyflieBridgeLogic::Params p;
    p.low_battery_hold_s = 0.1;
    Op op(p);
    op.to(m);
    op.status(3.0, 0x1B);
    op.tick_until([&] { return op.logic.stats().low_battery_events > 0; }, false, 20);
    const auto& h = op.logic.history();
    EXPECT_TRUE(std::any_of(h.begin(), h.end(), [&](const auto& tr) { return tr.guard == "low_battery" && tr.from == m; }))
        << to_string(m);
  }
}

TEST(BridgeOperator, ArmingRequestFollowsTheProtocolVersion) {
  Op op;
  op.to(Mode::kGrounded);
  auto r = op.logic.arm(true, op.t);
  ASSERT_TRUE(r.accepted) << r.reason;
  EXPECT_NE(r.reason.find("cannot be confirmed"), std::string::npos) << r.reason;  // no supervisor.info yet
  auto out = op.logic.take_outbox();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].port, port::kPlatform);  // protocol 0 (unknown) -> legacy platform request
  EXPECT_EQ(out[0].channel, 0);
  EXPECT_EQ(out[0].size, 2);
  EXPECT_EQ(out[0].data[0], 1);
  EXPECT_EQ(out[0].data[1], 1);
  op.logic.set_protocol_version(12);
  op.status(3.9, 0x0B);
  ASSERT_TRUE(op.logic.arm(false, op.t).accepted);
  out = op.logic.take_outbox();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].port, port::kSupervisor);
  EXPECT_EQ(out[0].channel, 1);
  EXPECT_EQ(out[0].data[0], 1);
  EXPECT_EQ(out[0].data[1], 0);
  op.to(Mode::kHovering);
  r = op.logic.arm(false, op.t);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("airborne"), std::string::npos) << r.reason;
}

TEST(BridgeOperator, StatusAndTransitionHistory) {
  Op op;
  auto st = op.logic.status(0);
  EXPECT_TRUE(std::isnan(st.battery_v));
  EXPECT_EQ(st.supervisor_info, -1);
  EXPECT_EQ(st.pm_state, -1);
  EXPECT_TRUE(std::isnan(st.log_age_s));
  EXPECT_TRUE(std::isnan(st.setpoint_age_s));
  op.to(Mode::kHovering);
  op.status(3.87, 0x1B);
  st = op.logic.status(op.t + 100 * kMs);
  EXPECT_EQ(st.mode, Mode::kHovering);
  EXPECT_DOUBLE_EQ(st.battery_v, 3.87);
  EXPECT_EQ(st.supervisor_info, 0x1B);
  EXPECT_TRUE(st.armed);
  EXPECT_NEAR(st.log_age_s, 0.1, 1e-9);
  EXPECT_EQ(op.logic.stats().status_samples, 1u);
  const auto& h = op.logic.history();
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].from, Mode::kGrounded);
  EXPECT_EQ(h[0].to, Mode::kTakingOff);
  EXPECT_EQ(h[0].guard, "takeoff");
  EXPECT_EQ(h[0].reason, "takeoff to 0.40 m in 1.00 s");
  EXPECT_EQ(h[1].guard, "takeoff_done");
  EXPECT_EQ(op.logic.stats().transitions_total, 2u);
}

TEST(BridgeOperator, AutostartOnlyFromGroundedAndOnlyWhenSet) {
  Rig r;  // autostart: true
  r.tick(true, true);
  EXPECT_EQ(r.logic.mode(), Mode::kForward);
  EXPECT_EQ(r.logic.history().front().guard, "autostart");
  // After the landing it does not restart by itself.
  auto land = hover(0, 0, 0, 0);
  land.land = true;
  r.tick(true, true, 0.4, land);
  for (int i = 0; i < 100; ++i) r.tick(true, true, 0.0);
  EXPECT_EQ(r.logic.mode(), Mode::kStopped);
}

TEST(BridgeOperator, NewParametersValidated) {
  const auto m = CrazyflieBridgeLogic::default_parameters();
  auto expect_bad = [&](const char* key, tactile_common::ParamValue v, const char* what) {
    auto bad = m;
    bad.set(key, v);
    try {
      CrazyflieBridgeLogic::params_from(bad);
      ADD_FAILURE() << key;
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_bad("takeoff_height", 2.0, "takeoff_height");
  expect_bad("takeoff_duration_s", 0.1, "max_vertical_speed");
  expect_bad("land_duration_s", 0.0, "land_duration_s");
  expect_bad("low_battery_v", 7.0, "low_battery_v");
  expect_bad("shutdown_land_timeout_s", 1.0, "shutdown_land_timeout_s");
  expect_bad("status_vars", std::vector<std::string>{"a", "b", "c", "d", "e", "f", "g"}, "status_vars");
  expect_bad("status_period_ms", int64_t{5}, "status_period_ms");
  const auto p = CrazyflieBridgeLogic::params_from(m);
  EXPECT_FALSE(p.autostart);
}
