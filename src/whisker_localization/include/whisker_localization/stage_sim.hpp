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

}  // namespace whisker_localization
