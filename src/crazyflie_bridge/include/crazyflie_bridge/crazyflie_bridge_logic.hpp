// Node logic of the Crazyflie bridge (no I/O, no rclcpp): decoded log samples
// in -> WhiskerPressure (left/right) and Odometry out; HoverSetpoint in ->
// CRTP generic-commander packets out on a fixed-rate timer, clamped to the
// configured limits; operator commands (arm, take-off, land, go-to, hand-over,
// hand-back, emergency stop) drive an explicit state machine:
//
//   kGrounded --takeoff--> kTakingOff --takeoff_done--> kHovering
//   kHovering --go_to--> kGoTo --goto_done--> kHovering
//   kHovering --start_behaviour--> kForward --notify_setpoints_stop--> kHovering
//   kForward --stale--> kHoverHold --fresh_again--> kForward
//                                  --hold_expired--> kLanding
//   any airborne --land / low_battery / behaviour_land--> kLanding --touchdown--> kStopped
//   any --emergency_stop--> kEmergency --arm(true) on the ground--> kGrounded
//   kGrounded --autostart (fresh setpoints and log)--> kForward   (autostart: true only)
//
// Nothing is sent to the motors in kGrounded. kStopped repeats the stop packet
// a few times, then sends nothing: the firmware's commander watchdog (500 ms
// level, 2 s motors off) is the last line when the ground station itself dies.
// kEmergency sends the stop packet every tick until arm(true) on the ground.
// Every transition is a named guard with a reason, counted in Stats and kept
// in history(). Every refused command returns accepted=false and the reason.
//
// Packets are encoded for the connected firmware generation as cflib does
// (commander::for_protocol: hover type 10, or legacy type 5 with the negated
// yaw rate for protocol <= 8). Message sequence numbers and stamps come from
// the firmware's log timestamps (LogClock: a lost log packet is a gap);
// odometry carries the full attitude, body rates and covariances from a
// second log block (AttitudeBlock). README: "Firmware generations",
// "Odometry", "Sequence numbers and stamps".
#pragma once

#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "crazyflie_bridge/attitude_block.hpp"
#include "crazyflie_bridge/client.hpp"
#include "crazyflie_bridge/crtp.hpp"
#include "crazyflie_bridge/log_clock.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/frames.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"

