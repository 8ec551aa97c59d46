// Node logic of the Crazyflie bridge (no I/O, no rclcpp): decoded log samples
// in -> WhiskerPressure (left/right) and Odometry out; HoverSetpoint in ->
// CRTP generic-commander packets out on a fixed-rate timer, clamped to the
// configured limits, with the safety chain
//   fresh setpoints and log data -> forward the (clamped) setpoint
//   setpoints stale or no log data -> hover in place (vx = vy = yaw rate = 0, last height)
//   still stale after hover_hold_s -> land (height ramps down at land_speed)
//   below land_height -> stop (motors off, sent 5 times), then nothing: the firmware's
//   commander watchdog (500 ms level, 2 s motors off) is the last line when
//   the ground station itself dies.
// Landing is latched: fresh setpoints do not resume flight once it began.
// Packets are encoded for the connected firmware generation as cflib does
// (commander::for_protocol: hover type 10, or legacy type 5 with the negated
// yaw rate for protocol <= 8). Message sequence numbers and stamps come from
// the firmware's log timestamps (LogClock: a lost log packet is a gap);
// odometry carries the full attitude, body rates and covariances from a
// second log block (AttitudeBlock). README: "Firmware generations",
// "Odometry", "Sequence numbers and stamps".
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "crazyflie_bridge/attitude_block.hpp"
#include "crazyflie_bridge/client.hpp"
#include "crazyflie_bridge/crtp.hpp"
#include "crazyflie_bridge/log_clock.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"

namespace crazyflie_bridge {

class CrazyflieBridgeLogic {
 public:
  static constexpr const char* kNodeName = "crazyflie_bridge";
  static constexpr const char* kLeftPressureTopic = "/whisker/left/pressure";    // tactile_msgs/msg/WhiskerPressure
  static constexpr const char* kRightPressureTopic = "/whisker/right/pressure";  // tactile_msgs/msg/WhiskerPressure
  static constexpr const char* kOdomTopic = "/odom";                             // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "/cmd_hover";                    // tactile_msgs/msg/HoverSetpoint

  struct Params {
    std::string uri = "radio://0/80/2M/E7E7E7E7E7?safelink=1";
    /// Whisker deck log variables (public deck driver names); 000: three
    /// barometers per whisker sampled at 50 Hz.
    std::vector<std::string> left_pressure_vars{"Whisker.Barometer1_1", "Whisker.Barometer1_2", "Whisker.Barometer1_3"};
    std::vector<std::string> right_pressure_vars{"Whisker1.Barometer2_1", "Whisker1.Barometer2_2",
                                                 "Whisker1.Barometer2_3"};
    double pressure_scale = 1.0;  ///< log unit -> Pa
    /// x, y, z [m], yaw [deg], vx, vy [m/s, world] (firmware state estimate).
    std::vector<std::string> state_vars{"stateEstimate.x", "stateEstimate.y", "stateEstimate.z",
                                        "stateEstimate.yaw", "stateEstimate.vx", "stateEstimate.vy"};
    int64_t whisker_period_ms = 20;  ///< 000: 50 Hz
    /// 100 Hz: the rate of the state estimate the pipeline was tuned with (SITL
  /// /odom); at 50 Hz the darkness wall-following FSM reached its target in
  /// 6/10 seeded trials instead of 10/10 (crazyflie_bridge/README.md).
  int64_t state_period_ms = 10;
    double setpoint_rate_hz = 50.0;  ///< commander packets (firmware expects >= 2 Hz: 500 ms watchdog)
    double max_velocity = 0.5;       ///< |vx|, |vy| clamp [m/s]
    double max_yaw_rate = 1.0;       ///< [rad/s]
    double min_height = 0.0;         ///< [m]
    double max_height = 1.5;         ///< [m]
    double setpoint_timeout_s = 0.2; ///< no setpoint for this long = stale (10 FSM ticks at 50 Hz)
    double log_timeout_s = 0.2;      ///< no log data for this long = link degraded
    double hover_hold_s = 1.0;       ///< hover in place this long before landing
    double land_speed = 0.25;        ///< [m/s]
    double land_height = 0.05;       ///< stop the motors below this height [m]
    /// Odometry covariance diagonals where the firmware logs no variance
    /// (position: unless kalman.varX/Y/Z are in the log TOC; the others always:
    /// a log block has no room for them). Not measured: the order of
    /// magnitude of the Kalman estimator's with the flow deck, see README.
    double position_variance = 1e-3;          ///< [m^2]
    double orientation_variance = 1e-3;       ///< [rad^2] roll, pitch, yaw
    double linear_velocity_variance = 1e-3;   ///< [(m/s)^2]
    double angular_velocity_variance = 1e-4;  ///< [(rad/s)^2]
    void validate() const;
  };

