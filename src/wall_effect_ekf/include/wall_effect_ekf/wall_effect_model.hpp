// Near-wall model of a quadrotor with ducted rotors (paper 004 eq. 3-10),
// written in the WALL frame W of 004 Fig. 3a: origin on the wall, x_W along
// the wall, y_W the wall normal pointing into the free space (the vehicle is
// at y > 0), z_W up. R is the body -> wall-frame rotation, body FLU.
//
//   gamma_h(d_bar) = a1 b1^d_bar,  gamma_v(d_bar) = 1 + a2 b2^d_bar      (004 eq. 4)
//   y_i = y + e2^T R r_i - R_rotor,  d_bar_i = y_i / R_rotor             (004, before eq. 5)
//   T_W,i = T0,i Gamma_i(y_i) R e3,
//   Gamma_i = [[1,0,0],[0,1,-gamma_h],[0,0,gamma_v]]                      (004 eq. 5)
//   m p_dd + m g e3 = T_W = sum_i T_W,i  (- k_drag p_dot, a choice)      (004 eq. 6)
//   tau = sum_i ([r_i]x + s_i c_tau I) R^T T_W,i = B T0                  (004 eq. 7-8)
//   n_x = e1^T R^T p_dot / z - w_y,  n_y = e2^T R^T p_dot / z + w_x      (004 eq. 9-10)
//
// This is the estimator's own model (ROS-free core, Eigen only, no
// allocation). It describes the same physics as the simulator's wall-effect
// model; test_sim_agreement checks that they agree.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

namespace wall_effect_ekf {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat3 = Eigen::Matrix3d;
using Mat34 = Eigen::Matrix<double, 3, 4>;
using Mat4 = Eigen::Matrix4d;
using Quat = Eigen::Quaterniond;

constexpr double kGravity = 9.81;  ///< [m/s^2]

/// [v]x, the cross-product matrix.
Mat3 skew(const Vec3& v);
/// SO(3) exponential map (Rodrigues), exact for any angle.
Mat3 so3_exp(const Vec3& phi);

/// Coefficients of the proximity effect (004 eq. 4, least-squares fit).
struct ProximityParams {
  double rotor_radius = 0.038;  ///< R [m] (004: AVAN 3024, R = 38 mm)
  double a1 = 0.21;             ///< gamma_h = a1 b1^d_bar (004 eq. 4)
  double b1 = 0.34;
  double a2 = 0.06;             ///< gamma_v = 1 + a2 b2^d_bar (004 eq. 4)
  double b2 = 0.54;
  /// Throws std::invalid_argument naming the field: R > 0, a_i > 0, b_i in (0, 1).
  void validate() const;
};

/// gamma_h, gamma_v of 004 eq. 4 at the rotor-wall distance y_i [m] and their
/// derivatives with respect to y_i [1/m]. y_i < 0 (rotor touching the wall)
/// is clamped to 0, where the derivatives are 0.
struct Proximity {
  double gh = 0.0, gv = 1.0;    ///< gamma_h, gamma_v
  double dgh = 0.0, dgv = 0.0;  ///< d gamma / d y_i [1/m]
};
Proximity proximity(double y_i, const ProximityParams& p);

/// Gamma_i(y_i) of 004 eq. 5 (wall frame).
Mat3 gamma_matrix(double y_i, const ProximityParams& p);

/// Rigid-body and rotor parameters of the vehicle. The paper gives m = 280 g
/// and R = 38 mm; geometry, inertia and c_tau are choices equal to the
/// simulated vehicle (rotor order counter-clockwise from front-right, spins
/// (-1)^(i+1) of 004 eq. 7).
struct VehicleParams {
  double mass = 0.280;                              ///< m [kg] (004: 280 g)
  Vec3 inertia_diag = Vec3(7.5e-4, 7.5e-4, 1.5e-3);  ///< J [kg m^2] (choice: the simulated vehicle's estimate)
  /// r_i = (+-L, +-L, 0) [m]: 004 "d* = 17 cm (a 5 cm gap between the ducted
  /// propeller and wall)" and "0.2 m ... d_bar = 2.1 for the nearest
  /// propeller" at psi_d = 0 both give L = 0.082 m.
  double rotor_offset = 0.082;
  double torque_coefficient = 0.01;                 ///< c_tau [m] (004 eq. 7, choice)
  /// Linear drag k [N s/m] subtracted from T_W in eq. 6 (choice; 004 eq. 6
  /// has none: set 0 for the paper's model).
  double linear_drag = 0.02;
  double max_rotor_thrust = 1.0791;                 ///< [N] (004: "over 440 g of thrust" = 0.44 g / 4)
  ProximityParams proximity;

  void validate() const;
  /// r_i, body frame: front-right, front-left, back-left, back-right.
  std::array<Vec3, 4> rotor_positions() const;
  /// (-1)^(i+1), i = 1..4 (004 eq. 7).
  static constexpr std::array<double, 4> kSpin = {1.0, -1.0, 1.0, -1.0};
};

/// Distance of rotor i to the wall: y_i = y + e2^T R r_i - R (004).
double rotor_wall_distance(double y, const Mat3& R, const Vec3& r_i, const ProximityParams& p);

/// Forces and torque of the four rotors near a wall at distance y.
struct Wrench {
  Vec3 force_wall = Vec3::Zero();  ///< T_W, wall frame (004 eq. 6) [N]
  Vec3 force_body = Vec3::Zero();  ///< R^T T_W [N]
  Vec3 torque_body = Vec3::Zero(); ///< tau (004 eq. 7) [N m]
};
/// 004 eq. 5-7. `wall_present = false` gives the free-flight wrench (Gamma = I).
Wrench rotor_wrench(const Vec4& thrust, double y, const Mat3& R, const VehicleParams& v,
                    bool wall_present = true);

/// B of 004 eq. 8 (tau = B T0), 3 x 4, at wall distance y and attitude R.
Mat34 torque_matrix(double y, const Mat3& R, const VehicleParams& v, bool wall_present = true);

/// Optical flow [n_x, n_y] of 004 eq. 9-10 from the wall-frame velocity,
/// attitude, body rates and height above the floor.
Vec2 optical_flow(const Vec3& velocity, const Mat3& R, const Vec3& omega, double height);

}  // namespace wall_effect_ekf
