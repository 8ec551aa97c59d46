// XPLORER (paper 001): a 1.12 kg quadrotor whose four arms are hinged to the
// body about the body z axis with torsional springs (001 eq. 2:
// J_zz theta_dd + b theta_d + k theta = tau_a, J_zz = 0.0015 kg m^2,
// b = 0.009 N m s/rad, k = 1.307 N m/rad, deflection limited to 30 deg). A
// propeller-guard circle at each arm tip contacts the arena; its contact force
// drives the hinge and reaches the body through the hinge. Flown by the
// cascaded P-PID position/attitude controller of 001 Sec. II (shared with the
// ducted quadrotor); reports the normalised thrust command (001 Sec. V-A3:
// thrust = command x 32.5 N) and per-arm IMU truth (001 Sec. V-A2: one IMU per
// arm, 50 Hz). Equations, parameters, what is not modelled: docs/physics.md,
// "XPLORER".
//
// Arms/rotors counter-clockwise from the front-right one: 0 front-right,
// 1 front-left, 2 back-left, 3 back-right (as tactile_msgs/ArmImu.arm_id).
#pragma once

#include <array>
#include <vector>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/contact.hpp"
#include "tactile_sim/ducted_quad.hpp"  // PositionSetpoint, CascadedController
#include "tactile_sim/types.hpp"
#include "tactile_sim/wall_effect.hpp"  // RotorGeometry, rotor_wrench

namespace tactile_sim {

/// XPLORER parameters; "001" marks paper values, the rest are documented
/// estimates/choices (docs/physics.md).
struct XplorerParams {
  double mass = 1.12;                                  ///< [kg] (001 Sec. V-A1)
  Vec3 inertia_diag = Vec3(0.0072, 0.0072, 0.015);     ///< [kg m^2] (estimate)
  double hinge_offset = 0.05;     ///< centre -> arm hinge along the diagonal [m] (estimate)
  double arm_length = 0.15;       ///< l of 001 eq. 2: hinge -> motor [m] (estimate)
  double arm_inertia = 0.0015;    ///< J_zz [kg m^2] (001 Sec. V-A2)
  double arm_damping = 0.009;     ///< b [N m s/rad] (001 Sec. V-A2)
  double arm_stiffness = 1.307;   ///< k [N m/rad] (001 Sec. V-A2)
  double arm_max_deflection = 30.0 * M_PI / 180.0;  ///< end stops [rad] (001 Sec. II)
  double end_stop_stiffness = 30.0;  ///< stiffness beyond the stop [N m/rad] (choice)
  double end_stop_damping = 0.1;     ///< damping beyond the stop [N m s/rad] (choice)
  /// The rigid-chassis comparison vehicle of 001 Sec. V-C4 ("a similar
  /// dimension rigid UAV"): the hinges are locked (theta_i = 0), an arm's
  /// contact force and its moment reach the body directly.
  bool rigid_arms = false;
  double guard_radius = 0.07;     ///< propeller guard around each motor [m] (estimate)
  double body_radius = 0.08;      ///< central body circle [m] (estimate)
  double thrust_scale = 32.5;     ///< thrust = normalised command x 32.5 N (001 Sec. V-A3)
  /// The rotors' real static thrust is not linear in the command (001 Sec.
  /// V-A3: the 32.5 N scale is "obtained empirically by calculating the hover
  /// thrust" and gives "the approximate value of the actual thrust"): rotor
  /// thrust = T_max ((1 - f) u + f u^2), u = command / (thrust_scale / 4),
  /// the PX4 THR_MDL_FAC form, with T_max such that the scale is exact at
  /// hover. Default 0: the thrust is exactly command x 32.5 (the ideal
  /// model the behaviours were tuned on); 0.65, ArduPilot's default
  /// MOT_THST_EXPO for typical ESC/motor pairs, in
  /// xplorer_static_wrench_imperfect.yaml.
  double thrust_curve_factor = 0.0;
  double torque_coefficient = 0.016;  ///< rotor drag torque per thrust [m] (choice, 5" props)
  double motor_time_constant = 0.03;  ///< [s] (choice)
  double linear_drag = 0.1;       ///< [N s/m] (choice)
  double arm_imu_position = 0.10; ///< arm IMU distance from the hinge along the arm [m] (estimate)
  double arm_imu_rate_hz = 50.0;  ///< (001 Sec. V-A2: BNO055 at 50 Hz)
  CascadedControllerParams controller = default_controller();
  ContactParams contact;