  enum class Mode { kWaiting, kForward, kHoverHold, kLanding, kStopped };

  struct Stats {
    uint64_t log_samples = 0;
    uint64_t dropped_nonfinite = 0;      ///< samples with NaN/inf values
    uint64_t dropped_unknown_block = 0;  ///< samples of a layout this logic did not ask for
    uint64_t setpoints_in = 0;
    uint64_t dropped_setpoint_nonfinite = 0;
    uint64_t setpoints_clamped = 0;
    uint64_t stale_events = 0;           ///< transitions into hover hold
    uint64_t landings = 0;
    uint64_t packets_out = 0;
    // Link truth (LogClock, AttitudeBlock)
    uint64_t attitude_samples = 0;       ///< attitude block samples used
    uint64_t log_samples_missed = 0;     ///< gaps in the per-block sequences (lost log packets)
    uint64_t log_clock_restarts = 0;     ///< firmware time went back (restart): sequences re-based
    uint64_t odom_without_attitude = 0;  ///< state samples with no attitude sample < 2 periods away (not published)
    uint64_t dropped_attitude_invalid = 0;  ///< attitude samples out of range (not used)
  };

  struct LogOutputs {
    std::optional<tactile_msgs::msg::WhiskerPressure> left, right;
    std::optional<nav_msgs::msg::Odometry> odom;
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  explicit CrazyflieBridgeLogic(const Params& params);

  /// Log block layouts this logic consumes: whisker block, state block.
  std::vector<std::string> whisker_block() const;
  const std::vector<std::string>& state_block() const { return params_.state_vars; }
  /// Tells the logic which block ids carry which layout.
  void set_block_ids(uint8_t whisker_block_id, uint8_t state_block_id);
  /// Attitude block layout (AttitudeBlock): the compressed estimate, plus
  /// kalman.varX/Y/Z when `with_variances` (the firmware logs them).
  std::vector<std::string> attitude_block(bool with_variances) const;
  /// Its block id (same period as the state block). Once set, odometry is
  /// published only with an attitude sample less than two periods from the
  /// state sample's firmware time; without it (the logic used without a link, as in
  /// unit tests) odometry carries yaw only.
  void set_attitude_block_id(uint8_t attitude_block_id);
  /// CRTP protocol version of the connected Crazyflie: selects the setpoint
  /// generation (commander::for_protocol). Defaults to the current generation
  /// (type 10); BridgeRunner sets it from the client at connect.
  void set_protocol_version(uint8_t version) { protocol_version_ = version; }
  uint8_t protocol_version() const { return protocol_version_; }
  const LogClock& log_clock() const { return clock_; }

  LogOutputs on_log_sample(const LogSample& sample, int64_t now_ns);
  void on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns);
  /// At setpoint_rate_hz: the packet to send now (none once stopped).
  std::optional<CrtpPacket> on_timer(int64_t now_ns);

  Mode mode() const { return mode_; }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  /// The setpoint last sent (after clamping / safety), body-frame velocities.
  const tactile_msgs::msg::HoverSetpoint& last_command() const { return command_; }

 private:
  Params params_;
  Stats stats_;
  Mode mode_ = Mode::kWaiting;
  int whisker_block_ = -1, state_block_ = -1, attitude_block_ = -1;
  LogClock clock_;
  std::optional<AttitudeBlock::Sample> attitude_;
  uint8_t protocol_version_ = 10;  ///< the emulator's default (> kLastLegacyProtocol: hover type 10)
  bool have_setpoint_ = false, have_log_ = false;
  int64_t setpoint_ns_ = 0, log_ns_ = 0, hold_start_ns_ = 0, last_timer_ns_ = 0;
  double height_ = 0.0;  ///< estimated height (state block z)
  static constexpr int kStopRepeats = 5;
  int stops_sent_ = 0;
  tactile_msgs::msg::HoverSetpoint setpoint_, command_;
};

const char* to_string(CrazyflieBridgeLogic::Mode m);

}  // namespace crazyflie_bridge
