// Whisker shaft against a wall: contact geometry and the pseudo-rigid-body
// model (PRBM) of paper 000, Supplementary eq. S1-S10.
//
// The whisker is a 200 mm, 0.4 mm Nitinol wire (000, Results "whisker shaft")
// mounted at the front of the drone, pointing forward in the drone's pitch
// plane and tilted up by the placement angle alpha (45 deg w.r.t. the yaw
// plane, 000 Methods "Hardware", Fig. 2, Fig. S2).
//
// The SITL world is 2D top-down. The shaft enters it as its horizontal
// projection: a segment from the base along the body x axis of length
// l_o cos(alpha) (the horizontal reach). A wall crossing that segment at
// horizontal distance `depth` from the base (the tactile depth: distance from
// the whisker base to the wall along the drone's forward axis, the quantity the
// tactile depth estimator predicts) deflects the whisker by the PRBM contact
// depth d: how far the base has advanced past the position where the undeformed
// tip first touched the wall, measured along the wall normal:
//     d = (l_o cos(alpha) - depth) * cos(phi),
// phi = incidence angle between the body x axis and the wall normal (phi = 0,
// a wall straight ahead, is the geometry of 000 Fig. S2a). The contact point is
// static on the wall (000 Fig. S2: P_c^S) at height l_o sin(alpha) above the base.
// See docs/physics.md, section "Whiskered Crazyflie", for every choice.
//
// Core layer: Eigen only, no allocation.
#pragma once

#include <cmath>
#include <cstdint>

#include "tactile_sim/types.hpp"

namespace tactile_sim {

/// Whisker shaft and mounting. "000" marks values of paper 000, the rest are
/// modelling choices (docs/physics.md).
struct WhiskerParams {
  double length = 0.200;          ///< l_o [m] (000: 200 mm Nitinol wire)
  double diameter = 0.4e-3;       ///< wire diameter [m] (000: 0.4 mm)
  /// Young's modulus of superelastic Nitinol in its austenite phase [Pa]
  /// (choice: 75 GPa, inside the 70-83 GPa range of austenitic NiTi datasheets).
  double youngs_modulus = 75.0e9;
  double placement_angle = M_PI / 4.0;  ///< alpha [rad] w.r.t. the yaw plane (000: 45 deg)
  /// Speed below which Coulomb friction is regularised linearly (stick ~ viscous) [m/s].
  double friction_speed_eps = 0.005;
  /// Stick-slip (friction-induced vibration) of a whisker sliding on a wall: a
  /// zero-mean fluctuation of the base bending moment, amplitude
  /// stick_slip_gain * mu * N * l_o sin(alpha) * min(|v_t| / friction_speed_eps, 1),
  /// a sawtooth per stick-slip cycle (load builds while the tip sticks, drops
  /// when it slips) whose cycles are stick_slip_length long on the wall with a
  /// per-cycle amplitude drawn from a hash of (stick_slip_seed, obstacle, cycle):
  /// the surface's asperities. 0 disables it. Choice, see docs/whisker_signal_model.md
  /// ("Stick-slip while sliding"). Zero without contact and without sliding.
  double stick_slip_gain = 2.0;
  double stick_slip_length = 0.0015;  ///< wall length of one stick-slip cycle [m]
  uint64_t stick_slip_seed = 0x5715C1157ULL;

  /// Second moment of area I = pi d^4 / 64 [m^4].
  double second_moment() const { return M_PI * std::pow(diameter, 4) / 64.0; }
  /// Bending stiffness E I [N m^2].
  double bending_stiffness() const { return youngs_modulus * second_moment(); }
  /// Horizontal projection of the undeformed shaft, l_o cos(alpha) [m].
  double horizontal_reach() const { return length * std::cos(placement_angle); }
  /// Height of the (static) contact point above the base, l_o sin(alpha) [m]:
  /// the lever of the wall's horizontal normal force about the base.
  double contact_height() const { return length * std::sin(placement_angle); }