namespace crazyflie_bridge {

class CrazyflieBridgeLogic {
 public:
  static constexpr const char* kNodeName = "crazyflie_bridge";
  static constexpr const char* kLeftPressureTopic = "whisker/left/pressure";    // tactile_msgs/msg/WhiskerPressure
  static constexpr const char* kRightPressureTopic = "whisker/right/pressure";  // tactile_msgs/msg/WhiskerPressure
  static constexpr const char* kOdomTopic = "odom";                             // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "cmd_hover";                    // tactile_msgs/msg/HoverSetpoint

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
  /// 6/10 seeded trials instead of 10/10 (docs/crazyflie_bridge_results.md).
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
    /// Touchdown waits for the measured height (fresh log) to reach land_height once the
    /// commanded height has; a vehicle whose estimate stays above it (sitting on an
    /// object, a biased range sensor) is stopped after this long at the floor [s].
    /// 1 s: four times the lag of the measured height behind the 0.25 m/s ramp seen in
    /// the SITL (0.13 m, about 0.5 s); choice.
    double touchdown_timeout_s = 1.0;
    /// Odometry covariance diagonals where the firmware logs no variance
    /// (position: unless kalman.varX/Y/Z are in the log TOC; the others always:
    /// a log block has no room for them). Not measured: the order of
    /// magnitude of the Kalman estimator's with the flow deck, see README.
    double position_variance = 1e-3;          ///< [m^2]
    double orientation_variance = 1e-3;       ///< [rad^2] roll, pitch, yaw
    double linear_velocity_variance = 1e-3;   ///< [(m/s)^2]
    double angular_velocity_variance = 1e-4;  ///< [(rad/s)^2]
    /// Forward the behaviour as soon as setpoints and log are fresh, without an
    /// operator take-off (the old behaviour; lockstep SITL graphs and tests).
    bool autostart = false;
    double takeoff_height = 0.4;           ///< default take-off target [m] (tactile fly --takeoff)
    double takeoff_duration_s = 2.0;       ///< default take-off ramp [s]
    double land_duration_s = 3.0;          ///< default land ramp [s] (service default, shutdown land)
    /// Operator take-off / land ramps faster than this are refused [m/s].
    double max_vertical_speed = 1.0;
    /// Status log block (battery, supervisor, RSSI); variables a firmware TOC
    /// does not have are skipped with a warning.
    std::vector<std::string> status_vars{"pm.vbat", "pm.state", "supervisor.info", "radio.rssi"};
    int64_t status_period_ms = 100;        ///< status block period [ms]
    /// Below this battery voltage in flight for low_battery_hold_s -> land [V].
    /// 3.2 V: the firmware's own low level (pm_stm32f4.c PM_BAT_LOW_VOLTAGE,
    /// lowPower after PM_BAT_LOW_TIMEOUT 5 s); 0 disables the guard.
    double low_battery_v = 3.2;
    /// [s] rides through short sags under motor load; shorter than the
    /// firmware's 5 s so the bridge lands before the firmware's low-power state.
    double low_battery_hold_s = 2.0;
    double shutdown_land_timeout_s = 10.0; ///< bound of the blocking land on Ctrl-C / SIGTERM [s]
    /// Goes before every frame name the bridge stamps and broadcasts but map ("" or
    /// ending in '/': "cf1/" gives cf1/base_link; tactile_common/frames.hpp).
    std::string frame_prefix;
    /// Where the Crazyflie stands at take-off, in map [m] (x, y, z; a robots file's
    /// initial_position, as Crazyswarm2's crazyflies.yaml). The firmware's estimate starts
    /// at its own origin, so map -> odom is this translation: several Crazyflies in one
    /// map each show where they are. The estimate, odometry and go-to goals stay in odom.
    std::vector<double> initial_position{0.0, 0.0, 0.0};
    void validate() const;
  };

  /// Nothing is ever sent to the motors in kGrounded.
  enum class Mode { kGrounded, kTakingOff, kHovering, kGoTo, kForward, kHoverHold, kLanding, kStopped, kEmergency };

  struct CommandResult {
    bool accepted = false;
    std::string reason;  ///< why refused (or what was done)
  };

  /// One mode change: the guard that fired and why.
  struct Transition {
    int64_t t_ns = 0;
    Mode from = Mode::kGrounded, to = Mode::kGrounded;
    std::string guard;   ///< e.g. "takeoff", "stale", "low_battery"
    std::string reason;  ///< human-readable detail
  };
  static constexpr size_t kMaxHistory = 1000;  ///< history() keeps the first 1000 transitions

  /// Everything a ground station shows; NaN / -1 where unknown.
  struct Status {
    Mode mode = Mode::kGrounded;
    bool armed = false;             ///< supervisor.info is-armed bit, else the last arm() request
    bool emergency_latched = false;
    double battery_v = NAN;         ///< pm.vbat
    int pm_state = -1;              ///< pm.state (0 battery, 1 charging, 2 charged, 3 low power, 4 shutdown)
    int supervisor_info = -1;       ///< supervisor.info bit field (SupervisorBit)
    int rssi_dbm = -1;              ///< radio.rssi (firmware logs -dBm as a positive u8)
    double link_quality = NAN;      ///< ACK rate [0, 1] (BridgeRunner fills the link fields)
    uint64_t packets_lost = 0, log_blocks_missed = 0;
    double setpoint_age_s = NAN, log_age_s = NAN;
    uint64_t low_battery_events = 0;
  };

