// INDI position controller and inner rate loop of paper 004 (Methods,
// eq. 26-36) for the ducted quadrotor.
//
//   outer (eq. 26):  p_dd_t = p_dd_d + K_d (p_dot_d - p_dot) + K_p (p_d - p) + K_i int (p_d - p)
//     (004 writes the errors as p - p_d with "positive gains"; the sign is
//     written here so that positive gains stabilise.)
//   increment (eq. 30): Delta(T0 z_B) = m (p_dd_t - p_dd_meas), p_dd_meas = R a_m - g e3
//     (a_m the specific force, +g at rest in ENU; 004's "R a_m + g e3" in its convention)
//   eq. 32-34: w_d,x = -m / (T0 tau) y_B^T e,  w_d,y = m / (T0 tau) x_B^T e,
//              T_d,0 = T0(t_k-1) + m z_B^T e,     e = p_dd_t - p_dd_meas
//     with tau = Delta t of the outer loop in 004; here a parameter
//     (attitude_time_constant, default 0.1 s; 0 = the outer-loop period as 004).
//   inner (eq. 35):  w_dot_d = -kappa_d (w - [w_d,x, w_d,y, 0]) - kappa_p [0, 0, psi - psi_d]
//   allocation (eq. 36): T0 = [B; 1 1 1 1]^-1 [J w_dot_d + w x J w; T_d,0],
//     B of eq. 8 with the wall effect when a wall estimate is given.
//
// Gains are not given by 004: choices (config/indi_controller.yaml, README).
// Core layer: Eigen only, no allocation.
#pragma once

#include <array>

#include "wall_effect_ekf/wall_effect_model.hpp"

namespace wall_effect_ekf {

struct IndiParams {
  VehicleParams vehicle;
  Vec3 k_p = Vec3(6.0, 6.0, 6.0);   ///< K_p [1/s^2] (choice)
  Vec3 k_d = Vec3(4.5, 4.5, 4.5);   ///< K_d [1/s] (choice)
  Vec3 k_i = Vec3(1.0, 1.0, 1.0);   ///< K_i [1/s^3] (choice)
  double integral_limit = 1.0;      ///< |K_i int e| per axis [m/s^2]
  /// The integral only runs while |p_d - p| < integral_zone on that axis
  /// (anti-windup during large transients; choice) [m].
  double integral_zone = 0.05;
  double max_accel_xy = 4.0;        ///< |p_dd_t| horizontal limit [m/s^2]
  /// tau of eq. 32-33 [s]; 0 uses the outer-loop period (004's literal
  /// Delta t). Default 0.1 s (choice): with the outer loop at 100 Hz and a
  /// first-order rate loop of 25 /s, tau = Delta t = 0.01 s makes the tilt
  /// loop faster than the rate loop and the simulated vehicle diverges
  /// after ~3 s of hover; 0.05-0.1 s is stable.
  double attitude_time_constant = 0.1;
  double max_rate_xy = 4.0;         ///< |w_d,x|, |w_d,y| limit [rad/s]
  double max_tilt = 0.5;            ///< no rate setpoint that tilts further [rad]
  Vec3 kappa_d = Vec3(25.0, 25.0, 6.0);  ///< kappa_d of eq. 35 [1/s] (choice)
  double kappa_p_yaw = 9.0;               ///< kappa_p of eq. 35 [1/s^2] (choice)
  double max_yaw_accel = 20.0;            ///< |w_dot_d,z| limit [rad/s^2]

  void validate() const;
};

/// Setpoint of the outer loop (p_d and its derivatives, psi_d).
struct IndiSetpoint {
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  Vec3 acceleration = Vec3::Zero();
  double yaw = 0.0;
  /// Per-axis switch of the position (K_p, K_i) terms: false = velocity
  /// control on that axis (004: a pilot's direction sets p_dot_d with
  /// K_p = K_i = 0).
  std::array<bool, 3> position_control = {true, true, true};
};

/// Feedback of the outer loop: position/velocity (motion capture, GPS or the
/// wall EKF), attitude and the accelerometer's specific force (body).
struct IndiFeedback {
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  Mat3 R = Mat3::Identity();      ///< body -> control frame
  Vec3 specific_force = Vec3(0.0, 0.0, kGravity);  ///< a_m, body [m/s^2]
};

struct IndiOuterOutput {
  Vec3 accel_target = Vec3::Zero();  ///< p_dd_t of eq. 26
  Vec3 increment = Vec3::Zero();     ///< Delta(T0 z_B) of eq. 30 [N]
  double rate_x = 0.0, rate_y = 0.0; ///< w_d,x, w_d,y of eq. 32-33 [rad/s]
  double thrust = 0.0;               ///< T_d,0 of eq. 34 [N]
};

/// Wall seen by the allocation (B of eq. 8); absent = free-flight B.
struct AllocationWall {
  bool present = false;
  double y = 0.0;                 ///< distance of the centre to the wall [m]
  Mat3 R = Mat3::Identity();      ///< body -> wall frame
};

class IndiController {
 public:
  explicit IndiController(const IndiParams& params);

  /// Clears the integral and sets T0(t_k-1) = m g (hover).
  void reset();

  /// Eq. 26 and 30-34 over one outer-loop period dt [s].
  IndiOuterOutput outer(const IndiSetpoint& sp, const IndiFeedback& fb, double dt);

  /// Eq. 35: desired angular acceleration from the body rates, the rate
  /// setpoints of the last outer() and the yaw error (yaw = psi or int w_z).
  Vec3 angular_accel(const Vec3& omega, double yaw, double yaw_setpoint) const;

  /// Eq. 36: rotor thrusts from w_dot_d, w and T_d,0; saturated to
  /// [0, max_rotor_thrust] keeping T_d,0 and scaling the torque part down.
  std::array<double, 4> allocate(const Vec3& angular_accel, const Vec3& omega, double total_thrust,
                                 const AllocationWall& wall = {}) const;

  /// Inner loop in one call: eq. 35 then eq. 36 with the last outer output.
  std::array<double, 4> inner(const Vec3& omega, double yaw, double yaw_setpoint,
                              const AllocationWall& wall = {}) const;

  const IndiOuterOutput& last_outer() const { return out_; }
  double previous_thrust() const { return thrust_prev_; }
  const IndiParams& params() const { return p_; }

 private:
  IndiParams p_;
  Vec3 integral_ = Vec3::Zero();
  double thrust_prev_ = 0.0;
  IndiOuterOutput out_;
};

}  // namespace wall_effect_ekf
