// Large-deflection (elastica) cantilever model of a whisker: paper 002 eq. 1-4
// and the discretised numerical model it adapts (Quist & Hartmann's
// Elastica2D, "force mode" and "point mode", 002 Sec. III-A, V-B, VI-A).
//
// Sensor frame: origin at the clamped base, x along the undeformed whisker,
// y lateral. s is arc length from the base. A positive force magnitude bends
// the whisker toward +y (slope phi > 0, base moment M(0) > 0).
//
// The beam equation EI(s) phi'(s) = M(s) with
//   M(s) = (x_a - x(s)) F_y - (y_a - y(s)) F_x        (002 eq. 4, 2-D load)
// is integrated from the loading point s_a (where M = 0) back to the base
// (where phi = 0) with a fixed-step RK4 over n_segments. For a load that stays
// normal to the whisker at s_a (frictionless contact, Elastica2D force mode)
// the backward problem does not depend on phi_a, so one pass solves it; for a
// load of fixed direction (eq. 1-2: vertical load) phi_a is found by a
// bracketed root finder. Beyond s_a the whisker is straight (002 eq. 3).
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

namespace whisker_localization {

/// Whisker beam: geometry and material. Defaults: the paper's nitinol whisker
/// (002 Sec. V-A: d = 0.58 mm, E = 52 GPa, I = 5.555e-15 m^4, L = 75 mm).
struct BeamParams {
  double length = 0.075;               ///< L [m], 002 Sec. V-A
  double youngs_modulus = 52e9;        ///< E [Pa], 002 Sec. V-A (nitinol)
  double moment_of_inertia = 5.555e-15;  ///< I at the base [m^4], 002 Sec. V-A (pi d^4 / 64, d = 0.58 mm)
  /// Tip-to-base diameter ratio of a linear taper (1 = uniform). The area
  /// moment scales as (d(s)/d_base)^4, I(s) = I_base (1 - (1 - r) s / L)^4.
  double taper_ratio = 1.0;
  /// RK4 steps over the loaded part [0, s_a] (the discretised numerical model).
  int n_segments = 64;
  void validate() const;

  double ei_base() const { return youngs_modulus * moment_of_inertia; }
  /// E I(s) at arc length s (taper included).
  double ei_at(double s) const;
};

/// How the contact load is directed.
enum class LoadMode {
  kNormal,  ///< normal to the whisker at s_a (frictionless contact; Elastica2D force mode)
  kFixed,   ///< fixed direction in the sensor frame (eq. 1-2: direction +y, "vertical load")
};

/// A solved deflection.
struct BeamShape {
  bool ok = false;          ///< false if the solve failed (no root / not finite)
  double force = 0.0;       ///< F, signed magnitude [N]
  double s_a = 0.0;         ///< arc length of the load [m]
  double force_x = 0.0;     ///< load components on the whisker in the sensor frame [N]
  double force_y = 0.0;
  double phi_a = 0.0;       ///< slope at the load point (002 eq. 8, end slope) [rad]
  double contact_x = 0.0;   ///< (p_x, p_y) = (x(s_a), y(s_a)) [m]
  double contact_y = 0.0;
  double base_moment = 0.0;  ///< M(0) [N m] (002 eq. 4, 9)
  double base_force_x = 0.0;  ///< reaction force at the base = -load [N]
  double base_force_y = 0.0;
  double tip_x = 0.0;       ///< (x(L), y(L)); delta_x = L - tip_x, delta_y = tip_y
  double tip_y = 0.0;
  /// Nodes of the loaded part, base first (n_segments + 1), then the straight
  /// part is implied by eq. 3. Filled only when asked for (shape output).
  std::vector<double> s, x, y, phi;
};

/// Force-mode and point-mode solver for one beam. Holds no per-solve state:
/// const methods may be called concurrently.
class ElasticaSolver {
 public:
  explicit ElasticaSolver(const BeamParams& params);

  const BeamParams& params() const { return params_; }

  /// Force mode, load normal to the whisker at s_a (Elastica2D force mode).
  /// One integration pass, no root finding. `with_nodes` fills the node arrays.
  BeamShape solve_normal(double force, double s_a, bool with_nodes = false) const;

  /// Force mode, load of fixed direction `direction` [rad] in the sensor frame
  /// (pi/2 = +y, the vertical load of eq. 1-2), magnitude `force` >= 0.
  /// phi_a is found by a bracketed root finder over (-pi, pi).
  BeamShape solve_fixed(double force, double direction, double s_a, bool with_nodes = false) const;

  /// Point mode (002 Sec. V-B): the frictionless (normal) load F and the arc
  /// length s_a whose contact point is (p_x, p_y). Nested bracketed root
  /// finders: for each s_a, F with y(s_a) = p_y (monotone in F), then s_a with
  /// x(s_a) = p_x (monotone in s_a). Returns ok = false if the point is out
  /// of reach (beyond the whisker, behind the base or needing phi_a > max_slope).
  BeamShape solve_point(double px, double py, bool with_nodes = false) const;

  /// Normal load at s_a whose base moment is M (the moment-sensor contact
  /// set, 002 eq. 9, 17). Bracketed root finder on F; ok = false if M is not
  /// reachable at s_a with slope <= max_slope.
  BeamShape solve_moment(double moment, double s_a, bool with_nodes = false) const;

  /// Fixed-direction load at s_a whose base moment is M (tip contact on a
  /// frictionless wall with a known wall normal). ok = false if unreachable.
  BeamShape solve_moment_fixed(double moment, double direction, double s_a, bool with_nodes = false) const;

  /// Largest end slope |phi_a| accepted by point/moment mode (beyond it the
  /// whisker folds back; outside the sensor's elastic range, 002 Model 3).
  static constexpr double kMaxSlope = 1.4;

  /// Shape of the whole whisker (loaded nodes then the straight part, eq. 3)
  /// sampled at `n` points from s = 0 to L, from a shape solved with nodes.
  static void full_shape(const BeamShape& shape, double length, int n, std::vector<double>& xs,
                         std::vector<double>& ys);

 private:
  BeamShape integrate(double fx_dir, double fy_dir, double force, double s_a, bool normal, double phi_a,
                      bool with_nodes) const;
  BeamParams params_;
};

/// Euler-Bernoulli small-deflection references (tests, eq. 15 model).
/// Tip deflection of a point load F at s_a, evaluated at the load point:
/// F s_a^3 / (3 E I); base moment F s_a (002 eq. 15).
double euler_bernoulli_deflection(double force, double s_a, double ei);

/// Baseline contact distance from a base translation t_y and the base moment
/// it produced, d = sqrt(3 E I t_y / M(0)) (002 eq. 5, Solomon & Hartmann).
/// Returns NaN if t_y / M <= 0.
double baseline_distance(double ei, double t_y, double moment);

}  // namespace whisker_localization
