// Preimage localization in a known planar map (002 Sec. IV-D, VII, eq. 22-25):
// the map's boundary polylines discretised at 1 mm; the whisker shape of an
// observation aligned with every boundary point (eq. 22) gives the possible
// robot poses; forward projection with the known motion (Sec. IV-D) and
// intersection with the next preimage shrink the set. Deterministic and
// possibilistic (bounded observation error epsilon, eq. 23-25) variants.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "whisker_localization/elastica.hpp"

namespace whisker_localization {

struct Pose2 {
  double x = 0.0, y = 0.0, theta = 0.0;
};

/// Pose composition a * b (b expressed in a's frame): the motion model
/// T'_k = T_k T_local of 002 Sec. IV-D.
Pose2 compose(const Pose2& a, const Pose2& b);
/// Angle wrapped to (-pi, pi].
double wrap_angle(double a);

/// Known map: boundary polylines, free space on the LEFT of each polyline's
/// direction (e.g. counter-clockwise around a room's inside is wrong: walk a
/// room clockwise, an obstacle counter-clockwise). Discretised at `spacing`.
class BoundaryMap {
 public:
  /// Throws std::invalid_argument naming the polyline and point on bad input
  /// (fewer than 2 points, non-finite, zero-length, spacing <= 0).
  BoundaryMap(const std::vector<std::vector<std::array<double, 2>>>& polylines, double spacing = 0.001);

  std::size_t size() const { return x_.size(); }
  double spacing() const { return spacing_; }
  /// Discretised boundary point k, its tangent angle (polyline direction) and polyline id.
  double x(std::size_t k) const { return x_[k]; }
  double y(std::size_t k) const { return y_[k]; }
  double tangent(std::size_t k) const { return tangent_[k]; }
  /// Total boundary length [m].
  double length() const { return length_; }
  /// Signed distance of (px, py) to the boundary: > 0 on the free (left)
  /// side of the nearest segment. Also returns the nearest point and the
  /// segment's tangent angle.
  double signed_distance(double px, double py, double* nx = nullptr, double* ny = nullptr,
                         double* tangent = nullptr) const;
  const std::vector<std::vector<std::array<double, 2>>>& polylines() const { return polylines_; }

 private:
  std::vector<std::vector<std::array<double, 2>>> polylines_;
  double spacing_;
  double length_ = 0.0;
  std::vector<double> x_, y_, tangent_;
  // Uniform grid of segment indices for signed_distance (cell = grid_cell_).
  struct Seg {
    double ax, ay, bx, by;
  };
  std::vector<Seg> segs_;
  double grid_cell_ = 0.005;
  double gx0_ = 0.0, gy0_ = 0.0;
  int gnx_ = 1, gny_ = 1;
  std::vector<std::vector<uint32_t>> grid_;
};

/// One observation turned into whisker geometry (002 Sec. VII-A): the
/// contact point in the robot (= sensor) frame and the boundary tangent at
/// the contact in the robot frame (oriented with free space on its left).
struct ContactGeometry {
  double cx = 0.0, cy = 0.0;  ///< contact point (x(s_a), y(s_a)) [m]
  double tangent = 0.0;       ///< boundary tangent angle phi_E in the robot frame [rad]
};

/// The set of possible robot poses (Q_t), discretised.
struct PoseSet {
  std::vector<Pose2> poses;
  std::size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
};

/// Preimage of a contact geometry (002 eq. 22): align the contact with every
/// boundary point k so the boundary tangent is preserved,
///   theta_k = beta_k - phi_E,  (x, y)_k = b_k - R(theta_k) c,
/// keeping poses whose base is on the free side by at least `min_clearance`.
void preimage(const BoundaryMap& map, const ContactGeometry& g, double min_clearance, PoseSet& out);

struct LocalizerParams {
  /// The observed contact point placed by a forward-projected pose must lie
  /// this close to the map boundary [m]. Choice: 0.3 mm (best of 0.2-0.5 mm in the Table II SITL).
  double contact_tolerance = 0.0003;
  /// Boundary-slope tolerance of the set intersection [rad]. Choice: 3 deg.
  double match_angle = 0.0524;
  /// Possibilistic bound epsilon as a fraction of the observation (002 eq. 24: 5 %).
  double epsilon = 0.05;
  /// Samples across [z (1 - eps), z (1 + eps)] and across the phi_E bounds
  /// (possibilistic; the preimage is the union of n x n aligned shapes). Choice.
  int epsilon_samples = 5;
  bool possibilistic = false;  ///< false: deterministic (002 Sec. VII-B), true: eq. 23-25
  /// Contact points used to estimate the boundary slope phi_E (002 Sec. VII-A: 2 to 5).
  int slope_samples = 5;
  /// Base must be at least this far on the free side of the boundary [m]. Choice.
  double min_clearance = 0.002;
  /// Heading hypotheses per aligned pose when a set is (re)built: rotations
  /// about the contact point over +-heading_spread (absorbs the error of the
  /// phi_E estimate, which the intersection then resolves). Choice.
  int heading_samples = 13;
  double heading_spread = 0.03;  ///< [rad]; choice (about 3 sigma of phi_E at 0.5 % noise)
  /// Only poses within this distance of the prior (the sweep's known start,
  /// 002 Sec. VII-D) start the set [m]; <= 0: the whole map. Choice: 30 mm.
  double prior_radius = 0.03;
  /// Neighbourhood of the mode used as the best estimate [m]. Choice: 2 mm.
  double mode_radius = 0.002;
  /// Shape refinement passes (force direction along the estimated boundary normal). Choice.
  int refine_passes = 2;
  void validate() const;
};

/// Preimage localizer for tip contact (002 Sec. VII, Table II).
class PreimageLocalizer {
 public:
  PreimageLocalizer(const BoundaryMap& map, const ElasticaSolver& solver, const LocalizerParams& params);

