// Virtual whisker sensors (002 Sec. IV-A, Models 1-4, eq. 6-9), their
// contact-point sets (eq. 10-18), spatial and temporal filtering by set
// intersection (eq. 19-21), tip-contact and slip detection (002 Sec. VI-A),
// the Hall-sensor calibration B -> M(0) (002 Sec. V-B) and obstacle-profile
// estimation by sweeping (002 Sec. VI-B, Fig. 12).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "whisker_localization/elastica.hpp"

namespace whisker_localization {

/// A set of possible contact points in the sensor frame (eq. 18): a polyline
/// ordered by its parameter, with the beam parameters of each point.
struct ContactSet {
  std::vector<double> x, y;      ///< contact point (x(s_a), y(s_a)) [m]
  std::vector<double> s_a;       ///< arc length of the contact [m]
  std::vector<double> force;     ///< F [N]
  std::vector<double> phi_a;     ///< end slope [rad]
  std::size_t size() const { return x.size(); }
  bool empty() const { return x.empty(); }
  void clear();
  void push(const BeamShape& b);
};

/// Sampling of the contact sets.
struct ContactSetParams {
  double s_min_fraction = 0.2;  ///< contact sets start at s_a = 0.2 L (closer contacts saturate the sensor); choice
  double ds = 0.0005;           ///< s_a sampling step [m] (0.5 mm); choice, finer than the map's 1 mm
  int force_samples = 121;      ///< F samples over [-F_max, F_max] for the strip sensor (Model 2); choice
  double f_max = 0.5;           ///< F_max [N], load limit of Models 1-2 (002 Model 1); choice (~ phi_a = 1.4 at 35 mm)
  void validate() const;
};

/// Builds the contact-point sets of the four virtual sensors.
class VirtualSensors {
 public:
  VirtualSensors(const ElasticaSolver& solver, const ContactSetParams& params);
  /// Model 1, load sensor h_ls = F (eq. 6, 10-11): s_a over [s_min, L].
  ContactSet load(double force) const;
  /// Model 2, contact strip h_css = J_a (eq. 7, 12): F over [-F_max, F_max] at s_a.
  ContactSet strip(double s_a) const;
  /// Model 3, end slope h_es = phi_a (eq. 8, 13-14): s_a over [s_min, L].
  ContactSet end_slope(double phi_a) const;
  /// Model 4, base bending moment h_bms = M(0) (eq. 9, 16-17), large-angle
  /// model: s_a over [s_min, L], normal load with that base moment.
  ContactSet moment(double m0) const;
  /// Model 4, small-angle case (eq. 15): F = M(0) / s_a, shapes from the
  /// vertical-load elastica of eq. 1-2.
  ContactSet moment_small_angle(double m0) const;

  const ElasticaSolver& solver() const { return solver_; }
  const ContactSetParams& params() const { return params_; }

 private:
  std::vector<double> s_grid() const;
  const ElasticaSolver& solver_;
  ContactSetParams params_;
};

/// Intersection point of two contact sets.
struct SetIntersection {
  double x = 0.0, y = 0.0;  ///< point in the frame of the first set [m]
  double s_a = 0.0;         ///< interpolated arc length on the first set
  double force = 0.0;       ///< interpolated F on the first set
  double phi_a = 0.0;       ///< interpolated end slope on the first set
};

/// Intersections of polyline `a` with polyline `b` translated by (bx, by)
/// (spatial filtering eq. 19-20 with the sensors' offset, temporal filtering
/// eq. 21 with the base displacement). Segment-segment tests, like the
/// paper's polyxpoly.
std::vector<SetIntersection> intersect_sets(const ContactSet& a, const ContactSet& b, double bx = 0.0,
                                            double by = 0.0);

/// Result of one temporal-filter step.
struct ContactEstimate {
  enum class Status : uint8_t {
    kNoContact = 0,   ///< |M(0)| below the contact threshold
    kFirst = 1,       ///< first observation of a contact, no intersection yet
    kEstimated = 2,   ///< P_t and P_t+1 intersect: contact point estimated (eq. 21)
    kTipContact = 3,  ///< no intersection, |M(0)| above the tip threshold: contact at the tip
    kSlip = 4,        ///< no intersection below the tip threshold: contact lost or slipped
  };
  Status status = Status::kNoContact;
  double x = 0.0, y = 0.0;  ///< contact point in the current sensor frame [m]
  double s_a = 0.0, force = 0.0, phi_a = 0.0;
  std::size_t n_intersections = 0;
};

struct TemporalFilterParams {
  /// |M(0)| below this is no contact [N m]. Choice: 5x a 2e-7 N m Hall noise floor.
  double contact_threshold = 1e-6;
  /// |M(0)| above this with empty intersections is tip contact (002 Sec. VI-A:
  /// "sensor output exceeds a predefined threshold"). Choice: 0.05 mN m.
  double tip_threshold = 5e-5;
  void validate() const;
};

/// Single-whisker temporal filtering (002 eq. 21): intersect the moment-sensor
/// set of the previous observation with the current one moved by the known
/// base displacement. The first observation after no contact uses the
/// undeformed axis (M(0) = 0) as P_t, i.e. the whisker just touched.
class TemporalContactFilter {
 public:
  TemporalContactFilter(const VirtualSensors& sensors, const TemporalFilterParams& params);
  /// `m0` is the base moment after the base moved by (dx, dy) in the previous
  /// sensor frame (pure translation, 002 Sec. VI-A). The first call after
  /// reset() has no previous set and returns kFirst (or kNoContact).
  ContactEstimate update(double m0, double dx, double dy);
  /// Start from a known touch: previous set = undeformed axis (M(0) = 0).
  void start_from_touch();
  void reset();

 private:
  const VirtualSensors& sensors_;
  TemporalFilterParams params_;
  bool have_prev_ = false;
  ContactSet prev_;
};

/// Hall-sensor calibration B -> M(0) (002 Sec. V-B, Fig. 8a): least-squares
/// polynomial of degree `degree` fitted from calibration pairs (B_i, M_i).
class HallCalibration {
 public:
  /// Throws std::invalid_argument on mismatched sizes, too few pairs, non-finite values.
  static HallCalibration fit(const std::vector<double>& flux, const std::vector<double>& moment, int degree);
  double moment(double flux) const;
  const std::vector<double>& coefficients() const { return coeffs_; }  ///< c0 + c1 B + ...
  double rms_residual() const { return rms_; }

 private:
  std::vector<double> coeffs_;
  double rms_ = 0.0;
};

/// Obstacle profile by sweeping (002 Sec. VI-B): union of the estimated
/// contact points moved into the world frame by the known base pose.
class ProfileEstimator {
 public:
  /// Base pose (x, y, yaw) in the world; contact point in the sensor frame.
  void add(double base_x, double base_y, double base_yaw, double cx, double cy);
  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& y() const { return y_; }
  std::size_t size() const { return x_.size(); }

 private:
  std::vector<double> x_, y_;
};

}  // namespace whisker_localization
