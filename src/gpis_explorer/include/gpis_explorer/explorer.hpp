// Corner penalty-based active perception (paper 000, Methods eq. 40-46 and
// Supplementary Fig. S4f): GPIS on a grid -> zero contour by marching squares
// -> curvature of each contour point (eq. 40) -> clusters of high negative
// curvature and their centroids (eq. 41-43) -> repulsive corner potential
// (eq. 45) -> penalised acquisition a~ = sigma^2 + P (eq. 44, 46) -> next
// target = contour point with the highest a~.
#pragma once

#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gpis_explorer/contour.hpp"
#include "gpis_explorer/gpis.hpp"
#include "gpis_explorer/local_gpis.hpp"

namespace gpis_explorer {

/// Which GP computes the map (ExplorerParams::solver).
enum class GpisSolver : uint8_t {
  kExact,  ///< one GP over every point (000 eq. 33-40): the onboard budget and the reference
  kLocal,  ///< local GPs over a quadtree, blended (local_gpis.hpp): ground-station scale
};
const char* to_string(GpisSolver s);
/// "exact" / "local"; throws std::invalid_argument naming the value otherwise.
GpisSolver solver_from_string(const std::string& s);

struct ExplorerParams {
  GpisParams gpis;
  /// Grid of the GPIS prediction: grid_cells x grid_cells nodes over
  /// grid_size x grid_size metres (000 Supplementary "Memory usage" and Results:
  /// 10 x 10 onboard; the 4 m side is our choice, twice the 2 m room).
  double grid_size = 4.0;
  uint32_t grid_cells = 10;
  /// q, curvature threshold of a corner point, kappa < q < 0 (000 eq. 41;
  /// -1.0 our value: a radius of curvature below 1 m).
  double corner_curvature = -1.0;
  /// c of the corner potential P (000 eq. 45) [m]: 0.2 m.
  double penalty_scale = 0.2;
  /// Candidate targets closer than this to a corner centroid are never chosen
  /// (the drone never flies into a penalised corner) [m]. Workspace choice:
  /// equal to penalty_scale (P < -exp(-1/2) there).
  double corner_exclusion = 0.2;
  /// Candidate targets are at least this far inside the grid border [m]
  /// (open contours end on the border, where the grid cut them, not at a
  /// surface). Workspace choice.
  double border_margin = 0.0;
  /// Predict the variance on the whole grid (the uncertainty map of 000
  /// Fig. 5). The target needs the variance on the contour points only; off,
  /// the grid variance is left at NaN and an update costs O(n m) instead of
  /// O(n^2 m) for n points and m grid nodes.
  bool grid_variance = true;
  /// Nodes per side of the variance map (the picture's uncertainty layer).
  /// 0: the variance on every grid node, one triangular solve per update
  /// (O(n^2 m)). k > 0 (and below grid_cells): the variance on k x k nodes
  /// spanning the grid, bilinearly interpolated to the grid nodes; its
  /// L^-1 k(X, q) is kept between updates and extended by the rows of the
  /// points added since (the incremental Cholesky rows, O(n k^2) per point;
  /// memory max_points x k^2 doubles). The target uses the exact variance at
  /// the contour points either way (000 eq. 44-46). Workspace choice.
  uint32_t variance_cells = 0;
  /// The GP behind the map: kExact (default; the paper's GPIS, O(n^2) per
  /// added point, O(n m) per grid of m nodes) or kLocal (local GPs over a
  /// quadtree with overlap blending after GPisMap, Lee et al. ICRA 2019;
  /// parameters in `local`; an approximation whose error against the exact
  /// GP is bounded in the README, "Local solver"). While every point fits in
  /// one leaf (local.leaf_points) the local solver is the exact GP.
  GpisSolver solver = GpisSolver::kExact;
  LocalGpisParams local;

  /// The onboard budget of 000: 50 points, 10 x 10 grid over 4 m.
  static ExplorerParams onboard();
  /// The ground-station budget: 5000 points, 100 x 100 grid over 4 m,
  /// a 40 x 40 variance map.
  static ExplorerParams ground();
  /// Throws std::invalid_argument "ExplorerParams.<field>: <reason>".
  void validate() const;
};

/// Outcome of one GPIS update (degenerate inputs are statuses, not errors).
enum class UpdateStatus : uint8_t {
  kOk,               ///< contours, corners and a target
  kNoPoints,         ///< no training point at all: prior only
  kNoSurfacePoints,  ///< no surface point (open space, no contact): the mean
                     ///< has no zero level set to follow
  kNoContour,        ///< surface points, but the zero level set misses the grid
  kNoCandidate,      ///< contours, but every point is excluded (corner / border)
};
const char* to_string(UpdateStatus s);

/// A contour with its per-point curvature (000 eq. 40) and acquisition (eq. 46).
struct ContourInfo {
  Contour contour;
  std::vector<double> curvature;    ///< NaN where the gradient vanishes
  std::vector<double> variance;     ///< sigma^2 (000 eq. 35, 44)
  std::vector<double> acquisition;  ///< a~ = sigma^2 + P (000 eq. 46)
};

struct UpdateResult {
  UpdateStatus status = UpdateStatus::kNoPoints;
  std::vector<ContourInfo> contours;
  std::vector<Eigen::Vector2d> corners;  ///< corner centroids (000 eq. 42-43)
  bool has_target = false;
  Eigen::Vector2d target = Eigen::Vector2d::Zero();
  double target_acquisition = 0.0;
  double target_variance = 0.0;
  std::size_t open_contours = 0;
  std::size_t closed_contours = 0;
  bool collinear = false;  ///< all training points on one line (still fitted)
};

/// High-curvature clustering of one ordered contour (000 eq. 41-43): runs of
/// consecutive points with kappa < q form clusters C_j; each yields its
/// centroid c_j (eq. 42). For a closed contour whose first and last points are
/// both in (different) clusters, the run wraps around: the two centroids are
/// merged by averaging them (eq. 43). NaN curvature ends a run.
std::vector<Eigen::Vector2d> cluster_corners(const std::vector<Eigen::Vector2d>& points,
                                             const std::vector<double>& curvature, bool closed, double q);

/// Corner potential (000 eq. 45): P(x) = min_k(-exp(-|x - c_k|^2 / (2 c^2))),
/// 0 without corners.
double corner_penalty(const Eigen::Vector2d& x, const std::vector<Eigen::Vector2d>& corners, double c);

/// The GPIS explorer: training set, grid prediction and target selection.
class GpisExplorer {
 public:
  explicit GpisExplorer(const ExplorerParams& params);