  static CascadedControllerParams default_controller();
  void validate() const;
};

/// Truth of one arm IMU (noise: sensors.hpp ImuModel per arm).
struct ArmImuTruth {
  Quat orientation = Quat::Identity();  ///< arm frame -> world (arm x along the arm)
  Vec3 gyro = Vec3::Zero();             ///< angular velocity in the arm frame [rad/s]
  Vec3 accel = Vec3::Zero();            ///< specific force at the IMU, arm frame [m/s^2]
  double angle = 0.0;                   ///< theta_i [rad]
  double rate = 0.0;                    ///< theta_i dot [rad/s]
};

class Xplorer {
 public:
  Xplorer(const XplorerParams& params, const RigidBodyState& initial);

  void set_setpoint(const PositionSetpoint& sp);  ///< held until replaced
  /// Extra torque on each arm about its hinge [N m] (tests, fault injection);
  /// held until replaced. Not transmitted to the body except through the spring.
  void set_arm_external_torque(const std::array<double, 4>& torque) { arm_ext_torque_ = torque; }
  /// Extra force at each motor location, body frame [N] (a push on the arm:
  /// hinge torque (rho x F)_z as in 001 eq. 2, force to the body at the hinge);
  /// held until replaced.
  void set_arm_tip_force(const std::array<Vec3, 4>& force_body) { arm_tip_force_ = force_body; }

  void step(double dt, const Arena& arena);

  double time() const { return time_; }
  const RigidBodyState& state() const { return state_; }
  const Vec3& specific_force_body() const { return specific_force_body_; }
  const std::array<double, 4>& arm_angles() const { return theta_; }
  const std::array<double, 4>& arm_rates() const { return theta_dot_; }
  ArmImuTruth arm_imu(int i) const;
  /// Normalised collective thrust command (001: thrust = command x 32.5 N), in [0, 1].
  double thrust_command() const { return thrust_command_; }
  double collective_thrust() const;  ///< actual sum of rotor thrusts [N]
  /// Static thrust of one rotor at normalised command u in [0, 1] (thrust_curve_factor) [N].
  double rotor_static_thrust(double u) const;
  const std::array<double, 4>& rotor_thrusts() const { return thrust_; }
  /// Contact forces on arms and body in the last step (world) [N].
  const Vec3& external_force_world() const { return contact_force_; }
  /// Contact force on arm i's guard in the last step (world) [N].
  const Vec3& arm_contact_force_world(int i) const { return arm_force_.at(i); }
  /// Impacts since the last call (parts "arm0".."arm3", "body").
  std::vector<CollisionEvent> take_collisions();
  /// Rotor positions in the body frame with the current arm deflections.
  RotorGeometry geometry() const;
  /// Undeflected direction of arm i in the body frame [rad] (arm 0 front-right, then
  /// counter-clockwise; the X layout of 001 Fig. 1).
  static constexpr std::array<double, 4> kArmDirections{-M_PI / 4, M_PI / 4, 3 * M_PI / 4, -3 * M_PI / 4};
  const XplorerParams& params() const { return p_; }

 private:
  Vec3 arm_point_body(int i, double s) const;  ///< point at distance s from hinge i along arm i

  XplorerParams p_;
  Mat3 inertia_;
  RotorGeometry nominal_;
  std::array<double, 4> arm_dir_{};  ///< undeflected arm angles in the body frame [rad]
  CascadedController controller_;
  RigidBodyState state_;
  double time_ = 0.0;
  bool landed_ = false;
  PositionSetpoint setpoint_;
  std::array<double, 4> command_{}, thrust_{};
  double thrust_command_ = 0.0;
  double rotor_max_ = 0.0;  ///< T_max of the thrust curve [N]
  std::array<double, 4> theta_{}, theta_dot_{}, theta_ddot_{}, arm_ext_torque_{};
  std::array<Vec3, 4> arm_tip_force_{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  std::array<CircleContact, 4> arm_contacts_;
  CircleContact body_contact_;
  std::array<Vec3, 4> arm_force_{};
  Vec3 contact_force_ = Vec3::Zero();
  Vec3 specific_force_body_ = Vec3(0, 0, kGravity);
  Vec3 accel_world_ = Vec3::Zero(), ang_accel_body_ = Vec3::Zero();
  std::vector<CollisionEvent> collisions_;
};

}  // namespace tactile_sim
