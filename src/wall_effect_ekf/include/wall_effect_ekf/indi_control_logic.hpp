// Node logic of the INDI controller of the ducted quadrotor (paper 004
// eq. 26-36): position setpoint, odometry (motion capture or GPS), IMU and
// the wall estimate in, the four rotor thrust commands out. Outer loop
// (eq. 26, 30-34) at outer_rate_hz, inner loop (eq. 35-36) at rate_hz.
//
// Setpoint (nav_msgs/Odometry on kSetpointTopic, world frame): pose.position
// is p_d, the yaw of pose.orientation is psi_d, twist.linear is p_dot_d
// (world frame). A NaN position component makes that axis velocity-only
// (004: a pilot's direction with K_p = K_i = 0).
//
// Fail-safe (README "INDI fail-safe"): the node never goes silent once it flies, so the
// vehicle never keeps a stale thrust command (a simulator or an ESC holds the last one).
//   WAITING_FOR_INPUT -> NOMINAL          inputs_ready: odometry and IMU both fresh
//   NOMINAL -> MOTORS_STOPPED             imu_lost: no attitude, flight terminated
//   NOMINAL -> ODOMETRY_LOST              odometry_lost: odometry stale, IMU fresh
//   ODOMETRY_LOST -> MOTORS_STOPPED       imu_lost, touchdown (for touchdown_confirm_s)
//                                         or descent_timed_out
// Inside ODOMETRY_LOST, below_floor starts a floor probe (no transition): the collective
// thrust ramps down; touchdown then stops the motors on the floor, airborne_in_probe aborts
// it in the air (the descent goes on, the floor bound off for the rest of it).
// WAITING_FOR_INPUT sends nothing (on the ground, motors idle); ODOMETRY_LOST descends on
// the IMU-integrated velocity (horizontal held at 0); MOTORS_STOPPED (terminal) sends zero
// thrusts every tick.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "wall_effect_ekf/indi_controller.hpp"

