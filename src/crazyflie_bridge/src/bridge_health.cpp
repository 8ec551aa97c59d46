#include "crazyflie_bridge/bridge_health.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "tactile_common/validation.hpp"

namespace crazyflie_bridge {

using tactile_common::ParamMap;

namespace {

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

constexpr const char* kType = "BridgeHealth";  // names the fields in validation errors

}  // namespace

void BridgeHealth::Params::validate() const {
  tactile_common::require_finite_positive(kType, "status_rate_hz", status_rate_hz);
  tactile_common::require_finite_positive(kType, "diagnostics_period_s", diagnostics_period_s);
  tactile_common::require_finite_positive(kType, "battery_warn_v", battery_warn_v);
  tactile_common::require_finite_positive(kType, "battery_error_v", battery_error_v);
  tactile_common::require_below(kType, "battery_error_v", battery_error_v, "battery_warn_v", battery_warn_v);
  tactile_common::require_finite_positive(kType, "link_quality_warn", link_quality_warn);
  tactile_common::require_finite_positive(kType, "link_quality_error", link_quality_error);
  if (link_quality_warn > 1.0) {
    throw std::invalid_argument("BridgeHealth.link_quality_warn: an ACK rate, must be <= 1, got " +
                                std::to_string(link_quality_warn));
  }
  tactile_common::require_below(kType, "link_quality_error", link_quality_error, "link_quality_warn", link_quality_warn);
  tactile_common::require_finite_positive(kType, "log_age_warn_s", log_age_warn_s);
  tactile_common::require_finite_positive(kType, "log_age_error_s", log_age_error_s);
  tactile_common::require_below(kType, "log_age_warn_s", log_age_warn_s, "log_age_error_s", log_age_error_s);
}

ParamMap BridgeHealth::default_parameters() {
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  const Params d;
  ParamMap m(kNodeName, "defaults");
  // The parameter spec of the health thresholds (README "Parameters"): value, description,
  // unit, the range validate() accepts (the warn/error order is checked there), and live:
  // the six thresholds are compared per evaluation, so they apply while running; the two
  // rates set up timers at start.
  m.set("status_rate_hz", d.status_rate_hz, {"rate of the `status` topic", "Hz", positive(), false, choice()});
  m.set("diagnostics_period_s", d.diagnostics_period_s,
        {"/diagnostics period (diagnostic_updater's default 1 s)", "s", positive(), false,
         choice("diagnostic_updater's default")});
  m.set("battery_warn_v", d.battery_warn_v,
        {"battery WARN below this (crazyflie-firmware pm.h PM_BAT_LOW_VOLTAGE 3.2 V); above battery_error_v", "V",
         positive(), true, choice("crazyflie-firmware pm.h PM_BAT_LOW_VOLTAGE 3.2 V")});
  m.set("battery_error_v", d.battery_error_v,
        {"battery ERROR below this (crazyflie-firmware pm.h PM_BAT_CRITICAL_LOW_VOLTAGE 3.0 V)", "V", positive(),
         true, choice("crazyflie-firmware pm.h PM_BAT_CRITICAL_LOW_VOLTAGE 3.0 V")});
  m.set("link_quality_warn", d.link_quality_warn,
        {"link WARN below this ACK rate (our choice, README)", "", ParamRange{0.0, 1.0, true, false}, true, choice()});
  m.set("link_quality_error", d.link_quality_error,
        {"link ERROR below this ACK rate; below link_quality_warn", "", positive(), true, choice()});
  m.set("log_age_warn_s", d.log_age_warn_s,
        {"log stream WARN when the newest log packet is older (5 log periods); below log_age_error_s", "s",
         positive(), true, choice("5 log periods")});
  m.set("log_age_error_s", d.log_age_error_s,
        {"log stream ERROR when it is older (the bridge's log_timeout_s default, where it holds hover)", "s",
         positive(), true, choice("the bridge's log_timeout_s")});
  return m;
}

BridgeHealth::Params BridgeHealth::live_update(const Params& current, const Params& next) {
  next.validate();
  if (next.status_rate_hz != current.status_rate_hz || next.diagnostics_period_s != current.diagnostics_period_s) {
    throw std::invalid_argument("BridgeHealth.live_update: status_rate_hz and diagnostics_period_s are read at start");
  }
  return next;
}

BridgeHealth::Params BridgeHealth::params_from(const ParamMap& m) {
  Params p;
  p.status_rate_hz = m.get_double("status_rate_hz");
  p.diagnostics_period_s = m.get_double("diagnostics_period_s");
  p.battery_warn_v = m.get_double("battery_warn_v");
  p.battery_error_v = m.get_double("battery_error_v");
  p.link_quality_warn = m.get_double("link_quality_warn");
  p.link_quality_error = m.get_double("link_quality_error");
  p.log_age_warn_s = m.get_double("log_age_warn_s");
  p.log_age_error_s = m.get_double("log_age_error_s");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw tactile_common::ParamError(m.source() + ": " + kNodeName + ": " + e.what());
  }
  return p;
}

