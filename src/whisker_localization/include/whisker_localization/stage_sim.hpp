// SITL of the paper's bench (002 Sec. VI-VII): the nitinol whisker on a
// linear stage or mobile base, producing base moments from the elastica model
// (point obstacles: frictionless point mode; walls: frictionless tip contact,
// load along the wall normal), with Hall-sensor noise. Also runs the Table I
// contact-estimation protocol. No ROS, no messages.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "whisker_localization/contact_estimation.hpp"
#include "whisker_localization/elastica.hpp"
#include "whisker_localization/preimage.hpp"

namespace whisker_localization {

/// Base-moment measurement noise (Hall sensor after calibration). The paper
/// gives no figure; choice: 0.5 % of the reading plus 0.2 uN m (about 0.1 % of
/// the smallest Table I moment, 0.19 mN m).
struct MomentNoise {
  double relative = 0.005;
  double absolute = 2e-7;  ///< [N m]
  void validate() const;
  double apply(double m, std::mt19937_64& rng) const;
};

/// Table I protocol (002 Sec. VI-A): a point obstacle (pole) at p_x on the
/// undeformed whisker axis; from the first touch the base moves laterally by
/// t_y (Table I: 1 mm) and the contact distance is estimated by temporal
/// filtering (ours, eq. 21: the undeformed axis at touch intersected with the
/// moment set after the move) and by d = sqrt(3 E I t_y / M(0)) (eq. 5).
/// Larger t_y give the large-deflection rows where eq. 5 breaks down.
struct Table1Params {
  BeamParams beam;
  ContactSetParams sets;
  MomentNoise noise;
  std::vector<double> contacts{0.035, 0.045, 0.055, 0.065, 0.070};  ///< p_x [m], 002 Table I
  /// Base displacements t_y from the first touch [m]: 1 mm is 002 Table I;
  /// 8 and 16 mm are large-deflection rows (choice).
  std::vector<double> displacements{0.001, 0.008, 0.016};
  int trials = 20;
  uint64_t seed = 1;
  void validate() const;
};

struct Table1Row {
  double p_x = 0.0;        ///< true contact distance [m]
  double t_y = 0.0;        ///< base displacement from the touch [m]
  double m0 = 0.0;         ///< true M(0) after the step [N m]
  double phi_a = 0.0;      ///< true end slope after the step [rad]
  double ours_mean = 0.0;  ///< mean estimated distance, temporal filter [m]
  double ours_error_pct = 0.0;      ///< mean |error| / p_x [%]
  double baseline_mean = 0.0;       ///< mean eq. 5 distance [m]
  double baseline_error_pct = 0.0;  ///< mean |error| / p_x [%]
  int ours_failures = 0;            ///< trials without an intersection
};

std::vector<Table1Row> run_table1(const Table1Params& p);

/// Tip contact of the whisker on a frictionless wall (002 Sec. VII, Table II:
/// "contact known to be at the tip"): the load at s = L is along the wall
/// normal at the contact; its magnitude puts the tip on the wall. No contact
/// (m0 = 0) when the undeformed tip is in free space.
struct WallContact {
  bool contact = false;
  bool ok = true;            ///< false if no equilibrium was found
  double m0 = 0.0;           ///< base moment [N m]
  double tip_x = 0.0, tip_y = 0.0;  ///< contact point in the world [m]
  BeamShape shape;
};
WallContact tip_wall_contact(const ElasticaSolver& solver, const BoundaryMap& map, const Pose2& base);

/// The concave boundary of the Table II experiment: a floor y = 0 from
/// x = -leg to 0, a concave fillet of radius r (centre (0, r)) turning up by
/// 90 deg, and a wall x = r up to y = r + leg. Walked floor -> wall, so the
/// free space (inside the corner) is on the left. `spacing` is the
/// polyline's point spacing [m].
std::vector<std::array<double, 2>> concave_corner_polyline(double fillet_radius, double leg, double spacing);

/// Table II protocol (002 Sec. VII-D): five sweeps of the stage along the
/// concave boundary with tip contact; the preimage localizer runs from an
/// unknown start pose (the whole map). Geometry values are choices (the paper
/// gives its object only as a CAD drawing).
struct Table2Params {
  BeamParams beam;
  LocalizerParams localizer;
  MomentNoise noise;
  bool bounded_noise = false;     ///< true: uniform relative noise in +-noise.relative (possibilistic test)
  double fillet_radius = 0.05;    ///< concave fillet radius [m]; choice
  double leg = 0.15;              ///< length of the straight floor and wall [m]; choice
  /// Tip contact x on the floor at the start of each sweep (sweep IDs 01-05)
  /// [m]; the fillet starts at x = 0. Choice: every sweep reaches the fillet.
  std::vector<double> sweep_starts{-0.020, -0.016, -0.012, -0.008, -0.004};
  double attack_deg = 40.0;       ///< whisker axis from the wall's inward normal [deg]; choice
  double penetration = 0.004;     ///< undeformed tip depth behind the wall at the start [m]; choice
  double step = 0.0005;           ///< base motion per step along +x (the floor) [m] (< 1 mm, 002 Sec. VII-D)
  int steps = 40;
  /// Truth counts as inside the pose set if a pose is within these [m], [rad]; choice.
  double truth_distance = 0.003;
  double truth_angle = 0.0524;
  /// The set counts as localized when its spread is at most this [m]; choice.
  double localized_spread = 0.010;
  uint64_t seed = 1;
  void validate() const;
};

struct Table2Sweep {
  int id = 0;
  int steps = 0;
  int localizing_steps = 0;       ///< steps with a preimage (>= 3 observations)
  int localized_steps = 0;        ///< steps with spread <= localized_spread
  int first_localized_step = -1;
  double mean_error_mm = 0.0;     ///< mean |best - truth| over the localizing steps of the second half of the sweep
  double std_error_mm = 0.0;
  double localized_mean_error_mm = 0.0;  ///< same over the localized steps (spread <= localized_spread)
  double localized_std_error_mm = 0.0;
  double final_error_mm = 0.0;
  double final_spread_mm = 0.0;
  std::size_t final_set_size = 0;
  double truth_kept_fraction = 0.0;  ///< fraction of localizing steps with the truth inside the set
  uint64_t resets = 0;            ///< empty intersections (restarted from the preimage)
  int contact_failures = 0;       ///< truth steps without a tip contact
  /// Obstacle profile (002 Sec. VI-B, Fig. 12): estimated contact points of
  /// the sweep moved to the world by the known base poses; their distance to
  /// the true boundary [mm].
  std::size_t profile_points = 0;
  double profile_mean_error_mm = 0.0;
  double profile_max_error_mm = 0.0;
};

std::vector<Table2Sweep> run_table2(const Table2Params& p);

}  // namespace whisker_localization
