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
}

const UpdateResult& GpisExplorer::update() {
  ++updates_;
  UpdateResult& r = result_;
  r = UpdateResult{};
  if (p_.grid_variance) {
    gpis_.predict_batch(nodes_, mean_buf_, var_buf_);  // 000 eq. 34-35 on the grid
    for (std::size_t k = 0; k < mean_.size(); ++k) {
      mean_[k] = mean_buf_(static_cast<Eigen::Index>(k));
      var_[k] = var_buf_(static_cast<Eigen::Index>(k));
    }
  } else {
    gpis_.mean_batch(nodes_, mean_buf_);  // 000 eq. 34 on the grid
    for (std::size_t k = 0; k < mean_.size(); ++k) {
      mean_[k] = mean_buf_(static_cast<Eigen::Index>(k));
      var_[k] = std::numeric_limits<double>::quiet_NaN();
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
    info.curvature.resize(P.size());
    for (std::size_t i = 0; i < P.size(); ++i) info.curvature[i] = gpis_.curvature(P[i]);  // 000 eq. 40
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
  return gpis_.state_bytes() + sizeof(double) * 2 * grid_.count();
}

}  // namespace gpis_explorer