  struct StepResult {
    bool contact = false;       ///< the observation was a usable tip contact
    bool localizing = false;    ///< enough history to build preimages (>= 3 observations)
    bool reset = false;         ///< the intersection was empty: restarted from the new preimage
    std::size_t preimage_size = 0;  ///< size of the preimage when the set was (re)built this step, else 0
    std::size_t set_size = 0;
    Pose2 best;                 ///< mean pose of the set
    double spread = 0.0;        ///< max distance of the set from `best` [m]
    ContactGeometry geometry;   ///< contact point and phi_E of this observation
  };

  /// One step: the base moved by `motion` (in the previous robot frame) and
  /// the base moment `m0` was observed, contact at the tip.
  StepResult step(const Pose2& motion, double m0);
  void reset();
  /// Known start location (002 Sec. VII-D: each sweep starts at a known
  /// location); used with prior_radius when the set is built.
  void set_prior(const Pose2& prior) {
    prior_ = prior;
    have_prior_ = true;
  }

  const PoseSet& set() const { return set_; }
  /// Accumulated squared residual of each pose of set() (same order): the
  /// observations' consistency with the pose since the set was built.
  const std::vector<double>& costs() const { return cost_; }
  const LocalizerParams& params() const { return params_; }
  uint64_t resets() const { return resets_; }

  /// Tip-contact geometry of a moment with the force along `direction` in
  /// the sensor frame (NaN direction: normal to the whisker, Elastica2D).
  BeamShape tip_shape(double m0, double direction) const;

 private:
  bool geometry_for(double m0, ContactGeometry& g);
  void tangent_bounds(double tangent, double& lo, double& hi);
  const BoundaryMap& map_;
  const ElasticaSolver& solver_;
  LocalizerParams params_;
  PoseSet set_;
  PoseSet obs_;
  PoseSet tmp_;
  /// Accumulated squared residual of each pose of set_ over the observations
  /// it was tested against (same order as set_.poses).
  std::vector<double> cost_, tmp_cost_;
  struct Cand {
    double cx, cy, tangent, tangent_halfwidth;
  };
  std::vector<Cand> cands_;  ///< observed contact geometries (several: possibilistic)
  /// Oldest contact of the slope history in the current robot frame: the
  /// slope phi_E is a chord over the history, compared with the map's chord
  /// between the same two contacts (no lag where the curvature changes).
  double chord_ox_ = 0.0, chord_oy_ = 0.0;
  bool have_set_ = false;
  Pose2 prior_;
  bool have_prior_ = false;
  void seed_set();
  void build_preimage(double m0, const ContactGeometry& g);
  uint64_t resets_ = 0;
  /// Recent contact points in the robot frame of their time and the motions between.
  struct Hist {
    double m0;
    Pose2 motion;  ///< motion from the previous observation to this one
    double cx, cy;
  };
  std::deque<Hist> hist_;
  double last_tangent_ = 0.0;
  bool have_tangent_ = false;
};

/// Mean pose (circular mean heading) and max distance of the set from it.
Pose2 mean_pose(const PoseSet& s, double* spread);
/// Best estimate of a set that may hold several clusters: the mean of the
/// poses within `radius` of the pose with the most such neighbours (a mode;
/// the plain mean for sets larger than 2000). `spread` as in mean_pose, from
/// the returned pose.
Pose2 best_pose(const PoseSet& s, double radius, double* spread);
/// Best estimate from the poses' accumulated residuals: the mean of the
/// poses within `radius` of the least-cost pose (falls back to the densest
/// mode when `cost` does not match the set).
Pose2 best_pose(const PoseSet& s, const std::vector<double>& cost, double radius, double* spread);

}  // namespace whisker_localization