namespace wall_effect_ekf {

enum class IndiFailsafeState { kWaitingForInput, kNominal, kOdometryLost, kMotorsStopped };
const char* to_string(IndiFailsafeState s);

/// Why the fail-safe's last transition was taken: tactile_msgs/FsmState REASON_INDI_*
/// (block 80-89, checked at compile time), published with the state on kStateTopic.
enum class IndiReason : uint8_t {
  kNone = 0,             ///< no transition yet
  kInputsReady = 80,     ///< WAITING_FOR_INPUT -> NOMINAL
  kImuLost = 81,         ///< -> MOTORS_STOPPED: IMU stale (flight terminated)
  kOdometryLost = 82,    ///< NOMINAL -> ODOMETRY_LOST
  kDescentTimedOut = 83, ///< ODOMETRY_LOST -> MOTORS_STOPPED: failsafe_max_descent_s
  kTouchdown = 84,       ///< ODOMETRY_LOST -> MOTORS_STOPPED: the land detector held
  kCrashed = 85,         ///< -> MOTORS_STOPPED: crash_attitude held in the descent, or odometry lost just after it
};

/// The guards of the fail-safe's transitions, each alone (tested one by one).
namespace indi_guards {
/// Ages of the controller's inputs at a tick (now - stamp; an input never received: have_* false).
struct InputAges {
  bool have_odometry = false, have_imu = false;
  double odometry_age_s = 0.0, imu_age_s = 0.0;
};
/// WAITING_FOR_INPUT -> NOMINAL: odometry and IMU both received and no older than max_age_s.
bool inputs_ready(const InputAges& in, double max_age_s);
/// -> MOTORS_STOPPED: no IMU or an IMU older than max_age_s (no attitude: the controller cannot fly).
bool imu_lost(const InputAges& in, double max_age_s);
/// NOMINAL -> ODOMETRY_LOST: odometry older than max_age_s while the IMU is fresh.
bool odometry_lost(const InputAges& in, double max_age_s);
/// Land detector, one tick (ODOMETRY_LOST -> MOTORS_STOPPED once it held touchdown_confirm_s):
/// the descent loop commands less than kTouchdownThrustFraction of the hover thrust m g, and
/// yet the measured acceleration R a_m - g e3 is that of rest (|.| < kRestingAccel): in the
/// air that thrust would accelerate the vehicle down by > g / 2, so the floor carries it.
/// (The IMU-integrated vertical speed alone cannot tell a steady descent from rest: both
/// measure a = 0; the descent loop winds the thrust down on the floor, where the estimate
/// keeps asking for the descent it no longer gets.)
constexpr double kTouchdownThrustFraction = 0.5;
constexpr double kRestingAccel = 1.0;  ///< [m/s^2]
bool touchdown(double commanded_thrust_n, const Vec3& accel_world, double mass);
/// ODOMETRY_LOST, starts the floor probe: the height dead-reckoned from the last odometry on
/// the IMU is kBelowFloorMargin below failsafe_floor_z. The fallback of the land detector: the
/// simulated IMU (500 Hz point samples of 1 kHz physics) misses the 1 ms impact about one
/// landing in three, and the integrated speed then keeps reading the descent on the floor at
/// hover thrust. The estimate drifts with an accelerometer bias or attitude error, so it does
/// not stop the motors itself: the probe ramps the collective thrust from its value at the
/// start to 0 over kFloorProbeRampS (attitude loop running). On the floor the IMU reads rest
/// and touchdown holds once the thrust is below m g / 2; in the air the vehicle accelerates
/// down and airborne_in_probe aborts the probe.
constexpr double kBelowFloorMargin = 0.1;  ///< [m]
bool below_floor(double height_estimate, double floor_z);
/// Ramp of the floor probe [s] (choice: in the air the guard below trips once the thrust
/// lost 2 m / (m g) = 20 % of hover, 0.1 s into the ramp, about 1 cm of extra fall; on the
/// floor the thrust is below m g / 2 after 0.25 s, so touchdown stops the motors
/// touchdown_confirm_s later).
constexpr double kFloorProbeRampS = 0.5;
/// Collective thrust of the floor probe, probe_s after its start from start_thrust_n [N].
double floor_probe_thrust(double start_thrust_n, double probe_s);
/// Aborts the floor probe: the measured vertical acceleration (R a_m - g e3)_z is below
/// kAirborneAccel, clearly not resting on a floor; back to the descent loop (thrust from
/// hover, the integrated speed kept) with the floor bound off for the rest of the descent.
constexpr double kAirborneAccel = -2.0;  ///< [m/s^2]
bool airborne_in_probe(const Vec3& accel_world);
/// ODOMETRY_LOST -> MOTORS_STOPPED: the descent lasted failsafe_max_descent_s.
bool descent_timed_out(double descent_s, double max_descent_s);
/// ODOMETRY_LOST -> MOTORS_STOPPED once it held kCrashConfirmS: the body z axis more than
/// kCrashTilt from the vertical, a crash (as PX4's failure detector: FD_FAIL_R / FD_FAIL_P
/// 60 deg for FD_FAIL_R_TTRI 0.3 s). The descent flies on the IMU-integrated velocity; the
/// impact that ends a crash lasts ~1 ms and the 500 Hz IMU misses it, so the estimate keeps
/// the fall's speed and the loop brakes a fall that is over: in the SITL (accelerometer bias
/// 0.1 m/s^2, held-out seed 103) a crash into the wall 0.3 s after the loss became a climb at
/// 3.9 m/s to 35 m. In NOMINAL the odometry recovers the vehicle (the same seed without the
/// loss took off again from the floor), so the guard is the descent's only.
constexpr double kCrashTilt = 60.0 * M_PI / 180.0;  ///< [rad]
constexpr double kCrashConfirmS = 0.3;              ///< [s]
bool crash_attitude(const Mat3& R_world_body);
/// NOMINAL -> MOTORS_STOPPED instead of ODOMETRY_LOST: the odometry is lost within
/// kCrashMemoryS of a crash_attitude. The last odometry may then be the fall's and the impact
/// after it is unmeasured: the same flyaway (SITL, tuned seed 18: tilted 90 deg into the wall
/// at 11.7 s, the last odometry at 12.0 s taken falling, the floor hit before the loss was
/// seen at 12.09 s; the descent braked the fall it still believed in and climbed to 40 m).
constexpr double kCrashMemoryS = 1.0;  ///< [s] (choice)
bool crashed_before_loss(double since_crash_attitude_s);
}  // namespace indi_guards

/// Bound of each component of the accelerometer bias estimate [m/s^2] (choice: 5x a
/// BMI088-class zero-g offset of 20 mg; an odometry that disagrees more with the IMU is not
/// a bias to learn).
constexpr double kMaxAccelBias = 1.0;
/// Gate of one interval's residual [m/s^2] (choice): a residual component beyond it is not a
/// bias but an event the 500 Hz IMU samples missed and the odometry saw, such as a 1 ms
/// contact with the wall (SITL: the guard's touches moved the z estimate by 0.25 m/s^2
/// without it); the interval is skipped. Twice the bias bound, so a bias at the bound is
/// still learned; above the residuals of flight (0.02 m/s^2 of noise per 10 ms interval).
constexpr double kAccelResidualGate = 2.0;
/// The bias update of one odometry interval (pure, tested alone): the residual, the
/// IMU-integrated velocity change imu_dv (bias already subtracted) minus the odometry's over
/// dt, in the body frame R^T (.) / dt, blended in with gain min(1, dt / time_constant_s),
/// each component clamped to +-kMaxAccelBias. nullopt when a residual component is beyond
/// kAccelResidualGate (the bias unchanged).
std::optional<Vec3> accel_bias_update(const Vec3& bias, const Vec3& imu_dv, const Vec3& odometry_dv, double dt,
                                      const Mat3& R, double time_constant_s);

/// Body -> wall-frame rotation (wall_effect_model.hpp) from the body -> world
/// attitude and the wall direction psi-hat in the body frame.
Mat3 wall_frame_attitude(const Mat3& R_world_body, double wall_direction_body);

class IndiControlLogic {
 public:
  static constexpr const char* kNodeName = "indi_controller";
  static constexpr const char* kSetpointTopic = "wall_effect/setpoint";  // nav_msgs/msg/Odometry (world)
  static constexpr const char* kOdometryTopic = "odom";                  // nav_msgs/msg/Odometry
  static constexpr const char* kImuTopic = "imu";                        // sensor_msgs/msg/Imu (with orientation)
  static constexpr const char* kWallTopic = "wall_effect/estimate";      // tactile_msgs/msg/WallEstimate
  static constexpr const char* kOutputTopic = "cmd_rotor_thrust";        // tactile_msgs/msg/ThrustCommand
  /// The fail-safe's state for a ground station and bags (behaviour "indi_failsafe"):
  /// on every transition and at 1 Hz.
  static constexpr const char* kStateTopic = "indi/fsm_state";            // tactile_msgs/msg/FsmState
  static constexpr int64_t kStatePeriodNs = 1'000'000'000;

