// Corner penalty-based active perception (000 eq. 40-46). See explorer.hpp.
#include "gpis_explorer/explorer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace gpis_explorer {
namespace {
[[noreturn]] void fail(const char* field, const std::string& reason) {
  throw std::invalid_argument(std::string("ExplorerParams.") + field + ": " + reason);
}
}  // namespace

ExplorerParams ExplorerParams::onboard() { return ExplorerParams{}; }

ExplorerParams ExplorerParams::ground() {
  ExplorerParams p;
  p.gpis.max_points = 5000;
  p.grid_cells = 100;
  p.variance_cells = 40;
  return p;
}

void ExplorerParams::validate() const {
  gpis.validate();
  if (!(std::isfinite(grid_size) && grid_size > 0.0)) fail("grid_size", "must be > 0, got " + std::to_string(grid_size));
  if (grid_cells < 2 || grid_cells > 5000) {
    fail("grid_cells", "must be in [2, 5000], got " + std::to_string(grid_cells));
  }
  if (!(std::isfinite(corner_curvature) && corner_curvature < 0.0)) {
    fail("corner_curvature", "q must be < 0 (000 eq. 41), got " + std::to_string(corner_curvature));
  }
  if (!(std::isfinite(penalty_scale) && penalty_scale > 0.0)) {
    fail("penalty_scale", "must be > 0 (000 eq. 45), got " + std::to_string(penalty_scale));
  }
  if (!(std::isfinite(corner_exclusion) && corner_exclusion >= 0.0)) {
    fail("corner_exclusion", "must be >= 0, got " + std::to_string(corner_exclusion));
  }
  if (variance_cells == 1 || variance_cells > 5000) {
    fail("variance_cells", "must be 0 (every grid node) or in [2, 5000], got " + std::to_string(variance_cells));
  }
  if (!(std::isfinite(border_margin) && border_margin >= 0.0 && 2.0 * border_margin < grid_size)) {
    fail("border_margin", "must be >= 0 and < grid_size / 2, got " + std::to_string(border_margin));
  }
}

const char* to_string(UpdateStatus s) {
  switch (s) {
    case UpdateStatus::kOk: return "ok";
    case UpdateStatus::kNoPoints: return "no_points";
    case UpdateStatus::kNoSurfacePoints: return "no_surface_points";
    case UpdateStatus::kNoContour: return "no_contour";
    case UpdateStatus::kNoCandidate: return "no_candidate";
  }
  return "unknown";
}

std::vector<Eigen::Vector2d> cluster_corners(const std::vector<Eigen::Vector2d>& points,
                                             const std::vector<double>& curvature, bool closed, double q) {
  if (points.size() != curvature.size()) {
    throw std::invalid_argument("cluster_corners: " + std::to_string(points.size()) + " points but " +
                                std::to_string(curvature.size()) + " curvatures");
  }
  std::vector<Eigen::Vector2d> centroids;
  const std::size_t n = points.size();
  bool first_in_cluster = false, last_in_cluster = false;
  std::size_t i = 0;
  while (i < n) {
    if (!(curvature[i] < q)) {  // NaN is not a corner point
      ++i;
      continue;
    }
    // C_j = {p_i | kappa_i < q, i in [s_j, e_j]} (000 eq. 41)
    const std::size_t s = i;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    while (i < n && curvature[i] < q) sum += points[i++];
    if (s == 0) first_in_cluster = true;
    if (i == n) last_in_cluster = true;
    centroids.push_back(sum / static_cast<double>(i - s));  // 000 eq. 42
  }
  if (closed && first_in_cluster && last_in_cluster && centroids.size() >= 2) {
    // The run crosses the start of a closed contour: c'_m = (c_1 + c_m) / 2 (000 eq. 43).
    centroids.front() = 0.5 * (centroids.front() + centroids.back());
    centroids.pop_back();
  }
  return centroids;
}

double corner_penalty(const Eigen::Vector2d& x, const std::vector<Eigen::Vector2d>& corners, double c) {
  double p = 0.0;
  for (const auto& ck : corners) p = std::min(p, -std::exp(-(x - ck).squaredNorm() / (2.0 * c * c)));  // eq. 45
  return p;
}

GpisExplorer::GpisExplorer(const ExplorerParams& params) : p_(params), gpis_((params.validate(), params.gpis)) {
  centre_grid(0.0, 0.0);
}

void GpisExplorer::centre_grid(double x, double y) { set_grid(GridSpec::centred(x, y, p_.grid_size, p_.grid_cells)); }

