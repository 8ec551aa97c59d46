// Ducted quadrotor of paper 004 (280 g, four ducted rotors, R = 38 mm) as a
// 6-DoF rigid body with per-rotor first-order motors, the rotor-wall effect of
// 004 eq. 5-8 (wall_effect.hpp) applied per rotor from the arena, duct-guard
// penalty contact (contact.hpp) and, when no external controller commands the
// rotors, the simulator's own cascaded position controller (also used by
// XPLORER, xplorer.hpp). Equations, parameters and what is not modelled:
// docs/physics.md, "Ducted quadrotor and wall effect".
//
// Frames (REP-103): world ENU, body FLU; rotor order counter-clockwise from
// the front-right rotor: 0 front-right, 1 front-left, 2 back-left, 3 back-right.
#pragma once

#include <array>
#include <vector>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/contact.hpp"
#include "tactile_sim/types.hpp"
#include "tactile_sim/wall_effect.hpp"

namespace tactile_sim {

/// Position / yaw setpoint of the cascaded controllers (XPLORER, ducted quad).
struct PositionSetpoint {
  Vec3 position = Vec3::Zero();     ///< world [m]
  double yaw = 0.0;                 ///< [rad]
  Vec3 velocity_ff = Vec3::Zero();  ///< world velocity feed-forward [m/s]
};

/// How allocate_rotors() gives up torque the rotors cannot produce within
/// [0, max_thrust] at the commanded collective thrust.
enum class TorqueDesaturation {
  /// One factor scales roll, pitch and yaw torque alike (the torque's
  /// direction is kept): a yaw demand beyond the rotors' authority shrinks
  /// the roll/pitch torque with it.
  kScaleAll,
  /// Roll and pitch first (scaled only if they alone exceed the rotors), yaw
  /// gets what is left: the PX4 multicopter mixer's order ("mix roll, pitch
  /// and thrust without yaw ... mix in yaw and scale if it leads to limit
  /// violation"). 001 flies a PIXHAWK (Sec. V-A1) without naming its
  /// firmware: our choice for the SITL's flight controller.
  kYawFirst,
};

/// Gains of the cascaded P-PID controller: position P -> velocity PID ->
/// acceleration/tilt -> attitude P (quaternion error) -> body-rate PID ->
/// torque (J alpha + w x J w) -> allocation (001 Sec. II: "cascaded P-PID
/// for both the position and attitude loops"; gains are choices).
struct CascadedControllerParams {
  Vec3 pos_p = Vec3(2.0, 2.0, 2.0);     ///< [1/s]
  Vec3 vel_p = Vec3(5.0, 5.0, 5.0);     ///< [1/s]
  Vec3 vel_i = Vec3(2.0, 2.0, 2.0);     ///< [1/s^2]
  Vec3 vel_d = Vec3(0.0, 0.0, 0.0);     ///< [-]
  double vel_i_limit = 2.0;             ///< |integral term| per axis [m/s^2]
  double max_speed_xy = 1.5;            ///< [m/s]
  double max_speed_z = 1.0;             ///< [m/s]
  double max_tilt = 0.6;                ///< [rad]
  Vec3 att_p = Vec3(10.0, 10.0, 5.0);     ///< [1/s]
  Vec3 rate_p = Vec3(30.0, 30.0, 15.0); ///< [1/s]
  Vec3 rate_i = Vec3(10.0, 10.0, 5.0);    ///< [1/s^2]
  Vec3 rate_d = Vec3(0.3, 0.3, 0.0);    ///< [-]
  double rate_i_limit = 20.0;           ///< |integral term| per axis [rad/s^2]
  Vec3 max_rate = Vec3(6.0, 6.0, 3.0);  ///< [rad/s]
  /// Allocation's saturation rule (allocate_rotors). Default kScaleAll (the
  /// ducted quadrotor, 004, as tuned); XplorerParams::default_controller()
  /// sets kYawFirst (XPLORER's arms pass contact yaw torques of up to
  /// k x 30 deg = 0.68 N m per arm, ~4x the rotors' yaw authority at hover).
  TorqueDesaturation desaturation = TorqueDesaturation::kScaleAll;

  void validate() const;
};

/// The cascaded controller; returns the collective thrust [N] and body torque.
class CascadedController {
 public:
  CascadedController(const CascadedControllerParams& params, double mass, const Mat3& inertia);

  struct Output {
    double thrust = 0.0;               ///< collective thrust along body z [N]
    Vec3 torque = Vec3::Zero();        ///< body torque [N m]
    Vec3 accel_world = Vec3::Zero();   ///< commanded acceleration incl. gravity compensation
    Vec3 rate_setpoint = Vec3::Zero(); ///< body rates [rad/s]
  };
  /// `landed`: the vehicle rests on the floor; no tilt is commanded and the
  /// horizontal velocity and rate integrators are held at zero (as flight
  /// stacks do before take-off), so they do not wind up against the floor.
  Output update(const RigidBodyState& s, const PositionSetpoint& sp, double dt, bool landed = false);
  void reset();

