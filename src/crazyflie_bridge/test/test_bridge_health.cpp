// BridgeHealth: the status message and the diagnostics thresholds of the bridge's ROS face
// (ROS-free; the rclcpp component only copies the checks into diagnostic_updater).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "crazyflie_bridge/bridge_health.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/parameters.hpp"

namespace crazyflie_bridge {
namespace {

using Level = BridgeHealth::Level;
using Mode = CrazyflieBridgeLogic::Mode;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

CrazyflieBridgeLogic::Status healthy() {
  CrazyflieBridgeLogic::Status s{};
  s.mode = Mode::kForward;
  s.armed = true;
  s.emergency_latched = false;
  s.battery_v = 3.9;
  s.pm_state = 0;
  s.supervisor_info = 2 | 8 | 16;
  s.rssi_dbm = 45;  // radio.rssi: -dBm as a positive number
  s.link_quality = 1.0;
  s.packets_lost = 0;
  s.log_blocks_missed = 0;
  s.setpoint_age_s = 0.01;
  s.log_age_s = 0.01;
  s.low_battery_events = 0;
  return s;
}

const BridgeHealth::Check& check(const std::vector<BridgeHealth::Check>& checks, const std::string& name) {
  for (const auto& c : checks) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no check " + name);
}

std::string value(const BridgeHealth::Check& c, const std::string& key) {
  for (const auto& [k, v] : c.values) {
    if (k == key) return v;
  }
  return "<missing>";
}

TEST(BridgeHealth, HealthyFlightIsOkEverywhere) {
  const auto checks = BridgeHealth::evaluate(BridgeHealth::Params{}, healthy());
  ASSERT_EQ(checks.size(), 4u);
  EXPECT_EQ(checks[0].name, "battery");
  EXPECT_EQ(checks[1].name, "link");
  EXPECT_EQ(checks[2].name, "log stream");
  EXPECT_EQ(checks[3].name, "flight");
  for (const auto& c : checks) EXPECT_EQ(c.level, Level::kOk) << c.name << ": " << c.message;
  EXPECT_EQ(value(check(checks, "flight"), "mode"), "forward");
  EXPECT_EQ(value(check(checks, "link"), "rssi"), "45");
  EXPECT_EQ(value(check(checks, "battery"), "battery_voltage"), "3.900");
}

TEST(BridgeHealth, BatteryThresholdsFromTheFirmware) {
  const BridgeHealth::Params p;  // 3.2 V low, 3.0 V critical (crazyflie-firmware pm.h)
  auto s = healthy();
  s.battery_v = 3.21;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "battery").level, Level::kOk);
  s.battery_v = 3.19;
  const auto warn = check(BridgeHealth::evaluate(p, s), "battery");
  EXPECT_EQ(warn.level, Level::kWarn);
  EXPECT_NE(warn.message.find("battery low: 3.19 V < battery_warn_v 3.20 V"), std::string::npos) << warn.message;
  s.battery_v = 2.99;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "battery").level, Level::kError);
  s.battery_v = kNaN;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "battery").level, Level::kStale);
}

TEST(BridgeHealth, LinkQualityThresholds) {
  BridgeHealth::Params p;
  p.link_quality_warn = 0.9;
  p.link_quality_error = 0.7;
  auto s = healthy();
  s.link_quality = 0.85;
  s.packets_lost = 12;
  const auto warn = check(BridgeHealth::evaluate(p, s), "link");
  EXPECT_EQ(warn.level, Level::kWarn);
  EXPECT_EQ(value(warn, "packets_lost"), "12");
  s.link_quality = 0.5;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "link").level, Level::kError);
  s.link_quality = kNaN;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "link").level, Level::kStale);
}

TEST(BridgeHealth, StaleLogThresholds) {
  const BridgeHealth::Params p;  // 0.1 s WARN, 0.2 s ERROR
  auto s = healthy();
  s.log_age_s = 0.15;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "log stream").level, Level::kWarn);
  s.log_age_s = 0.25;
  s.log_blocks_missed = 7;
  const auto err = check(BridgeHealth::evaluate(p, s), "log stream");
  EXPECT_EQ(err.level, Level::kError);
  EXPECT_NE(err.message.find("log data stale: 0.250 s > log_age_error_s 0.200 s"), std::string::npos) << err.message;
  EXPECT_EQ(value(err, "log_blocks_missed"), "7");
  s.log_age_s = kNaN;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "log stream").level, Level::kStale);
}

TEST(BridgeHealth, FlightLevels) {
  const BridgeHealth::Params p;
  auto s = healthy();
  s.mode = Mode::kEmergency;
  s.emergency_latched = true;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "flight").level, Level::kError);
  s = healthy();
  s.mode = Mode::kHoverHold;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "flight").level, Level::kWarn);
  s = healthy();
  s.mode = Mode::kStopped;
  s.low_battery_events = 1;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "flight").level, Level::kWarn);
  s.low_battery_events = 0;
  s.mode = Mode::kGrounded;
  EXPECT_EQ(check(BridgeHealth::evaluate(p, s), "flight").level, Level::kOk);
}

