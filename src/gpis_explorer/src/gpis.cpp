// GPIS core (000 eq. 33-40). See gpis.hpp.
#include "gpis_explorer/gpis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "imq_kernels.hpp"

#ifdef GPIS_EXPLORER_HAVE_OPENBLAS
#include <cblas.h>
extern "C" void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);  // LAPACK in OpenBLAS
#endif

namespace gpis_explorer {
namespace {

// Triangular solves and the Cholesky factorization with the lower factor L
// (column-major, leading dimension ld): OpenBLAS when built with it (runtime
// dispatch to the CPU's kernels), else Eigen's blocked routines.
using MapMat = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
using CMapMat = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

/// v := L^-1 v (trans false) or L^-T v (trans true).
void trsv_lower(const double* L, Eigen::Index ld, Eigen::Index n, double* v, bool trans) {
  if (n == 0) return;
#ifdef GPIS_EXPLORER_HAVE_OPENBLAS
  cblas_dtrsv(CblasColMajor, CblasLower, trans ? CblasTrans : CblasNoTrans, CblasNonUnit, static_cast<blasint>(n), L,
              static_cast<blasint>(ld), v, 1);
#else
  const CMapMat Lm(L, n, n, Eigen::OuterStride<>(ld));
  Eigen::Map<Eigen::VectorXd> x(v, n);
  if (trans) {
    Lm.triangularView<Eigen::Lower>().transpose().solveInPlace(x);
  } else {
    Lm.triangularView<Eigen::Lower>().solveInPlace(x);
  }
#endif
}

/// B := L^-1 B, B n x m with leading dimension ldb.
void trsm_lower(const double* L, Eigen::Index ld, Eigen::Index n, double* B, Eigen::Index ldb, Eigen::Index m) {
  if (n == 0 || m == 0) return;
#ifdef GPIS_EXPLORER_HAVE_OPENBLAS
  cblas_dtrsm(CblasColMajor, CblasLeft, CblasLower, CblasNoTrans, CblasNonUnit, static_cast<blasint>(n),
              static_cast<blasint>(m), 1.0, L, static_cast<blasint>(ld), B, static_cast<blasint>(ldb));
#else
  const CMapMat Lm(L, n, n, Eigen::OuterStride<>(ld));
  MapMat Bm(B, n, m, Eigen::OuterStride<>(ldb));
  Lm.triangularView<Eigen::Lower>().solveInPlace(Bm);
#endif
}

/// In place: the lower triangle of A (n x n, leading dimension ld) becomes its
/// Cholesky factor; the strict upper triangle is left alone. False if not PD.
bool potrf_lower(double* A, Eigen::Index ld, Eigen::Index n) {
#ifdef GPIS_EXPLORER_HAVE_OPENBLAS
  const int nn = static_cast<int>(n), lda = static_cast<int>(ld);
  int info = 0;
  dpotrf_("L", &nn, A, &lda, &info);
  return info == 0;
#else
  MapMat Am(A, n, n, Eigen::OuterStride<>(ld));
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(Am);  // in place, reads and writes the lower triangle
  return llt.info() == Eigen::Success;
#endif
}

[[noreturn]] void fail(const char* field, const std::string& reason) {
  throw std::invalid_argument(std::string("GpisParams.") + field + ": " + reason);
}

/// First allocation: the whole onboard budget, or a block that doubles.
constexpr std::size_t kInitialCapacity = 256;
/// Columns per block in predict_batch (bounds the work matrix to n x 512).
constexpr Eigen::Index kBatchColumns = 512;

}  // namespace

void GpisParams::validate() const {
  if (!(std::isfinite(beta) && beta > 0.0)) fail("beta", "must be > 0 (000 eq. 33), got " + std::to_string(beta));
  if (!(std::isfinite(c) && c > 0.0)) fail("c", "must be > 0 (000 eq. 33), got " + std::to_string(c));
  if (!(std::isfinite(noise) && noise > 0.0)) {
    fail("noise", "must be > 0 (keeps K + sigma^2 I positive definite), got " + std::to_string(noise));
  }
  if (max_points < 1) fail("max_points", "must be >= 1, got 0");
  if (max_points > 100000) {
    fail("max_points", "must be <= 100000 (dense factor of max_points^2 doubles), got " + std::to_string(max_points));
  }
  if (!(std::isfinite(duplicate_tolerance) && duplicate_tolerance >= 0.0)) {
    fail("duplicate_tolerance", "must be >= 0, got " + std::to_string(duplicate_tolerance));
  }
}

const char* to_string(AddStatus s) {
  switch (s) {
    case AddStatus::kAdded: return "added";
    case AddStatus::kDuplicate: return "duplicate";
    case AddStatus::kBudgetFull: return "budget_full";
    case AddStatus::kNonFinite: return "non_finite";
    case AddStatus::kBadLabel: return "bad_label";
    case AddStatus::kNotPositive: return "not_positive_definite";
  }
  return "unknown";
}

Gpis::Gpis(const GpisParams& params, bool factorize) : p_(params), factorize_(factorize) {
  p_.validate();
  half_beta_ = p_.beta == 0.5;
  prior_var_ = std::pow(p_.c * p_.c, -p_.beta);  // k(x, x), 000 eq. 33 with r = 0
  ensure_capacity(std::min(p_.max_points, kInitialCapacity));
}

void Gpis::ensure_capacity(std::size_t n) {
  if (n <= capacity_) return;
  std::size_t cap = std::max<std::size_t>(capacity_, 1);
  while (cap < n) cap *= 2;
  cap = std::min(std::max(cap, n), p_.max_points);
  const auto c = static_cast<Eigen::Index>(cap);
  const auto m = static_cast<Eigen::Index>(n_);
  Eigen::Matrix2Xd X(2, c);
  Eigen::VectorXd y(c), alpha(c);
  // A store of points only keeps no factor (0 x 0).
  Eigen::MatrixXd L = factorize_ ? Eigen::MatrixXd::Zero(c, c) : Eigen::MatrixXd();
  if (m > 0) {
    X.leftCols(m) = X_.leftCols(m);
    y.head(m) = y_.head(m);
    alpha.head(m) = alpha_.head(m);
    if (factorize_) L.topLeftCorner(m, m) = L_.topLeftCorner(m, m);
  }
  X_.swap(X);
  y_.swap(y);
  alpha_.swap(alpha);
  L_.swap(L);
  work_.resize(c);
  capacity_ = cap;
}

double Gpis::kernel(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  return imq(p_.c * p_.c + (a - b).squaredNorm());  // 000 eq. 33
}

AddStatus Gpis::add_point(const Eigen::Vector2d& x, double label) {
  if (!x.allFinite()) return AddStatus::kNonFinite;
  if (!std::isfinite(label)) return AddStatus::kBadLabel;
  const double tol2 = p_.duplicate_tolerance * p_.duplicate_tolerance;
  for (std::size_t i = 0; i < n_; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if ((X_.col(ii) - x).squaredNorm() <= tol2 && y_(ii) == label) return AddStatus::kDuplicate;
  }
  if (n_ >= p_.max_points) return AddStatus::kBudgetFull;
  ensure_capacity(n_ + 1);
  const auto n = static_cast<Eigen::Index>(n_);
  if (!factorize_) {
    X_.col(n) = x;
    y_(n) = label;
    ++n_;
    if (label == kSurfaceLabel) ++surface_count_;
    return AddStatus::kAdded;
  }
  // New row of the factor: L_{n,0:n} = L^-1 k(X, x), L_nn = sqrt(k(x,x) + sigma^2 - |l|^2).
  Eigen::VectorXd::SegmentReturnType l = work_.head(n);
  for (Eigen::Index i = 0; i < n; ++i) l(i) = kernel(X_.col(i), x);
  trsv_lower(L_.data(), L_.outerStride(), n, l.data(), false);
  const double pivot = prior_var_ + p_.noise - l.squaredNorm();
  if (!(pivot > 0.0) || !std::isfinite(pivot)) return AddStatus::kNotPositive;
  L_.row(n).head(n) = l.transpose();
  L_(n, n) = std::sqrt(pivot);
  X_.col(n) = x;
  y_(n) = label;
  ++n_;
  if (label == kSurfaceLabel) ++surface_count_;
  solve_alpha();
  return AddStatus::kAdded;
}

void Gpis::require_factor(const char* what) const {
  if (!factorize_) {
    throw std::logic_error(std::string("Gpis::") + what + ": this Gpis stores points only (built with factorize = false)");
  }
}

void Gpis::solve_alpha() {
  if (!factorize_) return;
  const auto n = static_cast<Eigen::Index>(n_);
  alpha_.head(n) = y_.head(n);
  trsv_lower(L_.data(), L_.outerStride(), n, alpha_.data(), false);
  trsv_lower(L_.data(), L_.outerStride(), n, alpha_.data(), true);
}

void Gpis::split_points(std::vector<double>& xs, std::vector<double>& ys) const {
  xs.resize(n_);
  ys.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    xs[i] = X_(0, static_cast<Eigen::Index>(i));
    ys[i] = X_(1, static_cast<Eigen::Index>(i));
  }
}