std::vector<BridgeHealth::Check> BridgeHealth::evaluate(const Params& p, const CrazyflieBridgeLogic::Status& s) {
  std::vector<Check> out;
  {
    Check c{"battery", Level::kOk, "", {}};
    if (!std::isfinite(s.battery_v)) {
      c.level = Level::kStale;
      c.message = "battery voltage not known yet (no status log data)";
    } else if (s.battery_v < p.battery_error_v) {
      c.level = Level::kError;
      c.message = "battery critical: " + fmt("%.2f", s.battery_v) + " V < battery_error_v " + fmt("%.2f", p.battery_error_v) + " V";
    } else if (s.battery_v < p.battery_warn_v) {
      c.level = Level::kWarn;
      c.message = "battery low: " + fmt("%.2f", s.battery_v) + " V < battery_warn_v " + fmt("%.2f", p.battery_warn_v) + " V";
    } else {
      c.message = "battery " + fmt("%.2f", s.battery_v) + " V";
    }
    c.values = {{"battery_voltage", fmt("%.3f", s.battery_v)},
                {"pm_state", std::to_string(s.pm_state)},
                {"low_battery_events", std::to_string(s.low_battery_events)}};
    out.push_back(std::move(c));
  }
  {
    Check c{"link", Level::kOk, "", {}};
    if (!std::isfinite(s.link_quality)) {
      c.level = Level::kStale;
      c.message = "no ACK statistics (UDP and USB links have no ACKs)";
    } else if (s.link_quality < p.link_quality_error) {
      c.level = Level::kError;
      c.message = "link quality " + fmt("%.2f", s.link_quality) + " < link_quality_error " + fmt("%.2f", p.link_quality_error);
    } else if (s.link_quality < p.link_quality_warn) {
      c.level = Level::kWarn;
      c.message = "link quality " + fmt("%.2f", s.link_quality) + " < link_quality_warn " + fmt("%.2f", p.link_quality_warn);
    } else {
      c.message = "link quality " + fmt("%.2f", s.link_quality);
    }
    c.values = {{"link_quality", fmt("%.3f", s.link_quality)},
                {"rssi", std::to_string(s.rssi_dbm)},
                {"packets_lost", std::to_string(s.packets_lost)}};
    out.push_back(std::move(c));
  }
  {
    Check c{"log stream", Level::kOk, "", {}};
    if (!std::isfinite(s.log_age_s)) {
      c.level = Level::kStale;
      c.message = "no log data received yet";
    } else if (s.log_age_s > p.log_age_error_s) {
      c.level = Level::kError;
      c.message = "log data stale: " + fmt("%.3f", s.log_age_s) + " s > log_age_error_s " + fmt("%.3f", p.log_age_error_s) + " s";
    } else if (s.log_age_s > p.log_age_warn_s) {
      c.level = Level::kWarn;
      c.message = "log data late: " + fmt("%.3f", s.log_age_s) + " s > log_age_warn_s " + fmt("%.3f", p.log_age_warn_s) + " s";
    } else {
      c.message = "log data fresh";
    }
    c.values = {{"log_age_s", fmt("%.3f", s.log_age_s)},
                {"log_blocks_missed", std::to_string(s.log_blocks_missed)},
                {"setpoint_age_s", fmt("%.3f", s.setpoint_age_s)}};
    out.push_back(std::move(c));
  }
  {
    Check c{"flight", Level::kOk, std::string("mode ") + to_string(s.mode), {}};
    if (s.emergency_latched || s.mode == CrazyflieBridgeLogic::Mode::kEmergency) {
      c.level = Level::kError;
      c.message = "emergency stop latched: motors off until arm";
    } else if (s.mode == CrazyflieBridgeLogic::Mode::kHoverHold) {
      c.level = Level::kWarn;
      c.message = "hover hold: behaviour setpoints or log data stale";
    } else if (s.low_battery_events > 0) {
      c.level = Level::kWarn;
      c.message += " (after " + std::to_string(s.low_battery_events) + " low-battery landing(s))";
    }
    c.values = {{"mode", to_string(s.mode)},
                {"armed", s.armed ? "true" : "false"},
                {"emergency_latched", s.emergency_latched ? "true" : "false"},
                {"supervisor_info", std::to_string(s.supervisor_info)}};
    out.push_back(std::move(c));
  }
  return out;
}