TEST(BridgeHealth, StatusMessageCarriesEveryField) {
  auto s = healthy();
  s.mode = Mode::kHovering;
  s.packets_lost = 3;
  s.log_blocks_missed = 4;
  s.low_battery_events = 1;
  s.pm_state = -1;
  s.supervisor_info = -1;
  const auto m = BridgeHealth::to_msg(s, 12'345'678'901LL);
  EXPECT_EQ(m.header.stamp.sec, 12);
  EXPECT_EQ(m.header.stamp.nanosec, 345'678'901u);
  EXPECT_EQ(m.mode, tactile_msgs::msg::BridgeStatus::MODE_HOVERING);
  EXPECT_EQ(m.mode_name, "hovering");
  EXPECT_TRUE(m.armed);
  EXPECT_FALSE(m.emergency_latched);
  EXPECT_FLOAT_EQ(m.battery_voltage, 3.9f);
  EXPECT_EQ(m.pm_state, -1);
  EXPECT_EQ(m.supervisor_info, -1);
  EXPECT_EQ(m.rssi, 45);
  EXPECT_FLOAT_EQ(m.link_quality, 1.0f);
  EXPECT_EQ(m.packets_lost, 3u);
  EXPECT_EQ(m.log_blocks_missed, 4u);
  EXPECT_FLOAT_EQ(m.setpoint_age_s, 0.01f);
  EXPECT_FLOAT_EQ(m.log_age_s, 0.01f);
  EXPECT_EQ(m.low_battery_events, 1u);
  s.battery_v = kNaN;
  EXPECT_TRUE(std::isnan(BridgeHealth::to_msg(s, 0).battery_voltage));
}

TEST(BridgeHealth, ModeCodesAreTheMessageConstants) {
  using B = tactile_msgs::msg::BridgeStatus;
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kGrounded), B::MODE_GROUNDED);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kTakingOff), B::MODE_TAKING_OFF);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kHovering), B::MODE_HOVERING);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kGoTo), B::MODE_GO_TO);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kForward), B::MODE_FORWARD);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kHoverHold), B::MODE_HOVER_HOLD);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kLanding), B::MODE_LANDING);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kStopped), B::MODE_STOPPED);
  EXPECT_EQ(BridgeHealth::mode_code(Mode::kEmergency), B::MODE_EMERGENCY);
}

TEST(BridgeHealth, ParametersValidatedWithTheirNames) {
  auto m = BridgeHealth::default_parameters();
  m.set("battery_error_v", 3.5);  // above battery_warn_v 3.2
  try {
    BridgeHealth::params_from(m);
    FAIL() << "battery_error_v above battery_warn_v accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("battery_error_v (3.500000) must be below battery_warn_v"), std::string::npos)
        << e.what();
  }
  m = BridgeHealth::default_parameters();
  m.set("link_quality_warn", 1.5);
  EXPECT_THROW(BridgeHealth::params_from(m), tactile_common::ParamError);
  m = BridgeHealth::default_parameters();
  m.set("status_rate_hz", 0.0);
  EXPECT_THROW(BridgeHealth::params_from(m), tactile_common::ParamError);
  m = BridgeHealth::default_parameters();
  m.set("log_age_error_s", 0.05);  // below log_age_warn_s
  EXPECT_THROW(BridgeHealth::params_from(m), tactile_common::ParamError);
}

TEST(BridgeHealth, RepositoryConfigIsTheDefaults) {
  const auto loaded = tactile_common::load_node_parameters(TACTILE_CONFIG_DIR "/crazyflie_bridge_health.yaml",
                                                           BridgeHealth::kNodeName, BridgeHealth::default_parameters());
  const auto p = BridgeHealth::params_from(loaded);
  const BridgeHealth::Params d;
  EXPECT_EQ(p.status_rate_hz, d.status_rate_hz);
  EXPECT_EQ(p.diagnostics_period_s, d.diagnostics_period_s);
  EXPECT_EQ(p.battery_warn_v, d.battery_warn_v);
  EXPECT_EQ(p.battery_error_v, d.battery_error_v);
  EXPECT_EQ(p.link_quality_warn, d.link_quality_warn);
  EXPECT_EQ(p.link_quality_error, d.link_quality_error);
  EXPECT_EQ(p.log_age_warn_s, d.log_age_warn_s);
  EXPECT_EQ(p.log_age_error_s, d.log_age_error_s);
}

// The parameter spec: every key described, no described range wider than validate()'s,
// the six thresholds live and the two rates read at start.
TEST(BridgeHealth, EveryParameterIsDescribedAndTheThresholdsAreLive) {
  const tactile_common::ParamMap d = BridgeHealth::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { BridgeHealth::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  std::vector<std::string> live;
  for (const auto& [key, info] : d.infos()) {
    if (info.live) live.push_back(key);
  }
  EXPECT_EQ(live, (std::vector<std::string>{"battery_error_v", "battery_warn_v", "link_quality_error",
                                            "link_quality_warn", "log_age_error_s", "log_age_warn_s"}));
}

// A new threshold changes the next evaluation; a rate change or an invalid order is refused.
TEST(BridgeHealth, LiveUpdateAppliesThresholdsAndRefusesRatesAndInvalidValues) {
  const BridgeHealth::Params current;
  BridgeHealth::Params next = current;
  next.battery_warn_v = 4.0;  // 3.9 V is now low
  const auto applied = BridgeHealth::live_update(current, next);
  EXPECT_EQ(check(BridgeHealth::evaluate(applied, healthy()), "battery").level, Level::kWarn);
  EXPECT_EQ(check(BridgeHealth::evaluate(current, healthy()), "battery").level, Level::kOk);
  next = current;
  next.status_rate_hz = 10.0;
  EXPECT_THROW(BridgeHealth::live_update(current, next), std::invalid_argument);
  next = current;
  next.battery_error_v = 3.5;  // above battery_warn_v 3.2
  EXPECT_THROW(BridgeHealth::live_update(current, next), std::invalid_argument);
}

}  // namespace
}  // namespace crazyflie_bridge