std::size_t Gpis::fit(const Eigen::Ref<const Eigen::Matrix2Xd>& X, const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (X.cols() != y.size()) {
    throw std::invalid_argument("Gpis::fit: " + std::to_string(X.cols()) + " points but " + std::to_string(y.size()) +
                                " labels");
  }
  clear();
  ensure_capacity(std::min<std::size_t>(static_cast<std::size_t>(X.cols()), p_.max_points));
  const double tol2 = p_.duplicate_tolerance * p_.duplicate_tolerance;
  for (Eigen::Index k = 0; k < X.cols() && n_ < p_.max_points; ++k) {
    if (!X.col(k).allFinite() || !std::isfinite(y(k))) continue;
    bool dup = false;
    for (std::size_t i = 0; i < n_ && !dup; ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      dup = (X_.col(ii) - X.col(k)).squaredNorm() <= tol2 && y_(ii) == y(k);
    }
    if (dup) continue;
    X_.col(static_cast<Eigen::Index>(n_)) = X.col(k);
    y_(static_cast<Eigen::Index>(n_)) = y(k);
    if (y(k) == kSurfaceLabel) ++surface_count_;
    ++n_;
  }
  refactorize();
  return n_;
}

void Gpis::pop_back() {
  if (n_ == 0) return;
  --n_;
  if (y_(static_cast<Eigen::Index>(n_)) == kSurfaceLabel) --surface_count_;
  solve_alpha();
}

