// Whiskered Crazyflie Brushless (paper 000): hover-setpoint velocity control
// as in the Crazyflie firmware's PID controller, translational dynamics with
// roll/pitch/yaw as closed-loop attitude lags, two forward whiskers (PRBM
// contact, 000 eq. S1-S10), a propeller-guard contact circle, and a mocap or
// flow-deck state estimate. Equations, parameters and sources:
// docs/physics.md, "Whiskered Crazyflie".
//
// Core layer: Eigen only, allocation-free step() (except collision events).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/contact.hpp"
#include "tactile_sim/flow_deck.hpp"
#include "tactile_sim/types.hpp"
#include "tactile_sim/whisker_mechanics.hpp"

namespace tactile_sim {

/// Velocity-mode setpoint (Crazyflie commander hover setpoint): vx, vy in the
/// body-yaw frame [m/s], yaw rate [rad/s] (CCW), height above the floor [m].
struct HoverSetpoint {
  double vx = 0, vy = 0, yaw_rate = 0, height = 0;
  bool land = false;
};

/// kMocap: truth + noise; kFlowDeck: flow deck + IMU (drifts); kImuTof: IMU +
/// ToF only, the flow deck's estimator without flow (000 Fig. 6, darkness).
enum class StateEstimateMode { kMocap, kFlowDeck, kImuTof };

/// Stream ids of the vehicle's own random sources (see stream_seed).
namespace crazyflie_streams {
constexpr uint64_t kMocap = 130;
}  // namespace crazyflie_streams

/// Parameters. "000" marks paper values; the rest are choices (docs/physics.md).
struct CrazyflieParams {
  // --- airframe ------------------------------------------------------------
  double mass = 0.0441;                      ///< [kg] (000: 44.1 g with whiskers and decks)
  double max_thrust_per_motor = 0.030 * kGravity;  ///< [N] (000: 4 motors, 30 g each)
  double motor_tau = 0.015;                  ///< motor/propeller thrust lag [s]
  double drag_coeff = 0.01;                  ///< linear drag [N s/m] (all axes)
  double yaw_inertia = 4.0e-5;               ///< I_zz [kg m^2] (whisker yaw torque only)
  double guard_radius = 0.08;                ///< propeller-guard contact circle [m]
  /// A guard contact starting less than this after the previous one ended is
  /// the same impact (bounces), not a new CollisionEvent [s].
  double collision_debounce = 0.3;
  // --- whiskers --------------------------------------------------------------
  WhiskerParams whisker;                     ///< 200 mm, 0.4 mm Nitinol, alpha 45 deg (000)
  bool whiskers_enabled = true;
  double whisker_spacing = 0.05;             ///< lateral distance of the bases [m] (000: 5 cm)
  double whisker_base_x = 0.05;              ///< base ahead of the centre of mass [m]
  // --- firmware-like controller (Crazyflie PID controller, hover mode) --------
  double thrust_base = 0.40;                 ///< base thrust before the vz integrator [N]
  double vel_kp = 25.0 * M_PI / 180.0;       ///< tilt per velocity error [rad/(m/s)] (fw: 25 deg)
  double vel_ki = 1.0 * M_PI / 180.0;        ///< [rad/(m/s)/s] (fw: 1 deg)
  double max_tilt = 20.0 * M_PI / 180.0;     ///< roll/pitch setpoint limit [rad] (fw: 20 deg)
  double z_kp = 2.0;                         ///< height -> vz [1/s] (fw)
  double z_ki = 0.5;                         ///< [1/s^2] (fw)
  double vz_max = 1.0;                       ///< [m/s] (fw)
  double vz_kp = 10.0;                       ///< vz error -> accel [1/s] (fw 25 thrust units/(m/s))
  double vz_ki = 6.0;                        ///< [1/s^2] (fw 15 thrust units/m)
  double max_yaw_rate = 200.0 * M_PI / 180.0;  ///< [rad/s]
  double land_speed = 0.25;                  ///< descent speed while landing [m/s]
  double land_cutoff_height = 0.02;          ///< motors stop below this while landing [m]
  // --- closed-loop attitude (second order) and yaw rate (first order) ----------
  double attitude_wn = 30.0;                 ///< natural frequency [rad/s]
  double attitude_zeta = 0.8;                ///< damping ratio
  double yaw_rate_tau = 0.05;                ///< yaw-rate lag [s]
  double yaw_kp = 6.0;                       ///< yaw angle -> rate [1/s] (fw attitude PID yaw kp 6)
  double yaw_ki = 1.0;                       ///< [1/s^2] (fw attitude PID yaw ki 1)
  // --- estimate ----------------------------------------------------------------
  StateEstimateMode estimate_mode = StateEstimateMode::kMocap;
  double mocap_position_noise = 0.0005;      ///< [m] (white, per step)
  double mocap_velocity_noise = 0.005;       ///< [m/s]
  double mocap_yaw_noise = 0.0035;           ///< [rad]
  FlowDeckParams flow_deck;
  ContactParams contact;