 private:
  CascadedControllerParams p_;
  double mass_;
  Mat3 inertia_;
  Vec3 vel_int_ = Vec3::Zero(), rate_int_ = Vec3::Zero();
  Vec3 prev_vel_err_ = Vec3::Zero(), prev_rate_ = Vec3::Zero();
  bool first_ = true;
};

/// Solves [T, tau_x, tau_y, tau_z] = M f for the rotor forces f of a
/// quadrotor (M from 004 eq. 7 without walls: tau = sum r_i x f_i e3 + s_i c_tau f_i e3).
/// Saturation: the collective thrust is kept (clamped to [0, 4 max]) and the
/// torque part is scaled down until every rotor is within [0, max_thrust]:
/// all three axes by one factor (kScaleAll) or roll/pitch first and yaw in
/// what is left (kYawFirst, TorqueDesaturation). Allocation-free.
std::array<double, 4> allocate_rotors(const RotorGeometry& g, double thrust, const Vec3& torque,
                                      double max_thrust,
                                      TorqueDesaturation mode = TorqueDesaturation::kScaleAll);

/// Parameters of the ducted quadrotor. "004" marks paper values; the rest are
/// documented estimates/choices (docs/physics.md).
struct DuctedQuadParams {
  double mass = 0.280;                            ///< [kg] (004: 280 g)
  Vec3 inertia_diag = Vec3(7.5e-4, 7.5e-4, 1.5e-3);  ///< [kg m^2] (estimate)
  /// Rotor centres at (+-rotor_offset, +-rotor_offset, 0) (X layout, arm
  /// 0.116 m). From 004 at psi_d = 0: "d* = 17 cm (a 5 cm gap between the
  /// ducted propeller and wall)" -> 0.17 - 0.05 - R = 0.082 m, and "0.2 m from
  /// the wall corresponds to d_bar = 2.1 for the nearest propeller" ->
  /// 0.20 - 2.1 R - R = 0.082 m (docs/physics.md).
  double rotor_offset = 0.082;                    ///< [m]
  double torque_coefficient = 0.01;               ///< c_tau of 004 eq. 7 [m] (choice)
  double max_rotor_thrust = 0.44 * kGravity / 4;  ///< [N] (004: "over 440 g of thrust")
  double motor_time_constant = 0.02;              ///< first-order motor lag [s] (choice)
  double linear_drag = 0.02;                      ///< body drag force per speed [N s/m] (choice)
  double guard_radius = 0.040;                    ///< duct outer radius: R + 2 mm wall [m]
  bool wall_effect_enabled = true;
  WallEffectParams wall_effect;                   ///< 004 eq. 4
  double wall_truth_range = 2.0;                  ///< range of wall_truth() [m]
  CascadedControllerParams controller;
  ContactParams contact;

  void validate() const;
};

/// Ground truth of the nearest wall (for /ground_truth/wall).
struct WallTruth {
  bool present = false;       ///< a wall within wall_truth_range
  double distance = 0.0;      ///< vehicle centre -> nearest wall point [m] (inf if none)
  Vec3 direction_body = Vec3::Zero();  ///< unit vector centre -> wall point, body frame
  double direction = 0.0;     ///< atan2 of direction_body (y, x) [rad]
  double height = 0.0;        ///< centre above the floor [m]
  int obstacle_id = -1;
};

class DuctedQuad {
 public:
  DuctedQuad(const DuctedQuadParams& params, const RigidBodyState& initial);

  /// External controller: per-rotor nominal thrust commands T0,i [N] (clamped
  /// to [0, max_rotor_thrust]); held until replaced or until
  /// set_position_setpoint() hands control back to the internal controller.
  void set_rotor_thrusts(const std::array<double, 4>& thrust);
  /// Internal cascaded controller (used when no external controller runs).
  void set_position_setpoint(const PositionSetpoint& sp);
  bool external_control() const { return external_; }

  /// Advances the world by dt [s] (controller, motors, wall effect, contact, dynamics).
  void step(double dt, const Arena& arena);

  double time() const { return time_; }
  const RigidBodyState& state() const { return state_; }
  /// Accelerometer truth R^T (p_dd + g e3) over the last step [m/s^2].
  const Vec3& specific_force_body() const { return specific_force_body_; }
  /// Actual rotor nominal thrusts T0,i after the motor lag [N].
  const std::array<double, 4>& rotor_thrusts() const { return thrust_; }
  const std::array<double, 4>& rotor_commands() const { return command_; }
  double collective_thrust() const;  ///< sum T0,i [N]
  WallTruth wall_truth() const { return wall_truth_; }
  /// Rotor-wall state of the last step (004: y_i, normal).
  const std::array<RotorWall, 4>& rotor_walls() const { return rotor_walls_; }
  /// Contact forces on the guards in the last step (world) [N].
  const Vec3& external_force_world() const { return contact_force_; }
  /// Aerodynamic wall-effect force T_W - sum T0,i R e3 of the last step (world) [N].
  const Vec3& wall_force_world() const { return wall_force_; }
  /// Body/guard impacts since the last call (part "guard").
  std::vector<CollisionEvent> take_collisions();
  const RotorGeometry& geometry() const { return geometry_; }
  const DuctedQuadParams& params() const { return p_; }

 private:
  DuctedQuadParams p_;
  RotorGeometry geometry_;
  Mat3 inertia_;
  CascadedController controller_;
  RigidBodyState state_;
  double time_ = 0.0;
  bool external_ = false;
  bool landed_ = false;
  PositionSetpoint setpoint_;
  std::array<double, 4> command_{}, thrust_{};
  std::array<RotorWall, 4> rotor_walls_{};
  std::array<CircleContact, 4> guards_;
  WallTruth wall_truth_;
  Vec3 specific_force_body_ = Vec3(0, 0, kGravity);
  Vec3 contact_force_ = Vec3::Zero(), wall_force_ = Vec3::Zero();
  std::vector<CollisionEvent> collisions_;
};

namespace detail {
/// Shared by the vehicles: semi-implicit Euler step of a rigid body with
/// world force f and body torque tau, then a flat floor (resting contact:
/// no penetration, stuck while the net vertical force points down).
void integrate_rigid_body(RigidBodyState& s, double mass, const Mat3& inertia, const Vec3& f_world,
                          const Vec3& tau_body, double dt, double floor_z);
/// Yaw-only attitude (used on the ground).
Quat yaw_only(const Quat& q);
}  // namespace detail

}  // namespace tactile_sim
