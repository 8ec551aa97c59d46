// Health of a whisker driver on the bench rig (ROS-free): one diagnostics check per
// driver, evaluated once per diagnostics period from WhiskerDriverLogic::stats() and the
// age of the newest published sample. The rclcpp component publishes it on /diagnostics
// through diagnostic_updater where the ROS 2 installation has it.
//
//   device gone  source errors (disconnect, failed reopen) in the period and no sample for
//                stall_error_s: ERROR (SerialSource retries the device once per second)
//   stall        no sample for stall_error_s: ERROR; for stall_warn_s: WARN
//   frame errors lines / frames dropped by the parser in the period, as a fraction of the
//                lines received: above frame_error_error ERROR, above frame_error_warn WARN
//   else OK
// Parameters: config/whisker_driver_health.yaml (a file of its own: the standalone host
// reads config/whisker_driver.yaml and publishes no diagnostics).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tactile_common/parameters.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"

namespace whisker_driver {

class DriverHealth {
 public:
  static constexpr const char* kNodeName = "whisker_driver";

  struct Params {
    double diagnostics_period_s = 1.0;  ///< [s] (diagnostic_updater's default)
    double stall_warn_s = 0.1;          ///< [s] 5 frames of the deck's 50 Hz (000 Methods)
    double stall_error_s = 1.0;         ///< [s] SerialSource's reopen interval
    double frame_error_warn = 0.01;     ///< dropped / received lines in a period (choice)
    double frame_error_error = 0.1;     ///< (choice)
    void validate() const;
  };

  enum class Level : uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };  ///< diagnostic_msgs values

  struct Check {
    Level level = Level::kOk;
    std::string message;
    std::vector<std::pair<std::string, std::string>> values;
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit DriverHealth(const Params& params);
  /// One diagnostics period: `stats` now (counters since start; the period's share is the
  /// difference to the previous call) and the age of the newest published sample [s].
  Check update(const WhiskerDriverLogic::Stats& stats, double sample_age_s);
  const Params& params() const { return params_; }

 private:
  Params params_;
  WhiskerDriverLogic::Stats last_{};
};

}  // namespace whisker_driver