  double max_thrust() const { return 4.0 * max_thrust_per_motor; }
  void validate() const;  ///< throws std::invalid_argument naming the field
};

class WhiskerCrazyflie {
 public:
  using Params = CrazyflieParams;

  struct Whisker {
    bool contact = false;
    Vec2 base = Vec2::Zero(), tip = Vec2::Zero(), contact_point = Vec2::Zero();
    double depth = NAN;  ///< true depth along body x [m], NaN if no wall within reach
    double normal_force = 0.0, friction_force = 0.0, base_moment = 0.0;
    int obstacle_id = -1;
  };

  /// Starts on the floor or in the air with motors off until a setpoint with
  /// height > 0 arrives. Throws std::invalid_argument on bad params.
  WhiskerCrazyflie(const CrazyflieParams& params, const RigidBodyState& initial, uint64_t seed);

  void set_setpoint(const HoverSetpoint& sp);  ///< held until replaced
  void step(double dt, const Arena& arena);

  double time() const { return time_; }
  const RigidBodyState& state() const { return state_; }  ///< truth
  Vec3 specific_force_body() const { return specific_force_body_; }  ///< accelerometer truth
  double collective_thrust() const { return thrust_; }  ///< [N]
  bool motors_on() const { return motors_on_; }
  const std::array<Whisker, 2>& whiskers() const { return whiskers_; }  ///< 0 left, 1 right
  /// Full PRBM detail of whisker i's last contact (000 eq. S1-S10).
  const WhiskerContact& whisker_detail(int i) const { return whisker_detail_[i]; }
  Vec3 external_force_world() const { return external_force_; }  ///< whiskers + guard [N]
  double external_yaw_moment() const { return external_yaw_moment_; }  ///< [N m]
  std::vector<CollisionEvent> take_collisions();
  RigidBodyState estimate() const { return estimate_; }
  const FlowDeckEstimator& flow_deck() const { return flow_deck_; }
  const HoverSetpoint& setpoint() const { return setpoint_; }
  /// Commanded roll/pitch (after the limit) [rad].
  double roll_command() const { return roll_cmd_; }
  double pitch_command() const { return pitch_cmd_; }
  double roll() const { return roll_; }
  double pitch() const { return pitch_; }
  const Params& params() const { return p_; }

 private:
  void control(double dt, double floor_z);
  void sense_whiskers(const Arena& arena);
  void update_estimate(double dt, const Vec3& accel_world, double floor_z);

  Params p_;
  Rng rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  FlowDeckEstimator flow_deck_;
  CircleContact guard_contact_;

  RigidBodyState state_;
  RigidBodyState estimate_;
  HoverSetpoint setpoint_;
  double time_ = 0.0;
  // attitude (ZYX Euler) and rates
  double roll_ = 0.0, pitch_ = 0.0, yaw_ = 0.0;
  double roll_rate_ = 0.0, pitch_rate_ = 0.0, yaw_rate_ = 0.0;
  double yaw_sp_ = 0.0, yaw_int_ = 0.0;  // integrated yaw setpoint, attitude-loop integrator
  // controller
  double roll_cmd_ = 0.0, pitch_cmd_ = 0.0, thrust_cmd_ = 0.0;
  double vx_int_ = 0.0, vy_int_ = 0.0, z_int_ = 0.0, vz_int_ = 0.0;
  double thrust_ = 0.0;
  bool motors_on_ = false;
  bool landing_done_ = false;
  double last_guard_contact_time_ = -1e9;
  // outputs
  std::array<Whisker, 2> whiskers_{};
  std::array<WhiskerContact, 2> whisker_detail_{};
  Vec3 external_force_ = Vec3::Zero();
  double external_yaw_moment_ = 0.0;
  Vec3 specific_force_body_ = Vec3(0, 0, kGravity);
  std::vector<CollisionEvent> collisions_;
};

}  // namespace tactile_sim