  /// supervisor.info bits: cflib crazyflie/supervisor.py BIT_CAN_BE_ARMED = 0
  /// .. BIT_IS_LOCKED = 6 (the firmware's supervisor bit field, also the
  /// supervisor.info log variable).
  enum SupervisorBit : int {
    kCanBeArmed = 1 << 0,
    kIsArmed = 1 << 1,
    kAutoArm = 1 << 2,
    kCanFly = 1 << 3,
    kIsFlying = 1 << 4,
    kIsTumbled = 1 << 5,
    kIsLocked = 1 << 6,
  };

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
    uint64_t low_battery_events = 0;     ///< landings for low battery
    uint64_t emergency_stops = 0;
    uint64_t commands_accepted = 0, commands_refused = 0;
    uint64_t status_samples = 0;
    uint64_t transitions_total = 0;
    std::map<std::string, uint64_t> transitions;  ///< "from->to:guard" -> count
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
  /// The status block's id and the variables it carries (the subset of
  /// status_vars the firmware's TOC has).
  void set_status_block(uint8_t block_id, std::vector<std::string> names);
  /// CRTP protocol version of the connected Crazyflie: selects the setpoint
  /// generation (commander::for_protocol) and the arming request's port (cflib
  /// Supervisor.send_arming_request: supervisor port from version 12). Defaults to
  /// the current generation (type 10); BridgeRunner sets it from the client at connect.
  void set_protocol_version(uint8_t version) { protocol_version_ = version; }
  uint8_t protocol_version() const { return protocol_version_; }
  const LogClock& log_clock() const { return clock_; }