  struct Params {
    IndiParams indi;
    double rate_hz = 500.0;        ///< inner loop (IMU rate of the simulated vehicle; choice)
    double outer_rate_hz = 100.0;  ///< outer loop (004: 100 Hz ground station)
    bool use_wall_in_allocation = true;  ///< eq. 36: B with the wall estimate when detected
    double max_input_age_s = 0.1;  ///< odometry / IMU older than this: the fail-safe (README)
    /// ODOMETRY_LOST: speed of the descent [m/s] (choice: wall_effect_nav's
    /// FAILSAFE_LAND speed).
    double failsafe_descent_speed = 0.25;
    /// ODOMETRY_LOST: the land detector must hold this long before the motors stop [s] (choice).
    double touchdown_confirm_s = 0.5;
    /// ODOMETRY_LOST: the motors stop after this long in the descent, touched down or not [s]
    /// (choice: a 2 m height bound at 0.25 m/s is 8 s, plus 2 s).
    double failsafe_max_descent_s = 10.0;
    /// ODOMETRY_LOST: the floor's z in the odometry frame [m] (choice: 0, the motion-capture
    /// and simulator floor).
    double failsafe_floor_z = 0.0;
    /// Time constant of the accelerometer bias estimate [s] (choice): while odometry flows,
    /// the IMU-integrated velocity change minus the odometry's, per second, is the bias (and
    /// noise); a first-order filter of this time constant averages it. ODOMETRY_LOST dead
    /// reckons on the IMU minus the estimate (README "INDI fail-safe").
    double accel_bias_time_constant_s = 2.0;
    void validate() const;
  };

