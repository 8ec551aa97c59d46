// Gaussian Process Implicit Surface in the plane (paper 000, Methods "Corner
// penalty-based active perception in tactile mapping", eq. 31-40).
//
// Core layer: no ROS, no message types. Training points are 2D positions with
// labels 0 (on a surface, contact point) and -1 (interior, free space), as in
// 000 ("contour points are labeled as 0 and interior points as -1"). The GP
// has zero prior mean and the inverse-multiquadric kernel (000 eq. 33)
//   k(x, x') = (c^2 + |x - x'|^2)^(-beta).
// The posterior (000 eq. 34-35) uses the Cholesky factor L of K + sigma^2 I:
//   alpha = (K + sigma^2 I)^-1 y = L^-T L^-1 y,
//   mean(x*) = k*^T alpha,  var(x*) = k(x*, x*) - |L^-1 k*|^2.
// Points are added one at a time: the factor grows by one row (O(n^2)),
// never re-inverted (the ground-station budget of thousands of points relies
// on this); refactorize() recomputes it from scratch (O(n^3)) for checks.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace gpis_explorer {

/// Label of a training point (000 Methods: surface 0, interior -1).
constexpr double kSurfaceLabel = 0.0;
constexpr double kInteriorLabel = -1.0;

struct GpisParams {
  /// beta of the IMQ kernel (000 eq. 33; 0.5 in the public onboard code).
  double beta = 0.5;
  /// c of the IMQ kernel [m] (000 eq. 33; 1.0 in the public onboard code).
  double c = 1.0;
  /// sigma^2, observation noise variance added to K (000 eq. 34-35; 1e-2 in
  /// the public onboard code).
  double noise = 1e-2;
  /// Maximum number of training points. 50 is the onboard budget of 000
  /// (Supplementary "Memory usage": "a limit of 50 training data samples");
  /// the ground-station budget uses thousands.
  std::size_t max_points = 50;
  /// A point closer than this to a stored point with the same label is a
  /// duplicate and is not added [m] (workspace choice).
  double duplicate_tolerance = 1e-6;

  /// Throws std::invalid_argument "GpisParams.<field>: <reason>".
  void validate() const;
};

/// Result of Gpis::add_point().
enum class AddStatus : uint8_t {
  kAdded,        ///< stored, factor updated
  kDuplicate,    ///< same position and label as a stored point: skipped
  kBudgetFull,   ///< max_points reached: skipped
  kNonFinite,    ///< NaN/inf position: skipped
  kBadLabel,     ///< label not finite: skipped
  kNotPositive,  ///< the new pivot was not positive (numerically singular): skipped
};
const char* to_string(AddStatus s);

class Gpis {
 public:
  /// factorize = false: a store of the training points only (positions,
  /// labels, the same duplicate / budget / finiteness checks), no factor and
  /// no prediction (those throw std::logic_error). The explorer's local
  /// solver (local_gpis.hpp) keeps its points in one, so a ground-station
  /// budget never allocates the dense max_points^2 factor.
  explicit Gpis(const GpisParams& params, bool factorize = true);
  /// False for a store of points only (see the constructor).
  bool factorized() const { return factorize_; }

  /// Adds one training point and extends the Cholesky factor by one row
  /// (O(n^2)); alpha is recomputed by two triangular solves (O(n^2)).
  AddStatus add_point(const Eigen::Vector2d& x, double label);
  /// Replaces the training set by the columns of X with labels y and
  /// factorizes once (blocked Cholesky, O(n^3)). Points that add_point()
  /// would skip are skipped the same way; returns the number stored.
  std::size_t fit(const Eigen::Ref<const Eigen::Matrix2Xd>& X, const Eigen::Ref<const Eigen::VectorXd>& y);
  /// Removes the most recently added point (the factor loses its last row,
  /// O(n^2) for alpha). No effect when empty.
  void pop_back();
  /// Removes point i (the later points move up one index) and refactorizes
  /// (O(n^3)); out of range: no effect.
  void remove(std::size_t i);
  /// Recomputes the factor from the stored points (O(n^3)).
  void refactorize();
  /// Removes every point (keeps the allocated memory).
  void clear();

  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  std::size_t surface_count() const { return surface_count_; }
  const GpisParams& params() const { return p_; }
  Eigen::Vector2d point(std::size_t i) const { return X_.col(static_cast<Eigen::Index>(i)); }
  double label(std::size_t i) const { return y_(static_cast<Eigen::Index>(i)); }
  /// Lower Cholesky factor of K + sigma^2 I (n x n view).
  Eigen::Ref<const Eigen::MatrixXd> cholesky() const;
  /// (K + sigma^2 I)^-1 y.
  Eigen::Ref<const Eigen::VectorXd> alpha() const;