uint8_t BridgeHealth::mode_code(CrazyflieBridgeLogic::Mode mode) {
  using M = CrazyflieBridgeLogic::Mode;
  using B = tactile_msgs::msg::BridgeStatus;
  switch (mode) {
    case M::kGrounded: return B::MODE_GROUNDED;
    case M::kTakingOff: return B::MODE_TAKING_OFF;
    case M::kHovering: return B::MODE_HOVERING;
    case M::kGoTo: return B::MODE_GO_TO;
    case M::kForward: return B::MODE_FORWARD;
    case M::kHoverHold: return B::MODE_HOVER_HOLD;
    case M::kLanding: return B::MODE_LANDING;
    case M::kStopped: return B::MODE_STOPPED;
    case M::kEmergency: return B::MODE_EMERGENCY;
  }
  throw std::logic_error("BridgeHealth::mode_code: unknown mode " + std::to_string(static_cast<int>(mode)));
}

tactile_msgs::msg::BridgeStatus BridgeHealth::to_msg(const CrazyflieBridgeLogic::Status& s, int64_t stamp_ns) {
  tactile_msgs::msg::BridgeStatus m;
  m.header.stamp.sec = static_cast<int32_t>(stamp_ns / 1000000000);
  m.header.stamp.nanosec = static_cast<uint32_t>(stamp_ns % 1000000000);
  m.mode = mode_code(s.mode);
  m.mode_name = to_string(s.mode);
  m.armed = s.armed;
  m.emergency_latched = s.emergency_latched;
  m.battery_voltage = static_cast<float>(s.battery_v);
  m.pm_state = static_cast<int8_t>(s.pm_state);
  m.supervisor_info = static_cast<int32_t>(s.supervisor_info);
  m.rssi = static_cast<int16_t>(s.rssi_dbm);
  m.link_quality = static_cast<float>(s.link_quality);
  m.packets_lost = s.packets_lost;
  m.log_blocks_missed = s.log_blocks_missed;
  m.setpoint_age_s = static_cast<float>(s.setpoint_age_s);
  m.log_age_s = static_cast<float>(s.log_age_s);
  m.low_battery_events = s.low_battery_events;
  return m;
}

const char* to_string(BridgeHealth::Level level) {
  switch (level) {
    case BridgeHealth::Level::kOk: return "OK";
    case BridgeHealth::Level::kWarn: return "WARN";
    case BridgeHealth::Level::kError: return "ERROR";
    case BridgeHealth::Level::kStale: return "STALE";
  }
  return "?";
}

}  // namespace crazyflie_bridge