  /// Adds a training point (incremental Cholesky update; local solver: the
  /// point is stored, the local GPs take it at the next update()).
  AddStatus add_point(const Eigen::Vector2d& x, double label) { return gpis_.add_point(x, label); }
  /// Replaces the training set and factorizes once (Gpis::fit).
  std::size_t fit(const Eigen::Ref<const Eigen::Matrix2Xd>& X, const Eigen::Ref<const Eigen::VectorXd>& y) {
    vrows_ = 0;
    if (local_) local_->invalidate();
    return gpis_.fit(X, y);
  }
  void pop_back() {
    gpis_.pop_back();
    vrows_ = std::min(vrows_, gpis_.size());
    if (local_) local_->invalidate();
  }
  void remove(std::size_t i) {
    vrows_ = 0;
    if (local_) local_->invalidate();
    gpis_.remove(i);
  }
  void refactorize() {
    vrows_ = 0;
    if (local_) local_->invalidate();
    gpis_.refactorize();
  }
  void clear() {
    vrows_ = 0;
    if (local_) local_->invalidate();
    gpis_.clear();
  }
  /// Posterior mean and its gradient at x from the chosen solver (000 eq. 34,
  /// 36-37); the local solver answers from the last update()'s local GPs
  /// (NaN outside them).
  double mean(const Eigen::Vector2d& x) const;
  Eigen::Vector2d gradient(const Eigen::Vector2d& x) const;
  /// The local solver (null for kExact).
  const LocalGpis* local() const { return local_.get(); }
  /// Centres the prediction grid on (x, y) (grid_size, grid_cells unchanged).
  void centre_grid(double x, double y);
  void set_grid(const GridSpec& grid);

  /// Predicts the grid, extracts contours, curvature, corners and the target.
  const UpdateResult& update();

  /// The training points; with the exact solver also the GP itself (with
  /// the local solver a store of points only: Gpis::factorized() false).
  const Gpis& gpis() const { return gpis_; }
  const GridSpec& grid() const { return grid_; }
  const std::vector<double>& grid_mean() const { return mean_; }
  const std::vector<double>& grid_variance() const { return var_; }
  const UpdateResult& last() const { return result_; }
  std::size_t updates() const { return updates_; }
  const ExplorerParams& params() const { return p_; }
  /// Nodes of the variance map (all grid nodes when variance_cells is 0).
  const Eigen::Matrix2Xd& variance_nodes() const { return variance_cells_active() ? vnodes_ : nodes_; }
  /// State of the onboard-budget representation: GPIS (points, labels,
  /// factor, alpha, work) + grid mean and variance [bytes], for max_points.
  std::size_t state_bytes() const;

 private:
  bool variance_cells_active() const {
    return p_.variance_cells > 0 && (p_.variance_cells < grid_.width || p_.variance_cells < grid_.height);
  }
  /// Extends (or recomputes) V = L^-1 k(X, vnodes_) to the current points and
  /// interpolates the coarse variance map onto var_.
  void coarse_variance();
  /// The grid mean and variance from the local GPs, recomputed only where
  /// the last LocalGpis::sync() changed a local GP.
  void local_grid();
  /// Bilinear interpolation of the variance-map values onto var_ (picture).
  void interpolate_variance(const Eigen::VectorXd& cvar);

  ExplorerParams p_;
  Gpis gpis_;
  Eigen::Matrix2Xd vnodes_;   ///< variance-map nodes (variance_cells^2), row-major
  uint32_t vw_ = 0, vh_ = 0;  ///< variance-map nodes per row / column
  Eigen::MatrixXd V_;         ///< rows: points (first vrows_ valid), cols: vnodes_
  std::size_t vrows_ = 0;
  GridSpec grid_;
  Eigen::Matrix2Xd nodes_;
  std::vector<double> mean_, var_;
  Eigen::VectorXd mean_buf_, var_buf_;
  UpdateResult result_;
  std::size_t updates_ = 0;
  std::unique_ptr<LocalGpis> local_;  ///< kLocal only
  bool grid_fresh_ = false;           ///< local: mean_/var_ hold the last update's values on this grid
  std::vector<double> cvar_;          ///< local: variance on the variance-map nodes
};

}  // namespace gpis_explorer