void Gpis::refactorize() {
  const auto n = static_cast<Eigen::Index>(n_);
  if (n == 0 || !factorize_) return;
  // K + sigma^2 I into the factor's storage (lower triangle, column by column),
  // zeros above the diagonal, then the Cholesky factorization in place.
  const double c2 = p_.c * p_.c;
  std::vector<double> xs, ys;
  split_points(xs, ys);
  for (Eigen::Index j = 0; j < n; ++j) {
    double* col = &L_(0, j);
    for (Eigen::Index i = 0; i < j; ++i) col[i] = 0.0;
    if (half_beta_) {
      detail::imq_block(xs.data() + j, ys.data() + j, n - j, &xs[static_cast<std::size_t>(j)],
                        &ys[static_cast<std::size_t>(j)], 1, c2, col + j, n);
    } else {
      for (Eigen::Index i = j; i < n; ++i) col[i] = kernel(X_.col(i), X_.col(j));
    }
    col[j] += p_.noise;
  }
  if (!potrf_lower(L_.data(), L_.outerStride(), n)) {
    clear();
    throw std::runtime_error("Gpis::refactorize: K + sigma^2 I not positive definite");
  }
  solve_alpha();
}

void Gpis::remove(std::size_t i) {
  if (i >= n_) return;
  if (y_(static_cast<Eigen::Index>(i)) == kSurfaceLabel) --surface_count_;
  for (std::size_t k = i + 1; k < n_; ++k) {
    X_.col(static_cast<Eigen::Index>(k - 1)) = X_.col(static_cast<Eigen::Index>(k));
    y_(static_cast<Eigen::Index>(k - 1)) = y_(static_cast<Eigen::Index>(k));
  }
  --n_;
  refactorize();
}

void Gpis::clear() {
  n_ = 0;
  surface_count_ = 0;
}

Eigen::Ref<const Eigen::MatrixXd> Gpis::cholesky() const {
  require_factor("cholesky");
  const auto n = static_cast<Eigen::Index>(n_);
  return L_.topLeftCorner(n, n);
}

Eigen::Ref<const Eigen::VectorXd> Gpis::alpha() const {
  require_factor("alpha");
  return alpha_.head(static_cast<Eigen::Index>(n_));
}

double Gpis::mean(const Eigen::Vector2d& x) const {
  require_factor("mean");
  double m = 0.0;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(n_); ++i) m += kernel(X_.col(i), x) * alpha_(i);  // eq. 34
  return m;
}

void Gpis::predict(const Eigen::Vector2d& x, double* mean, double* variance) const {
  require_factor("predict");
  const auto n = static_cast<Eigen::Index>(n_);
  double m = 0.0;
  auto v = work_.head(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    v(i) = kernel(X_.col(i), x);
    m += v(i) * alpha_(i);  // 000 eq. 34
  }
  if (mean) *mean = m;
  if (variance) {
    trsv_lower(L_.data(), L_.outerStride(), n, v.data(), false);
    *variance = std::max(0.0, prior_var_ - v.squaredNorm());  // 000 eq. 35
  }
}