  struct Stats {
    uint64_t setpoints = 0, odometry = 0, imu = 0, walls = 0, published = 0;
    uint64_t dropped_nonfinite = 0;   ///< NaN/inf where a number is required
    uint64_t dropped_out_of_order = 0;  ///< odometry stamped at or before the last one used
    uint64_t ticks_without_input = 0; ///< WAITING_FOR_INPUT: no fresh odometry + IMU yet, nothing sent (on the ground)
    uint64_t ticks_nominal = 0, ticks_odometry_lost = 0, ticks_motors_stopped = 0;
    uint64_t odometry_ignored = 0;    ///< odometry after the fail-safe left NOMINAL (the descent is terminal)
    IndiFailsafeState state = IndiFailsafeState::kWaitingForInput;
    const char* reason = "no odometry and IMU yet";  ///< why the last transition was taken
    IndiReason reason_code = IndiReason::kNone;      ///< the same for programs (FsmState.reason_code)
    IndiFailsafeState previous = IndiFailsafeState::kWaitingForInput;
    uint32_t transitions = 0;
    uint64_t state_messages = 0;
    int64_t state_since_ns = 0;       ///< node time of the last transition
    double vertical_speed_estimate = 0.0;  ///< ODOMETRY_LOST: last odometry v_z + int (R a_m - g e3)_z dt [m/s]
    double height_estimate = 0.0;          ///< ODOMETRY_LOST: last odometry z + int v_z dt [m]
    double commanded_thrust = 0.0;         ///< ODOMETRY_LOST: collective thrust sent (the probe's ramp) [N]
    uint64_t floor_probes = 0, floor_probes_aborted = 0;  ///< started / aborted by airborne_in_probe
    /// The accelerometer bias estimate (body frame) [m/s^2], frozen when odometry is lost,
    /// and the odometry intervals it was updated on.
    Vec3 accel_bias = Vec3::Zero();
    uint64_t accel_bias_updates = 0;
    uint64_t accel_bias_gated = 0;    ///< intervals skipped by kAccelResidualGate
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  explicit IndiControlLogic(const Params& params);

