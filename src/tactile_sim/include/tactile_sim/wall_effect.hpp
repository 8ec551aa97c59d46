// Wall effect of ducted rotors (paper 004 eq. 1-8).
//
// A ducted propeller of radius R near a vertical surface keeps its power but
// its thrust tilts towards the wall (004 eq. 2-3): with the nominal thrust T0
// (the vertical thrust far from any wall),
//     T_h = gamma_h(d_bar) T0,   T_v = gamma_v(d_bar) T0,    d_bar = d / R   (004 eq. 3)
//     gamma_h = a1 b1^d_bar,     gamma_v = 1 + a2 b2^d_bar                    (004 eq. 4)
// where d is the distance between the duct (rotor disk edge) and the wall:
// 004 writes y_i = y + e2^T R r_i - R for a wall along x_W with normal y_W.
// Eq. 5 turns the body thrust T0,i R e3 into the world force with
//     Gamma_i = [[1, 0, 0], [0, 1, -gamma_h], [0, 0, gamma_v]]   (wall normal = y_W)
// i.e. the vertical component is amplified by gamma_v and a horizontal force
// gamma_h (e3^T R e3) T0 attracts the rotor to the wall. Here the wall normal
// may point anywhere in the horizontal plane, so Gamma_i is written
// frame-free:  Gamma = I + (gamma_v - 1) e3 e3^T - gamma_h n e3^T,
// n = unit horizontal normal out of the wall (towards the rotor); with
// n = y_W this is exactly eq. 5.
//
// Core layer: Eigen only, no allocation.
#pragma once

#include <array>

#include "tactile_sim/types.hpp"

namespace tactile_sim {

/// Coefficients of the wall effect. Defaults: 004 eq. 4 least-squares fit and
/// the benchtop/vehicle rotor radius (004 Methods, R = 38 mm).
struct WallEffectParams {
  double rotor_radius = 0.038;  ///< R [m] (004 Methods: AVAN 3024, R = 38 mm)
  double a1 = 0.21;             ///< gamma_h = a1 b1^d_bar (004 eq. 4)
  double b1 = 0.34;
  double a2 = 0.06;             ///< gamma_v = 1 + a2 b2^d_bar (004 eq. 4)
  double b2 = 0.54;
  /// Normalised distance beyond which the effect is ignored (choice: at
  /// d_bar = 8, gamma_h = 3.7e-5 and gamma_v - 1 = 4.4e-4, below the force
  /// resolution of interest). Arena queries use rotor_radius * (1 + cutoff).
  double cutoff_normalized = 8.0;

  /// Throws std::invalid_argument naming the field: R > 0, a_i > 0,
  /// b_i in (0, 1) (004 eq. 4 constraints), cutoff > 0.
  void validate() const;
};

/// gamma_h(d_bar) = a1 b1^d_bar (004 eq. 4); d_bar < 0 is clamped to 0
/// (rotor touching or inside the wall), d_bar > cutoff gives 0.
double gamma_h(double d_bar, const WallEffectParams& p = {});
/// gamma_v(d_bar) = 1 + a2 b2^d_bar (004 eq. 4); clamped like gamma_h, 1 beyond cutoff.
double gamma_v(double d_bar, const WallEffectParams& p = {});

/// Gamma_i of 004 eq. 5 for a wall with unit horizontal normal `n_world`
/// (out of the wall, towards the rotor) at edge distance `distance` [m]
/// (d = rotor-centre-to-wall distance minus R, 004: y_i).
/// Gamma = I + (gamma_v - 1) e3 e3^T - gamma_h n e3^T.
Mat3 gamma_matrix(double distance, const Vec3& n_world, const WallEffectParams& p = {});

/// Wall seen by one rotor.
struct RotorWall {
  bool present = false;            ///< false: no wall within the cutoff (Gamma = I)
  double distance = 0.0;           ///< d = y_i of 004: rotor centre to wall minus R [m]
  Vec3 normal_world = Vec3::UnitY();  ///< unit horizontal normal out of the wall
};

/// One rotor's force in the WORLD frame: T_W,i = T0,i Gamma_i R e3 (004 eq. 5).
/// `R_wb` is the body->world rotation.
Vec3 rotor_force_world(double nominal_thrust, const Mat3& R_wb, const RotorWall& wall,
                       const WallEffectParams& p = {});
/// The same force in the BODY frame: R^T T_W,i (the quantity eq. 7 uses).
Vec3 rotor_force_body(double nominal_thrust, const Mat3& R_wb, const RotorWall& wall,
                      const WallEffectParams& p = {});

/// Geometry of a quadrotor for eq. 6-7.
struct RotorGeometry {
  std::array<Vec3, 4> position_body;  ///< r_i: centre of mass -> rotor i, body frame [m]
  /// Yaw reaction sign of rotor i: the (-1)^(i+1) of 004 eq. 7 (i = 1..4 -> +,-,+,-).
  std::array<double, 4> spin_sign = {1.0, -1.0, 1.0, -1.0};
  double torque_coefficient = 0.01;   ///< c_tau [m] (004 eq. 7)
};

/// Total force (world) and torque (body) of four rotors near walls.
struct RotorWrench {
  Vec3 force_world = Vec3::Zero();   ///< T_W = sum_i T_W,i (004 eq. 6)
  Vec3 torque_body = Vec3::Zero();   ///< tau (004 eq. 7) = B T0 (eq. 8)
  std::array<Vec3, 4> rotor_force_world{};  ///< T_W,i (004 eq. 5)
};

/// 004 eq. 5-7: T_W,i = T0,i Gamma_i R e3; T_W = sum T_W,i;
/// tau = sum ([r_i]x + s_i c_tau I) R^T T_W,i.
RotorWrench rotor_wrench(const std::array<double, 4>& nominal_thrust, const Mat3& R_wb,
                         const RotorGeometry& geometry, const std::array<RotorWall, 4>& walls,
                         const WallEffectParams& p = {});

}  // namespace tactile_sim