void Gpis::kernel_block(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::Ref<Eigen::MatrixXd> K) const {
  require_factor("kernel_block");
  const auto n = static_cast<Eigen::Index>(n_);
  if (K.rows() != n || K.cols() != Q.cols()) {
    throw std::invalid_argument("Gpis::kernel_block: K is " + std::to_string(K.rows()) + " x " +
                                std::to_string(K.cols()) + ", need " + std::to_string(n) + " x " +
                                std::to_string(Q.cols()));
  }
  if (n == 0 || Q.cols() == 0) return;
  const double c2 = p_.c * p_.c;
  if (half_beta_) {
    std::vector<double> xs, ys;
    split_points(xs, ys);
    const Eigen::VectorXd qx = Q.row(0).transpose(), qy = Q.row(1).transpose();
    detail::imq_block(xs.data(), ys.data(), n, qx.data(), qy.data(), Q.cols(), c2, K.data(), K.outerStride());
    return;
  }
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    const Eigen::Vector2d q = Q.col(j);
    for (Eigen::Index i = 0; i < n; ++i) K(i, j) = imq(c2 + (X_.col(i) - q).squaredNorm());  // 000 eq. 33
  }
}

void Gpis::solve_lower(Eigen::Ref<Eigen::MatrixXd> B) const {
  require_factor("solve_lower");
  const auto n = static_cast<Eigen::Index>(n_);
  if (B.rows() != n) {
    throw std::invalid_argument("Gpis::solve_lower: B has " + std::to_string(B.rows()) + " rows, need " +
                                std::to_string(n));
  }
  trsm_lower(L_.data(), L_.outerStride(), n, B.data(), B.outerStride(), B.cols());
}

void Gpis::predict_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean,
                         Eigen::VectorXd& variance) const {
  require_factor("predict_batch");
  const auto n = static_cast<Eigen::Index>(n_);
  const Eigen::Index m = Q.cols();
  mean.resize(m);
  variance.resize(m);
  if (n == 0) {
    mean.setZero();
    variance.setConstant(prior_var_);
    return;
  }
  const auto alpha = alpha_.head(n);
  Eigen::MatrixXd Ks(n, std::min(m, kBatchColumns));
  for (Eigen::Index start = 0; start < m; start += kBatchColumns) {
    const Eigen::Index b = std::min(kBatchColumns, m - start);
    auto block = Ks.leftCols(b);
    kernel_block(Q.middleCols(start, b), block);
    mean.segment(start, b).noalias() = block.transpose() * alpha;  // 000 eq. 34
    solve_lower(block);
    variance.segment(start, b) =
        (prior_var_ - block.colwise().squaredNorm().array()).max(0.0).matrix().transpose();  // 000 eq. 35
  }
}

void Gpis::mean_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& mean) const {
  require_factor("mean_batch");
  const auto n = static_cast<Eigen::Index>(n_);
  mean.setZero(Q.cols());
  const double c2 = p_.c * p_.c;
  if (half_beta_) {
    if (n == 0) return;
    std::vector<double> xs, ys;
    split_points(xs, ys);
    const Eigen::VectorXd qx = Q.row(0).transpose(), qy = Q.row(1).transpose();
    detail::imq_mean(xs.data(), ys.data(), alpha_.data(), n, qx.data(), qy.data(), Q.cols(), c2, mean.data());
    return;
  }
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    const double qx = Q(0, j), qy = Q(1, j);
    double m = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double dx = X_(0, i) - qx, dy = X_(1, i) - qy;
      m += imq(c2 + dx * dx + dy * dy) * alpha_(i);  // 000 eq. 34
    }
    mean(j) = m;
  }
}

void Gpis::curvature_batch(const Eigen::Ref<const Eigen::Matrix2Xd>& Q, Eigen::VectorXd& kappa,
                           double min_gradient) const {
  require_factor("curvature_batch");
  const Eigen::Index m = Q.cols();
  kappa.resize(m);
  if (!half_beta_) {
    for (Eigen::Index j = 0; j < m; ++j) kappa(j) = curvature(Q.col(j), min_gradient);
    return;
  }
  std::vector<double> xs, ys;
  split_points(xs, ys);
  const Eigen::VectorXd qx = Q.row(0).transpose(), qy = Q.row(1).transpose();
  Eigen::MatrixXd D(m, 5);
  detail::imq_derivatives(xs.data(), ys.data(), alpha_.data(), static_cast<Eigen::Index>(n_), qx.data(), qy.data(), m,
                          p_.c * p_.c, D.col(0).data(), D.col(1).data(), D.col(2).data(), D.col(3).data(),
                          D.col(4).data());
  for (Eigen::Index j = 0; j < m; ++j) {
    const Eigen::Vector2d g(D(j, 0), D(j, 1));
    Eigen::Matrix2d H;
    H << D(j, 2), D(j, 3), D(j, 3), D(j, 4);
    const double gn = g.norm();
    kappa(j) = (!(gn >= min_gradient) || gn == 0.0) ? std::numeric_limits<double>::quiet_NaN()
                                                      : (g.dot(H * g) - g.squaredNorm() * H.trace()) / (gn * gn * gn);  // 000 eq. 40
  }
}