  void on_setpoint(const nav_msgs::msg::Odometry& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  void on_imu(const sensor_msgs::msg::Imu& msg);
  void on_wall(const tactile_msgs::msg::WallEstimate& msg);
  std::optional<tactile_msgs::msg::ThrustCommand> on_timer(int64_t now_ns);
  /// The fail-safe's FsmState when there is one to publish at now_ns: after a transition
  /// not yet published, or kStatePeriodNs after the last message.
  std::optional<tactile_msgs::msg::FsmState> state_message(int64_t now_ns);

  int64_t period_ns() const;

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: the setpoint in reliable (a command, never dropped), odometry, IMU and
  /// wall estimate in as sensor data; the rotor thrusts out at period_ns() on the node's clock.
  template <class Ports>
  static void wire(Ports& p, IndiControlLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto thrust = p.template publisher<tactile_msgs::msg::ThrustCommand>(kOutputTopic, Pub::kData);
    p.template subscribe<nav_msgs::msg::Odometry>(kSetpointTopic, Sub::kReliable,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_setpoint(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdometryTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.template subscribe<sensor_msgs::msg::Imu>(kImuTopic, Sub::kSensorData,
                                                [&l](const sensor_msgs::msg::Imu& m) { l.on_imu(m); });
    p.template subscribe<tactile_msgs::msg::WallEstimate>(kWallTopic, Sub::kSensorData,
                                                          [&l](const tactile_msgs::msg::WallEstimate& m) { l.on_wall(m); });
    auto state = p.template publisher<tactile_msgs::msg::FsmState>(kStateTopic, Pub::kData);
    p.timer(l.period_ns(), [&l, thrust, state](int64_t now_ns) {
      if (auto out = l.on_timer(now_ns)) thrust(std::move(*out));
      if (auto s = l.state_message(now_ns)) state(std::move(*s));
    });
  }
  const Stats& stats() const { return stats_; }
  IndiFailsafeState state() const { return stats_.state; }
  /// ODOMETRY_LOST: the floor probe is running.
  bool floor_probe() const { return probe_since_ns_ >= 0; }
  const Params& params() const { return params_; }
  const IndiController& controller() const { return ctl_; }

 private:
  std::string body_frame_ = "base_link";  ///< of the rotor thrusts: the odometry's child frame
  Params params_;
  IndiController ctl_;
  Stats stats_;
  IndiSetpoint sp_;
  bool have_sp_ = false, have_odom_ = false, have_imu_ = false, have_wall_ = false;
  int64_t odom_ns_ = 0, imu_ns_ = 0, wall_ns_ = 0;
  Vec3 pos_ = Vec3::Zero(), vel_ = Vec3::Zero();
  Mat3 R_ = Mat3::Identity();
  Vec3 acc_ = Vec3(0, 0, kGravity), gyro_ = Vec3::Zero();
  bool wall_detected_ = false;
  double wall_distance_ = 0.0, wall_direction_ = 0.0;
  int64_t ticks_ = 0;
  int outer_every_ = 5;
  // Fail-safe.
  Vec3 imu_dv_since_odom_ = Vec3::Zero();  ///< int (R (a_m - b) - g e3) dt over the IMU samples since the last odometry
  Vec3 imu_dp_since_odom_ = Vec3::Zero();  ///< int (v_odom + dv) dt since the last odometry
  double imu_dt_since_odom_ = 0.0;         ///< the IMU time those integrals cover [s]
  void update_accel_bias(const Vec3& velocity, int64_t stamp_ns);
  double yaw_hold_ = 0.0;           ///< ODOMETRY_LOST: the yaw at the loss
  int64_t resting_since_ns_ = -1;   ///< ODOMETRY_LOST: the land detector holds since then (-1: not)
  int64_t tilted_since_ns_ = -1;    ///< ODOMETRY_LOST: crash_attitude holds since then (-1: not)
  int64_t crash_attitude_ns_ = -1;  ///< the last tick with crash_attitude (any state; -1: never)
  int64_t probe_since_ns_ = -1;     ///< ODOMETRY_LOST: the floor probe runs since then (-1: not)
  double probe_start_thrust_ = 0.0; ///< ODOMETRY_LOST: the collective thrust at the probe's start [N]
  bool floor_bound_off_ = false;    ///< ODOMETRY_LOST: a probe was aborted in the air
  void transition(IndiFailsafeState to, IndiReason code, const char* reason, int64_t now_ns);
  int64_t last_state_msg_ns_ = -1;
  int64_t first_tick_ns_ = -1;  ///< state_message()'s first call (time in WAITING_FOR_INPUT)
  uint32_t published_transitions_ = 0;
  void update_state(int64_t now_ns);
  tactile_msgs::msg::ThrustCommand command(int64_t now_ns, const std::array<double, 4>& f);
  std::optional<tactile_msgs::msg::ThrustCommand> nominal(int64_t now_ns);
  tactile_msgs::msg::ThrustCommand descend(int64_t now_ns);
  AllocationWall allocation_wall(int64_t now_ns) const;
};

}  // namespace wall_effect_ekf