void GpisExplorer::set_grid(const GridSpec& grid) {
  grid.validate();
  grid_ = grid;
  nodes_ = grid_.nodes();
  mean_.assign(grid_.count(), 0.0);
  var_.assign(grid_.count(), gpis_.prior_variance());
  vrows_ = 0;
  vw_ = std::min(p_.variance_cells, grid_.width);
  vh_ = std::min(p_.variance_cells, grid_.height);
  vnodes_.resize(2, variance_cells_active() ? static_cast<Eigen::Index>(vw_) * vh_ : 0);
  if (variance_cells_active()) {
    // Node (a, b) at the fractional grid index (a (W-1)/(vw-1), b (H-1)/(vh-1)): same extent as the grid.
    const double sx = (grid_.width - 1) * grid_.resolution / (vw_ - 1);
    const double sy = (grid_.height - 1) * grid_.resolution / (vh_ - 1);
    Eigen::Index k = 0;
    for (uint32_t b = 0; b < vh_; ++b) {
      for (uint32_t a = 0; a < vw_; ++a) vnodes_.col(k++) = Eigen::Vector2d(grid_.origin_x + a * sx, grid_.origin_y + b * sy);
    }
  }
}

void GpisExplorer::coarse_variance() {
  const auto n = static_cast<Eigen::Index>(gpis_.size());
  const Eigen::Index m = vnodes_.cols();
  Eigen::VectorXd cvar(m);
  if (n == 0) {
    cvar.setConstant(gpis_.prior_variance());
  } else {
    if (V_.rows() < n || V_.cols() != m) {
      // Room for the rows to come (doubling, at most the budget); valid rows kept.
      const Eigen::Index rows = std::min<Eigen::Index>(static_cast<Eigen::Index>(gpis_.params().max_points),
                                                       std::max<Eigen::Index>(n, 2 * V_.rows()));
      if (V_.cols() != m) {
        V_.resize(rows, m);
        vrows_ = 0;
      } else {
        V_.conservativeResize(rows, m);
      }
    }
    const auto r0 = static_cast<Eigen::Index>(std::min(vrows_, gpis_.size()));
    if (r0 == 0) {
      // From scratch: V = L^-1 k(X, Q) (000 eq. 35), one blocked solve.
      auto Vn = V_.topRows(n);
      gpis_.kernel_block(vnodes_, Vn);
      gpis_.solve_lower(Vn);
    } else if (r0 < n) {
      // Rows of the points added since the last update, by the rows of the
      // incremental factor: V_new = L_nn^-1 (k(X_new, Q) - L_no V_old).
      const Eigen::Index b = n - r0;
      const auto L = gpis_.cholesky();
      Eigen::MatrixXd B(b, m);
      for (Eigen::Index r = 0; r < b; ++r) {
        const Eigen::Vector2d x = gpis_.point(static_cast<std::size_t>(r0 + r));
        for (Eigen::Index q = 0; q < m; ++q) B(r, q) = gpis_.kernel(x, vnodes_.col(q));
      }
      B.noalias() -= L.block(r0, 0, b, r0) * V_.topRows(r0);
      L.block(r0, r0, b, b).triangularView<Eigen::Lower>().solveInPlace(B);
      V_.middleRows(r0, b) = B;
    }
    vrows_ = static_cast<std::size_t>(n);
    cvar = (gpis_.prior_variance() - V_.topRows(n).colwise().squaredNorm().array()).max(0.0).matrix().transpose();
  }
  // Bilinear interpolation onto the grid nodes (the picture only).
  const double fx = static_cast<double>(vw_ - 1) / (grid_.width - 1);
  const double fy = static_cast<double>(vh_ - 1) / (grid_.height - 1);
  for (uint32_t j = 0; j < grid_.height; ++j) {
    const double v = j * fy;
    const auto b = std::min<uint32_t>(static_cast<uint32_t>(v), vh_ - 2);
    const double tv = v - b;
    for (uint32_t i = 0; i < grid_.width; ++i) {
      const double u = i * fx;
      const auto a = std::min<uint32_t>(static_cast<uint32_t>(u), vw_ - 2);
      const double tu = u - a;
      const Eigen::Index k00 = static_cast<Eigen::Index>(b) * vw_ + a;
      const Eigen::Index k01 = k00 + static_cast<Eigen::Index>(vw_);
      var_[static_cast<std::size_t>(j) * grid_.width + i] =
          (1 - tv) * ((1 - tu) * cvar(k00) + tu * cvar(k00 + 1)) + tv * ((1 - tu) * cvar(k01) + tu * cvar(k01 + 1));
    }
  }
}