const char* Gpis::backend() {
  const bool avx2 = std::string(detail::simd_dispatch()) == "avx2";
#ifdef GPIS_EXPLORER_HAVE_OPENBLAS
  return avx2 ? "openblas+avx2" : "openblas+baseline";
#else
  return avx2 ? "eigen+avx2" : "eigen+baseline";
#endif
}

void Gpis::derivatives(const Eigen::Vector2d& x, Eigen::Vector2d* gradient, Eigen::Matrix2d* hessian) const {
  require_factor("derivatives");
  // k = s^-beta, s = c^2 + |d|^2, d = x - x_i:
  //   dk/dx   = -2 beta s^(-beta-1) d                                   (000 eq. 37)
  //   d2k/dx2 = -2 beta s^(-beta-1) I + 4 beta (beta+1) s^(-beta-2) d d^T (000 eq. 39)
  // For beta = 1/2 these are -d s^-3/2 and s^-5/2 (3 d d^T - s I); 000 eq. 37
  // and 39 print a factor 2 and |d|^2 in place of s, which the finite-difference
  // tests reject (see README). The mean's derivatives are sum_i alpha_i dk_i
  // (000 eq. 36, 38).
  Eigen::Vector2d g = Eigen::Vector2d::Zero();
  Eigen::Matrix2d H = Eigen::Matrix2d::Zero();
  const double c2 = p_.c * p_.c;
  const double b = p_.beta;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(n_); ++i) {
    const Eigen::Vector2d d = x - X_.col(i);
    const double s = c2 + d.squaredNorm();
    const double s1 = half_beta_ ? 1.0 / (s * std::sqrt(s)) : std::pow(s, -b - 1.0);
    const double a = alpha_(i);
    g += (-2.0 * b * s1 * a) * d;
    if (hessian) {
      H += (4.0 * b * (b + 1.0) * s1 / s * a) * (d * d.transpose());
      H.diagonal().array() += -2.0 * b * s1 * a;
    }
  }
  if (gradient) *gradient = g;
  if (hessian) *hessian = H;
}

Eigen::Vector2d Gpis::gradient(const Eigen::Vector2d& x) const {
  Eigen::Vector2d g;
  derivatives(x, &g, nullptr);
  return g;
}

Eigen::Matrix2d Gpis::hessian(const Eigen::Vector2d& x) const {
  Eigen::Vector2d g;
  Eigen::Matrix2d H;
  derivatives(x, &g, &H);
  return H;
}

double Gpis::curvature(const Eigen::Vector2d& x, double min_gradient) const {
  Eigen::Vector2d g;
  Eigen::Matrix2d H;
  derivatives(x, &g, &H);
  const double gn = g.norm();
  if (!(gn >= min_gradient) || gn == 0.0) return std::numeric_limits<double>::quiet_NaN();
  return (g.dot(H * g) - g.squaredNorm() * H.trace()) / (gn * gn * gn);  // 000 eq. 40
}

std::size_t Gpis::state_bytes() const {
  const std::size_t n = p_.max_points;
  // points (2 doubles), label, alpha and work (1 double each), dense factor n^2.
  if (!factorize_) return sizeof(double) * (n * 2 + n);
  return sizeof(double) * (n * 2 + n + n + n + n * n);
}

bool points_collinear(const Eigen::Ref<const Eigen::Matrix2Xd>& points, double tolerance) {
  if (points.cols() < 3) return true;
  const Eigen::Vector2d mu = points.rowwise().mean();
  const Eigen::Matrix2Xd centred = points.colwise() - mu;
  const Eigen::Matrix2d cov = centred * centred.transpose() / static_cast<double>(points.cols());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  return std::sqrt(std::max(0.0, es.eigenvalues()(0))) < tolerance;
}

}  // namespace gpis_explorer