  LogOutputs on_log_sample(const LogSample& sample, int64_t now_ns);
  void on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns);
  /// At setpoint_rate_hz: the packet to send now (none in kGrounded, none
  /// once stopped).
  std::optional<CrtpPacket> on_timer(int64_t now_ns);

  // Operator commands (operator surface). Each returns accepted and the reason.
  /// Arming request as cflib's Supervisor.send_arming_request sends it for the
  /// firmware's protocol version (queued in the outbox); arm(true) also clears
  /// the emergency latch, only on the ground. Refused while airborne.
  CommandResult arm(bool on, int64_t now_ns);
  /// Height ramps from the measured z to height_m over duration_s -> kHovering.
  CommandResult takeoff(double height_m, double duration_s, int64_t now_ns);
  /// From any airborne mode but kLanding: height ramps down to height_m
  /// (in [0, land_height]) over duration_s, then the motors stop.
  CommandResult land(double height_m, double duration_s, int64_t now_ns);
  /// From kHovering / kGoTo: position setpoints interpolated over duration_s.
  CommandResult go_to(double x, double y, double z, double yaw_rad, double duration_s, bool relative, int64_t now_ns);
  /// Hand-over: kHovering -> kForward.
  CommandResult start_behaviour(int64_t now_ns);
  /// Hand-back: kForward -> kHovering once the last setpoint's remain_valid_ms ran out.
  CommandResult notify_setpoints_stop(uint32_t remain_valid_ms, int64_t now_ns);
  /// Any mode -> kEmergency: stop packet now and every tick, latched until arm(true).
  CommandResult emergency_stop(int64_t now_ns);

  /// Packets to send now besides the timer's (arming requests, the immediate
  /// emergency stop); the caller sends them in order and the queue empties.
  std::vector<CrtpPacket> take_outbox();

  /// Logic fields of the status; link fields are NaN / 0 (BridgeRunner fills them).
  Status status(int64_t now_ns) const;
  bool airborne() const;  ///< kTakingOff .. kLanding
  const std::vector<Transition>& history() const { return history_; }

  Mode mode() const { return mode_; }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  /// Static transforms of the frame tree (prefixed): map -> odom (the translation
  /// initial_position: no behaviour of the radio graph owns a world map, and the firmware's
  /// estimate starts at its origin, where the Crazyflie stood)
  /// and base_link -> whisker_left/right, imu_link, flow, tof_down, from the whiskered
  /// Crazyflie's geometry (tactile_sim::robot_model(CrazyflieParams), 000's whiskers).
  std::vector<tactile_common::StaticFrame> static_frames() const;
  /// The URDF of the same links (robot_description).
  std::string robot_description() const;
  /// The setpoint last sent (after clamping / safety), body-frame velocities.
  const tactile_msgs::msg::HoverSetpoint& last_command() const { return command_; }

 private:
  Params params_;
  std::string odom_frame_, base_frame_, whisker_frame_[2];  ///< prefixed frame names
  Stats stats_;
  /// Sets mode_, counts the transition and records it (the only place mode_ changes).
  void transition(Mode to, const char* guard, std::string reason, int64_t now_ns);
  /// Entry actions of each mode, run by transition().
  void enter(Mode to, int64_t now_ns);
  CommandResult refuse(std::string reason);
  CommandResult accept(std::string reason);
  /// The one place a hover setpoint becomes a CRTP packet (vx, vy body frame
  /// [m/s], yaw rate [rad/s] CCW, height [m]).
  CrtpPacket hover_packet(double vx, double vy, double yaw_rate_rad, double height) const;
  LogOutputs on_status_sample(const LogSample& sample, int64_t now_ns);
  bool log_fresh(int64_t now_ns) const;
  bool setpoint_fresh(int64_t now_ns) const;
  /// Guard of arm(true) in kEmergency: fresh estimate at or below land_height and
  /// the supervisor (where logged) not reporting flight.
  bool on_the_ground(int64_t now_ns) const;
  /// Touchdown guard of kLanding (its reason, nullptr while still descending): the
  /// measured height at land_height (fresh log); or the commanded height at land_height
  /// with no fresh log (nothing better to go by); or touchdown_timeout_s at the floor.
  const char* touchdown(bool log_is_fresh, int64_t now_ns) const;
  /// Low-battery guard: true when the voltage has been below low_battery_v
  /// for low_battery_hold_s while airborne.
  bool low_battery(int64_t now_ns);

  Mode mode_ = Mode::kGrounded;
  std::vector<Transition> history_;
  std::deque<CrtpPacket> outbox_;
  int whisker_block_ = -1, state_block_ = -1, attitude_block_ = -1, status_block_ = -1;
  LogClock clock_;
  std::optional<AttitudeBlock::Sample> attitude_;
  std::vector<std::string> status_names_;
  double battery_v_ = NAN;
  int pm_state_ = -1, supervisor_info_ = -1, rssi_ = -1;
  bool arm_requested_ = false, emergency_latched_ = false;
  int64_t low_batt_since_ns_ = -1;
  // Ramps (take-off, land, go-to): from -> to over [start, start + duration].
  struct Ramp {
    double x0 = 0, y0 = 0, z0 = 0, yaw0 = 0, x1 = 0, y1 = 0, z1 = 0, yaw1 = 0;
    int64_t start_ns = 0;
    double duration_s = 0;
  } ramp_;
  bool ramp_done_ = false;  ///< the ramp's end point was sent (kTakingOff / kGoTo end on the next tick)
  double landing_speed_ = 0.0;   ///< kLanding descent [m/s]
  double landing_target_ = 0.0;  ///< kLanding floor of the commanded height [m]
  int64_t floor_since_ns_ = -1;  ///< kLanding: when the commanded height reached land_height
  double hold_height_ = 0.0;  ///< kHovering / kHoverHold height [m]
  double x_ = 0.0, y_ = 0.0, yaw_ = 0.0;  ///< state estimate [m, m, rad]
  uint8_t protocol_version_ = 10;  ///< the emulator's default (> kLastLegacyProtocol: hover type 10)
  int64_t handback_ns_ = -1;  ///< kForward -> kHovering at this time (notify_setpoints_stop)
  bool have_setpoint_ = false, have_log_ = false;
  int64_t setpoint_ns_ = 0, log_ns_ = 0, hold_start_ns_ = 0, last_timer_ns_ = 0;
  double height_ = 0.0;  ///< estimated height (state block z)
  static constexpr int kStopRepeats = 5;
  int stops_sent_ = 0;
  tactile_msgs::msg::HoverSetpoint setpoint_, command_;
};

const char* to_string(CrazyflieBridgeLogic::Mode m);

}  // namespace crazyflie_bridge
