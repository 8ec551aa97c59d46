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
/// x = -leg to 0, a concave arc of radius r (centre (0, r)) turning up by
/// 90 deg, and a wall x = r up to y = r + leg. Walked floor -> wall, so the
/// free space (inside the corner) is on the left. `spacing` is the
/// polyline's point spacing [m].
std::vector<std::array<double, 2>> concave_corner_polyline(double fillet_radius, double leg, double spacing);

/// A point of that boundary by arc length s from the start of the arc
/// (s < 0 on the floor, s > pi r / 2 on the wall) and its tangent angle.
void concave_corner_point(double fillet_radius, double s, double& x, double& y, double& tangent);

/// Table II protocol (002 Sec. VII-D): five sweeps of the linear stage along
/// the concave boundary with tip contact, each from a known start location
/// (the sweep ID), localized by the preimage localizer. The paper gives its
/// object only as a picture (Fig. 11) and describes the sweeps as the
/// contact approaching a concave region with increasing curvature or moving
/// away from it with decreasing curvature (Sec. VII-A, Fig. 13): sweeps
/// 01-03 come from the straight floor into the arc, 04-05 leave the arc onto
/// the straight wall. Geometry values are choices.
struct Table2Params {
  BeamParams beam;
  LocalizerParams localizer;
  MomentNoise noise;
  bool bounded_noise = false;     ///< true: uniform relative noise in +-noise.relative (possibilistic test)
  double fillet_radius = 0.05;    ///< radius of the concave arc [m]; choice
  double leg = 0.15;              ///< length of the straight floor and wall [m]; choice
  /// Where the undeformed tip meets the boundary at the start of each sweep
  /// (sweep IDs 01-05), as arc length along the boundary from the start of
  /// the arc [m] (< 0: on the floor; the arc ends at pi r / 2 = 78.5 mm).
  /// Choice: the deflected tip touches ~8 mm further on and, at 0.5 mm per
  /// step, passes the curvature change in the first half of every sweep
  /// (01-03 enter the arc after ~15, ~11, ~7 steps, 04-05 leave it after ~16,
  /// ~12 steps). Along a stretch of constant curvature (a straight floor, the
  /// arc itself) the position along the boundary is not observable.
  std::vector<double> sweep_starts{-0.016, -0.014, -0.012, 0.060, 0.064};
  double attack_deg = 40.0;       ///< whisker axis from the boundary's inward normal at the start [deg]; choice
  double penetration = 0.004;     ///< undeformed tip depth behind the boundary at the start [m]; choice
  /// Base motion per step [m] (< 1 mm, 002 Sec. VII-D), along the chord from
  /// the start contact to the boundary point steps * step further (a linear
  /// stage moves in a straight line).
  double step = 0.0005;
  int steps = 40;
  /// Truth counts as inside the pose set if a pose is within these [m], [rad]; choice.
  double truth_distance = 0.003;
  double truth_angle = 0.0524;
  /// The set counts as localized when its spread is at most this [m]; choice.
  double localized_spread = 0.010;
  uint64_t seed = 1;
  void validate() const;
};

/// Start pose of sweep `index` (the whisker base) and the base motion per
/// step in the base frame.
void table2_sweep(const Table2Params& p, std::size_t index, Pose2& start, Pose2& motion);

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

/// Score of one sweep (002 Table II: mean and std of the localization error),
/// shared by run_table2 and the `tactile sim` graph of the whisker stage.
class SweepScore {
 public:
  SweepScore(int id, const Table2Params& p);
  /// One localizing step: the true base pose, the pose set, its best
  /// estimate and spread; `second_half` steps enter mean_error_mm.
  void add(const Pose2& truth, const std::vector<Pose2>& set, const Pose2& best, double spread, int step,
           bool second_half);
  /// An estimated contact (sensor frame) placed by the known base pose, for
  /// the obstacle profile (002 Sec. VI-B, Fig. 12), against the true boundary.
  void add_profile_point(const BoundaryMap& world, const Pose2& base, double cx, double cy);
  void contact_failure() { ++r_.contact_failures; }
  Table2Sweep finish(int steps, uint64_t resets) const;

 private:
  double truth_distance_, truth_angle_, localized_spread_;
  Table2Sweep r_;
  int kept_ = 0;
  double profile_sum_ = 0.0;
  std::vector<double> half_, localized_;
};

std::vector<Table2Sweep> run_table2(const Table2Params& p);

}  // namespace whisker_localization