const UpdateResult& GpisExplorer::update() {
  ++updates_;
  UpdateResult& r = result_;
  r = UpdateResult{};
  if (p_.grid_variance && !variance_cells_active()) {
    gpis_.predict_batch(nodes_, mean_buf_, var_buf_);  // 000 eq. 34-35 on every grid node
    for (std::size_t k = 0; k < mean_.size(); ++k) {
      mean_[k] = mean_buf_(static_cast<Eigen::Index>(k));
      var_[k] = var_buf_(static_cast<Eigen::Index>(k));
    }
  } else {
    gpis_.mean_batch(nodes_, mean_buf_);  // 000 eq. 34 on the grid
    for (std::size_t k = 0; k < mean_.size(); ++k) mean_[k] = mean_buf_(static_cast<Eigen::Index>(k));
    if (p_.grid_variance) {
      coarse_variance();  // 000 eq. 35 on the variance map, interpolated (picture)
    } else {
      std::fill(var_.begin(), var_.end(), std::numeric_limits<double>::quiet_NaN());
    }
  }
  const std::size_t n = gpis_.size();
  if (n == 0) {
    r.status = UpdateStatus::kNoPoints;
    return r;
  }
  Eigen::Matrix2Xd pts(2, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) pts.col(static_cast<Eigen::Index>(i)) = gpis_.point(i);
  r.collinear = points_collinear(pts);
  if (gpis_.surface_count() == 0) {
    r.status = UpdateStatus::kNoSurfacePoints;
    return r;
  }
  std::vector<Contour> contours = marching_squares(grid_, mean_);
  if (contours.empty()) {
    r.status = UpdateStatus::kNoContour;
    return r;
  }
  for (auto& c : contours) {
    ContourInfo info;
    info.contour = std::move(c);
    const auto& P = info.contour.points;
    Eigen::Matrix2Xd Pm(2, static_cast<Eigen::Index>(P.size()));
    for (std::size_t i = 0; i < P.size(); ++i) Pm.col(static_cast<Eigen::Index>(i)) = P[i];
    Eigen::VectorXd kappa;
    gpis_.curvature_batch(Pm, kappa);  // 000 eq. 40, one pass over the points
    info.curvature.assign(kappa.data(), kappa.data() + kappa.size());
    auto corners = cluster_corners(P, info.curvature, info.contour.closed, p_.corner_curvature);
    r.corners.insert(r.corners.end(), corners.begin(), corners.end());
    (info.contour.closed ? r.closed_contours : r.open_contours)++;
    r.contours.push_back(std::move(info));
  }
  // Acquisition a~ = sigma^2 + P over every contour point (000 eq. 44-46).
  const double excl2 = p_.corner_exclusion * p_.corner_exclusion;
  const double lo_x = grid_.origin_x + p_.border_margin, lo_y = grid_.origin_y + p_.border_margin;
  const double hi_x = grid_.origin_x + (grid_.width - 1) * grid_.resolution - p_.border_margin;
  const double hi_y = grid_.origin_y + (grid_.height - 1) * grid_.resolution - p_.border_margin;
  double best = -std::numeric_limits<double>::infinity();
  std::size_t total = 0;
  for (const auto& info : r.contours) total += info.contour.points.size();
  Eigen::Matrix2Xd cp(2, static_cast<Eigen::Index>(total));
  Eigen::Index col = 0;
  for (const auto& info : r.contours) {
    for (const auto& q : info.contour.points) cp.col(col++) = q;
  }
  Eigen::VectorXd cmean, cvar;
  gpis_.predict_batch(cp, cmean, cvar);  // sigma^2 at every contour point (000 eq. 35), one blocked solve
  col = 0;
  for (auto& info : r.contours) {
    const auto& P = info.contour.points;
    info.variance.resize(P.size());
    info.acquisition.resize(P.size());
    for (std::size_t i = 0; i < P.size(); ++i) {
      const double var = cvar(col++);
      info.variance[i] = var;                                                          // 000 eq. 44
      info.acquisition[i] = var + corner_penalty(P[i], r.corners, p_.penalty_scale);  // 000 eq. 46
      bool excluded = P[i].x() < lo_x || P[i].x() > hi_x || P[i].y() < lo_y || P[i].y() > hi_y;
      for (const auto& ck : r.corners) excluded = excluded || (P[i] - ck).squaredNorm() < excl2;
      if (!excluded && info.acquisition[i] > best) {
        best = info.acquisition[i];
        r.has_target = true;
        r.target = P[i];
        r.target_acquisition = info.acquisition[i];
        r.target_variance = var;
      }
    }
  }
  r.status = r.has_target ? UpdateStatus::kOk : UpdateStatus::kNoCandidate;
  return r;
}

std::size_t GpisExplorer::state_bytes() const {
  const std::size_t vmap =
      variance_cells_active() ? gpis_.params().max_points * static_cast<std::size_t>(vnodes_.cols()) : 0;
  return gpis_.state_bytes() + sizeof(double) * (2 * grid_.count() + vmap);
}

}  // namespace gpis_explorer
