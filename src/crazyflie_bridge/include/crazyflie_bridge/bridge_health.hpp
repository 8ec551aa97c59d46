// Ground-station health of the bridge (ROS-free): thresholds from
// config/crazyflie_bridge_health.yaml applied to BridgeRunner::status(), giving the checks
// the rclcpp component publishes on /diagnostics (diagnostic_msgs/DiagnosticArray through
// diagnostic_updater) and the tactile_msgs/BridgeStatus of its `status` topic.
//
//   battery    battery_voltage < battery_error_v: ERROR, < battery_warn_v: WARN, unknown: STALE
//   link       link_quality (ACK rate) < link_quality_error: ERROR, < link_quality_warn: WARN,
//              unknown: STALE
//   log stream log_age_s > log_age_error_s: ERROR, > log_age_warn_s: WARN, none yet: STALE
//   flight     emergency latched: ERROR; hover hold (stale inputs) or a low-battery landing
//              so far: WARN; else OK with the mode
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_msgs/msg/bridge_status.hpp"

namespace crazyflie_bridge {

class BridgeHealth {
 public:
  /// The same node as CrazyflieBridgeLogic: its parameters live beside the logic's, in a
  /// file of their own (the standalone host, which has no /diagnostics, reads only
  /// config/crazyflie_bridge.yaml).
  static constexpr const char* kNodeName = "crazyflie_bridge";
  static constexpr const char* kStatusTopic = "status";  ///< relative: tactile_msgs/msg/BridgeStatus

  struct Params {
    double status_rate_hz = 5.0;        ///< `status` topic rate [Hz]
    double diagnostics_period_s = 1.0;  ///< /diagnostics period [s] (diagnostic_updater's default)
    /// Crazyflie 2.x 1S LiPo: crazyflie-firmware src/hal/interface/pm.h PM_BAT_LOW_VOLTAGE
    /// 3.2 V (the firmware's own low-battery state) and PM_BAT_CRITICAL_LOW_VOLTAGE 3.0 V.
    double battery_warn_v = 3.2;   ///< [V]
    double battery_error_v = 3.0;  ///< [V]
    /// ACK rate of the radio link (choices: the bridge flew the SITL with 30 % loss both
    /// ways, README; below 0.7 a pipeline tuned for a complete 50 Hz stream degrades).
    double link_quality_warn = 0.9;
    double link_quality_error = 0.7;
    /// Age of the newest log packet (log blocks every 10-20 ms): WARN after 5 periods,
    /// ERROR at the bridge's own log_timeout_s default (0.2 s), where it holds hover.
    double log_age_warn_s = 0.1;   ///< [s]
    double log_age_error_s = 0.2;  ///< [s]
    void validate() const;
  };

  enum class Level : uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };  ///< diagnostic_msgs values

  struct Check {
    std::string name;  ///< "battery", "link", "log stream", "flight"
    Level level = Level::kOk;
    std::string message;
    std::vector<std::pair<std::string, std::string>> values;  ///< key-value details
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  /// The thresholds while running (`ros2 param set`): `next` if it validates and only the
  /// live keys of default_parameters() differ from `current` (the six thresholds; the two
  /// rates drive timers made at start); std::invalid_argument otherwise.
  static Params live_update(const Params& current, const Params& next);

  /// The four checks, in the order above.
  static std::vector<Check> evaluate(const Params& params, const CrazyflieBridgeLogic::Status& status);
  /// The `status` message (header stamp from `stamp_ns`, frame_id empty).
  static tactile_msgs::msg::BridgeStatus to_msg(const CrazyflieBridgeLogic::Status& status, int64_t stamp_ns);
  /// BridgeStatus::MODE_* of a mode.
  static uint8_t mode_code(CrazyflieBridgeLogic::Mode mode);
};

const char* to_string(BridgeHealth::Level level);

}  // namespace crazyflie_bridge