  /// Throws std::invalid_argument naming the field and the reason.
  void validate() const;
};

/// Every intermediate of 000 eq. S1-S10 for one contact depth d.
struct PrbmState {
  double d = 0.0;       ///< contact depth [m] (000 Fig. S2a)
  double px = 0.0;      ///< P_c^S x (000 eq. S3) [m]
  double py = 0.0;      ///< P_c^S y (000 eq. S3) [m]
  double theta = 0.0;   ///< pseudo-rigid-body angle (000 eq. S6) [rad]
  double beta = 0.0;    ///< force angle, 3/2 theta (000 eq. S2) [rad]
  double n = 0.0;       ///< force ratio tan(beta) (000 eq. S1)
  double gamma = 0.0;   ///< characteristic radius factor (000 eq. S7)
  double k_theta = 0.0; ///< stiffness polynomial a0 - a1 n + ... + a4 n^4 (000 eq. S8)
  double lr = 0.0;      ///< flexural beam length (000 eq. S4-S5) [m]
  double spring_k = 0.0;  ///< torsion spring constant K (000 eq. S8) [N m / rad]
  double force_f = 0.0;   ///< transverse force F at P_c (000 eq. S1, S9) [N]
  double normal_force = 0.0;  ///< normal force N on the wall (000 eq. S10) [N]
  double base_moment = 0.0;   ///< N * l_o sin(alpha): bending moment at the base [N m]
};

/// 000 eq. S1-S10 for contact depth d (0 <= d <= l_o cos(alpha); d is clamped
/// to that range). d = 0 gives all forces 0. The polynomials of eq. S7-S8 are
/// fitted for 0.5 < n < 10 (000); they are evaluated as given outside it.
PrbmState prbm_contact(const WhiskerParams& params, double d);

/// One whisker's contact with the arena in the top-down plane.
struct WhiskerContact {
  bool contact = false;
  Vec2 base = Vec2::Zero();           ///< whisker base (world x, y)
  Vec2 tip = Vec2::Zero();            ///< undeformed tip projection
  Vec2 contact_point = Vec2::Zero();  ///< wall contact (projection), = tip without contact
  Vec2 normal = Vec2::Zero();         ///< wall normal (out of the obstacle), 0 without contact
  double depth = NAN;        ///< base -> wall along the body x axis [m]; NaN without contact
  double deflection = 0.0;   ///< PRBM contact depth d [m]
  double normal_force = 0.0;    ///< N [N]
  double friction_force = 0.0;  ///< |friction| (mu N while sliding) [N]
  /// Bending moment at the base [N m] (barometer load): the PRBM moment
  /// (prbm.base_moment) plus the stick-slip fluctuation while sliding.
  double base_moment = 0.0;
  double stick_slip_moment = 0.0;  ///< stick-slip part of base_moment [N m]
  Vec2 force_on_body = Vec2::Zero();  ///< horizontal reaction on the drone (normal + friction) [N]
  int obstacle_id = -1;
  PrbmState prbm;               ///< eq. S1-S10 intermediates of this contact
};

/// Stick-slip profile along the wall: zero-mean sawtooth in [-1, 1] of the wall
/// coordinate u [m] (cycles of `length`, per-cycle amplitude in [0.5, 1] from a
/// hash of seed, obstacle and cycle index). Deterministic, no state.
double stick_slip_profile(double u, double length, uint64_t seed, int obstacle_id);

/// Contact of a whisker whose base is at `base`, pointing along the unit
/// vector `forward` (body x in the plane), with a wall hit found by a segment
/// query from the base to the undeformed tip projection:
/// `hit`, `hit_distance` (from the base along `forward`), `hit_point`,
/// `hit_normal` (unit, out of the obstacle), `friction` (Coulomb mu of the wall
/// material). `base_velocity` (world, x y) sets the sliding direction of the
/// friction force.
WhiskerContact whisker_contact(const WhiskerParams& params, const Vec2& base,
                               const Vec2& forward, const Vec2& base_velocity, bool hit,
                               double hit_distance, const Vec2& hit_point,
                               const Vec2& hit_normal, double friction, int obstacle_id);

}  // namespace tactile_sim