  /// IMQ kernel (000 eq. 33).
  double kernel(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// k(x, x) = c^(-2 beta): the prior variance.
  double prior_variance() const { return prior_var_; }

  /// Posterior mean (000 eq. 34). 0 (the prior) without points.
  double mean(const Eigen::Vector2d& x) const;
  /// Posterior mean and variance (000 eq. 34-35). Uses an internal work
  /// vector: not thread-safe, no allocation.
  void predict(const Eigen::Vector2d& x, double* mean, double* variance) const;
  /// Mean and variance at the columns of Q (2 x m), in blocks (Level-3
  /// triangular solve). mean and variance are resized to m.
  void predict_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean,
                     Eigen::VectorXd& variance) const;
  /// Mean only at the columns of Q (O(n m), no triangular solve).
  void mean_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean) const;
  /// K(i, j) = k(x_i, q_j) for the n training points and the columns of Q;
  /// K must be n x Q.cols() (000 eq. 33).
  void kernel_block(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::Ref<Eigen::MatrixXd> K) const;
  /// B := L^-1 B for B with n rows (blocked triangular solve; BLAS where built
  /// with OpenBLAS). |column of L^-1 K(X, q)|^2 is the variance reduction of eq. 35.
  void solve_lower(Eigen::Ref<Eigen::MatrixXd> B) const;
  /// Curvature (eq. 40) at the columns of Q in one pass over the points
  /// (same values as curvature() per point). kappa is resized to Q.cols().
  void curvature_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& kappa,
                       double min_gradient = 1e-9) const;
  /// Which linear algebra and kernel loops this build runs: "openblas" or
  /// "eigen", "+avx2" or "+baseline" (the kernel clone this CPU runs).
  static const char* backend();
  /// Gradient of the posterior mean (000 eq. 36-37, for general beta).
  Eigen::Vector2d gradient(const Eigen::Vector2d& x) const;
  /// Hessian of the posterior mean (000 eq. 38-39, for general beta).
  Eigen::Matrix2d hessian(const Eigen::Vector2d& x) const;
  /// Gradient and Hessian in one pass.
  void derivatives(const Eigen::Vector2d& x, Eigen::Vector2d* gradient, Eigen::Matrix2d* hessian) const;
  /// Curvature of the level set through x (000 eq. 40):
  ///   kappa = (g^T H g - |g|^2 tr(H)) / |g|^3.
  /// With interior -1 and surface 0 the mean grows outward, so the corner of a
  /// room seen from inside has kappa << 0 (a circle of radius R: -1/R).
  /// NaN where |g| < min_gradient (no defined level set).
  double curvature(const Eigen::Vector2d& x, double min_gradient = 1e-9) const;

  /// Bytes of state for n = max_points (points, labels, factor, alpha,
  /// work vector), as allocated.
  std::size_t state_bytes() const;

 private:
  /// s^-beta; 1/sqrt(s) for the default beta = 0.5 (no pow in the inner loops).
  double imq(double s) const { return half_beta_ ? 1.0 / std::sqrt(s) : std::pow(s, -p_.beta); }
  void ensure_capacity(std::size_t n);
  void solve_alpha();
  /// Throws std::logic_error naming `what` on a store of points only.
  void require_factor(const char* what) const;
  /// Training coordinates as two contiguous arrays (kernel loops).
  void split_points(std::vector<double>& xs, std::vector<double>& ys) const;

  GpisParams p_;
  bool factorize_ = true;
  double prior_var_ = 1.0;
  bool half_beta_ = true;
  std::size_t n_ = 0;
  std::size_t capacity_ = 0;
  std::size_t surface_count_ = 0;
  Eigen::Matrix2Xd X_;     ///< 2 x capacity
  Eigen::VectorXd y_;      ///< capacity
  Eigen::MatrixXd L_;      ///< capacity x capacity, lower n x n block used
  Eigen::VectorXd alpha_;  ///< capacity
  mutable Eigen::VectorXd work_;  ///< capacity
};

/// True if the points (columns) all lie within `tolerance` [m] of one line
/// (or there are fewer than 3 distinct points): the smallest principal
/// standard deviation is below tolerance.
bool points_collinear(const Eigen::Ref<const Eigen::Matrix2Xd>& points, double tolerance = 1e-3);

}  // namespace gpis_explorer
