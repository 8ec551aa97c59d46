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
  local.validate();
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

const char* to_string(GpisSolver s) {
  switch (s) {
    case GpisSolver::kExact: return "exact";
    case GpisSolver::kLocal: return "local";
  }
  return "unknown";
}

GpisSolver solver_from_string(const std::string& s) {
  if (s == "exact") return GpisSolver::kExact;
  if (s == "local") return GpisSolver::kLocal;
  throw std::invalid_argument("GPIS solver must be 'exact' or 'local', got '" + s + "'");
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

GpisExplorer::GpisExplorer(const ExplorerParams& params)
    : p_(params), gpis_((params.validate(), params.gpis), params.solver == GpisSolver::kExact) {
  if (p_.solver == GpisSolver::kLocal) local_ = std::make_unique<LocalGpis>(p_.gpis, p_.local);
  centre_grid(0.0, 0.0);
}

double GpisExplorer::mean(const Eigen::Vector2d& x) const { return local_ ? local_->mean(x) : gpis_.mean(x); }

Eigen::Vector2d GpisExplorer::gradient(const Eigen::Vector2d& x) const {
  return local_ ? local_->gradient(x) : gpis_.gradient(x);
}

void GpisExplorer::centre_grid(double x, double y) { set_grid(GridSpec::centred(x, y, p_.grid_size, p_.grid_cells)); }

void GpisExplorer::set_grid(const GridSpec& grid) {
  grid.validate();
  grid_ = grid;
  grid_fresh_ = false;
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
  interpolate_variance(cvar);
}

void GpisExplorer::interpolate_variance(const Eigen::VectorXd& cvar) {
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
  if (local_) {
    local_grid();  // the local GPs (LocalGpis), recomputed where they changed
  } else if (p_.grid_variance && !variance_cells_active()) {
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
    if (local_) {
      local_->curvature_batch(Pm, kappa);  // 000 eq. 40 of the blended mean
    } else {
      gpis_.curvature_batch(Pm, kappa);  // 000 eq. 40, one pass over the points
    }
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
  if (local_) {
    local_->predict_batch(cp, cmean, cvar);  // blended sigma^2 of the local GPs at every contour point
  } else {
    gpis_.predict_batch(cp, cmean, cvar);  // sigma^2 at every contour point (000 eq. 35), one blocked solve
  }
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

void GpisExplorer::local_grid() {
  if (gpis_.empty()) {  // the prior (000 eq. 34-35 without points), as the exact solver
    std::fill(mean_.begin(), mean_.end(), 0.0);
    std::fill(var_.begin(), var_.end(), p_.grid_variance ? gpis_.prior_variance() : std::numeric_limits<double>::quiet_NaN());
    local_->invalidate();
    grid_fresh_ = false;
    return;
  }
  const Eigen::Vector2d lo(grid_.origin_x, grid_.origin_y);
  const Eigen::AlignedBox2d cover(lo, grid_.node(grid_.width - 1, grid_.height - 1));
  const bool all = local_->sync(gpis_, cover) || !grid_fresh_;
  const auto& dirty = local_->dirty_boxes();
  // Grid nodes inside a changed local GP's box (one node of margin).
  std::vector<Eigen::Index> idx;
  if (all) {
    idx.resize(grid_.count());
    for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = static_cast<Eigen::Index>(k);
  } else {
    std::vector<char> mark(grid_.count(), 0);
    const double r = grid_.resolution;
    for (const auto& b : dirty) {
      const auto lo_i = static_cast<long>(std::floor((b.min().x() - grid_.origin_x) / r)) - 1;
      const auto hi_i = static_cast<long>(std::ceil((b.max().x() - grid_.origin_x) / r)) + 1;
      const auto lo_j = static_cast<long>(std::floor((b.min().y() - grid_.origin_y) / r)) - 1;
      const auto hi_j = static_cast<long>(std::ceil((b.max().y() - grid_.origin_y) / r)) + 1;
      for (long j = std::max(0L, lo_j); j <= std::min<long>(hi_j, grid_.height - 1); ++j) {
        for (long i = std::max(0L, lo_i); i <= std::min<long>(hi_i, grid_.width - 1); ++i) {
          mark[static_cast<std::size_t>(j) * grid_.width + static_cast<std::size_t>(i)] = 1;
        }
      }
    }
    for (std::size_t k = 0; k < mark.size(); ++k) {
      if (mark[k]) idx.push_back(static_cast<Eigen::Index>(k));
    }
  }
  Eigen::Matrix2Xd Q(2, static_cast<Eigen::Index>(idx.size()));
  for (std::size_t k = 0; k < idx.size(); ++k) Q.col(static_cast<Eigen::Index>(k)) = nodes_.col(idx[k]);
  local_->mean_batch(Q, mean_buf_);  // 000 eq. 34, blended
  for (std::size_t k = 0; k < idx.size(); ++k) mean_[static_cast<std::size_t>(idx[k])] = mean_buf_(static_cast<Eigen::Index>(k));
  if (!p_.grid_variance) {
    std::fill(var_.begin(), var_.end(), std::numeric_limits<double>::quiet_NaN());
  } else if (!variance_cells_active()) {
    Eigen::VectorXd m;
    local_->predict_batch(Q, m, var_buf_);  // 000 eq. 35, blended
    for (std::size_t k = 0; k < idx.size(); ++k) var_[static_cast<std::size_t>(idx[k])] = var_buf_(static_cast<Eigen::Index>(k));
  } else {
    // The variance-map nodes inside a changed box, then the picture's interpolation.
    const Eigen::Index m = vnodes_.cols();
    if (all || cvar_.size() != static_cast<std::size_t>(m)) cvar_.assign(static_cast<std::size_t>(m), 0.0);
    std::vector<Eigen::Index> vi;
    const Eigen::Vector2d pad = Eigen::Vector2d::Constant(grid_.resolution);
    for (Eigen::Index k = 0; k < m; ++k) {
      bool in = all;
      for (std::size_t b = 0; b < dirty.size() && !in; ++b) {
        in = Eigen::AlignedBox2d(dirty[b].min() - pad, dirty[b].max() + pad).contains(vnodes_.col(k));
      }
      if (in) vi.push_back(k);
    }
    Eigen::Matrix2Xd V(2, static_cast<Eigen::Index>(vi.size()));
    for (std::size_t k = 0; k < vi.size(); ++k) V.col(static_cast<Eigen::Index>(k)) = vnodes_.col(vi[k]);
    Eigen::VectorXd vm, vv;
    local_->predict_batch(V, vm, vv);
    for (std::size_t k = 0; k < vi.size(); ++k) cvar_[static_cast<std::size_t>(vi[k])] = vv(static_cast<Eigen::Index>(k));
    interpolate_variance(Eigen::Map<const Eigen::VectorXd>(cvar_.data(), m));
  }
  grid_fresh_ = true;
}

std::size_t GpisExplorer::state_bytes() const {
  if (local_) return gpis_.state_bytes() + local_->state_bytes() + sizeof(double) * (2 * grid_.count() + cvar_.size());
  const std::size_t vmap =
      variance_cells_active() ? gpis_.params().max_points * static_cast<std::size_t>(vnodes_.cols()) : 0;
  return gpis_.state_bytes() + sizeof(double) * (2 * grid_.count() + vmap);
}

}  // namespace gpis_explorer
