#include "whisker_localization/preimage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace whisker_localization {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

double wrap_angle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a <= 0.0) a += 2.0 * kPi;
  return a - kPi;
}

Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return Pose2{a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap_angle(a.theta + b.theta)};
}

BoundaryMap::BoundaryMap(const std::vector<std::vector<std::array<double, 2>>>& polylines, double spacing)
    : polylines_(polylines), spacing_(spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument("BoundaryMap.spacing: must be finite and > 0, got " + std::to_string(spacing));
  if (polylines.empty()) throw std::invalid_argument("BoundaryMap.polylines: must not be empty");
  for (std::size_t p = 0; p < polylines.size(); ++p) {
    const auto& pl = polylines[p];
    const std::string where = "BoundaryMap.polylines[" + std::to_string(p) + "]";
    if (pl.size() < 2) throw std::invalid_argument(where + ": needs >= 2 points, got " + std::to_string(pl.size()));
    for (std::size_t i = 0; i < pl.size(); ++i) {
      if (!std::isfinite(pl[i][0]) || !std::isfinite(pl[i][1]))
        throw std::invalid_argument(where + "[" + std::to_string(i) + "]: not finite");
      if (i > 0 && pl[i][0] == pl[i - 1][0] && pl[i][1] == pl[i - 1][1])
        throw std::invalid_argument(where + "[" + std::to_string(i) + "]: repeats the previous point (zero-length segment)");
    }
    // Resample at `spacing` along the arc length (002 Sec. VII-B: 1 mm points).
    std::vector<double> cum(pl.size(), 0.0);
    for (std::size_t i = 1; i < pl.size(); ++i)
      cum[i] = cum[i - 1] + std::hypot(pl[i][0] - pl[i - 1][0], pl[i][1] - pl[i - 1][1]);
    const double total = cum.back();
    length_ += total;
    const int n = std::max(2, static_cast<int>(std::floor(total / spacing)) + 1);
    std::size_t seg = 0;
    const std::size_t first = x_.size();
    for (int k = 0; k < n; ++k) {
      const double s = std::min(total, k * spacing);
      while (seg + 2 < pl.size() && cum[seg + 1] < s) ++seg;
      const double len = cum[seg + 1] - cum[seg];
      const double t = (s - cum[seg]) / len;
      x_.push_back(pl[seg][0] + t * (pl[seg + 1][0] - pl[seg][0]));
      y_.push_back(pl[seg][1] + t * (pl[seg + 1][1] - pl[seg][1]));
    }
    for (std::size_t i = 0; i + 1 < pl.size(); ++i) segs_.push_back(Seg{pl[i][0], pl[i][1], pl[i + 1][0], pl[i + 1][1]});
    // Tangent by central differences of the discretised points (one-sided at the ends).
    const std::size_t last = x_.size() - 1;
    for (std::size_t k = first; k <= last; ++k) {
      const std::size_t a = k == first ? k : k - 1, b = k == last ? k : k + 1;
      tangent_.push_back(std::atan2(y_[b] - y_[a], x_[b] - x_[a]));
    }
  }
  // Segment grid: every cell a segment's bounding box touches.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& g : segs_) {
    x0 = std::min({x0, g.ax, g.bx});
    y0 = std::min({y0, g.ay, g.by});
    x1 = std::max({x1, g.ax, g.bx});
    y1 = std::max({y1, g.ay, g.by});
  }
  gx0_ = x0;
  gy0_ = y0;
  gnx_ = std::min(4096, static_cast<int>(std::floor((x1 - x0) / grid_cell_)) + 1);
  gny_ = std::min(4096, static_cast<int>(std::floor((y1 - y0) / grid_cell_)) + 1);
  grid_cell_ = std::max({grid_cell_, (x1 - x0) / gnx_ * 1.000001, (y1 - y0) / gny_ * 1.000001});
  grid_.assign(static_cast<std::size_t>(gnx_) * gny_, {});
  for (uint32_t i = 0; i < segs_.size(); ++i) {
    const auto& g = segs_[i];
    const int ax = static_cast<int>(std::floor((std::min(g.ax, g.bx) - gx0_) / grid_cell_));
    const int bx = static_cast<int>(std::floor((std::max(g.ax, g.bx) - gx0_) / grid_cell_));
    const int ay = static_cast<int>(std::floor((std::min(g.ay, g.by) - gy0_) / grid_cell_));
    const int by = static_cast<int>(std::floor((std::max(g.ay, g.by) - gy0_) / grid_cell_));
    for (int ix = std::max(0, ax); ix <= std::min(gnx_ - 1, bx); ++ix) {
      for (int iy = std::max(0, ay); iy <= std::min(gny_ - 1, by); ++iy) grid_[static_cast<std::size_t>(iy) * gnx_ + ix].push_back(i);
    }
  }
}

double BoundaryMap::signed_distance(double px, double py, double* nx, double* ny, double* tangent) const {
  double best = std::numeric_limits<double>::infinity(), sign = 1.0, bx = 0.0, by = 0.0, bt = 0.0;
  auto test = [&](const Seg& g) {
    const double ax = g.ax, ay = g.ay, dx = g.bx - ax, dy = g.by - ay;
    const double l2 = dx * dx + dy * dy;
    const double t = std::clamp(((px - ax) * dx + (py - ay) * dy) / l2, 0.0, 1.0);
    const double qx = ax + t * dx, qy = ay + t * dy;
    const double d = std::hypot(px - qx, py - qy);
    if (d < best) {
      best = d;
      bx = qx;
      by = qy;
      bt = std::atan2(dy, dx);
      sign = (dx * (py - ay) - dy * (px - ax)) >= 0.0 ? 1.0 : -1.0;  // left = free
    }
  };
  // Rings of grid cells around the query until the ring is farther than the best.
  const long cx = static_cast<long>(std::floor((px - gx0_) / grid_cell_));
  const long cy = static_cast<long>(std::floor((py - gy0_) / grid_cell_));
  const long rmax = std::max<long>(gnx_, gny_) + std::labs(cx) + std::labs(cy) + 1;
  for (long r = 0; r <= rmax; ++r) {
    if (best < (static_cast<double>(r) - 1.0) * grid_cell_) break;
    for (long ix = cx - r; ix <= cx + r; ++ix) {
      for (long iy = cy - r; iy <= cy + r; ++iy) {
        if (std::labs(ix - cx) != r && std::labs(iy - cy) != r) continue;  // ring only
        if (ix < 0 || iy < 0 || ix >= gnx_ || iy >= gny_) continue;
        for (uint32_t i : grid_[static_cast<std::size_t>(iy) * gnx_ + ix]) test(segs_[i]);
      }
    }
  }
  if (nx) *nx = bx;
  if (ny) *ny = by;
  if (tangent) *tangent = bt;
  return sign * best;
}

void preimage(const BoundaryMap& map, const ContactGeometry& g, double min_clearance, PoseSet& out) {
  // 002 eq. 22: q_k = T_k R(.) [-x(s_a), -y(s_a)]: the contact sits on boundary
  // point k and the boundary tangent seen from the robot equals the map's.
  for (std::size_t k = 0; k < map.size(); ++k) {
    const double th = wrap_angle(map.tangent(k) - g.tangent);
    const double c = std::cos(th), s = std::sin(th);
    Pose2 q{map.x(k) - (c * g.cx - s * g.cy), map.y(k) - (s * g.cx + c * g.cy), th};
    // The base must be in free space. Cheap test first: the local boundary line.
    const double lx = q.x - map.x(k), ly = q.y - map.y(k);
    const double tc = std::cos(map.tangent(k)), ts = std::sin(map.tangent(k));
    if (tc * ly - ts * lx < min_clearance) continue;
    if (map.signed_distance(q.x, q.y) < min_clearance) continue;
    out.poses.push_back(q);
  }
}

void LocalizerParams::validate() const {
  auto pos = [](double v, const char* f) {
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string("LocalizerParams.") + f + ": must be finite and > 0, got " + std::to_string(v));
  };
  pos(contact_tolerance, "contact_tolerance");
  pos(match_angle, "match_angle");
  if (!(epsilon >= 0.0 && epsilon < 1.0)) throw std::invalid_argument("LocalizerParams.epsilon: must be in [0, 1), got " + std::to_string(epsilon));
  if (epsilon_samples < 1) throw std::invalid_argument("LocalizerParams.epsilon_samples: must be >= 1, got " + std::to_string(epsilon_samples));
  if (slope_samples < 2 || slope_samples > 50) throw std::invalid_argument("LocalizerParams.slope_samples: must be in [2, 50], got " + std::to_string(slope_samples));
  if (!(min_clearance >= 0.0)) throw std::invalid_argument("LocalizerParams.min_clearance: must be >= 0, got " + std::to_string(min_clearance));
  if (heading_samples < 1 || heading_samples > 101) throw std::invalid_argument("LocalizerParams.heading_samples: must be in [1, 101], got " + std::to_string(heading_samples));
  if (!(heading_spread >= 0.0 && heading_spread < 0.5)) throw std::invalid_argument("LocalizerParams.heading_spread: must be in [0, 0.5), got " + std::to_string(heading_spread));
  if (!std::isfinite(prior_radius)) throw std::invalid_argument("LocalizerParams.prior_radius: must be finite");
  if (!(mode_radius > 0.0)) throw std::invalid_argument("LocalizerParams.mode_radius: must be > 0, got " + std::to_string(mode_radius));
  if (refine_passes < 0 || refine_passes > 10) throw std::invalid_argument("LocalizerParams.refine_passes: must be in [0, 10], got " + std::to_string(refine_passes));
}

PreimageLocalizer::PreimageLocalizer(const BoundaryMap& map, const ElasticaSolver& solver, const LocalizerParams& params)
    : map_(map), solver_(solver), params_(params) {
  params_.validate();
}

void PreimageLocalizer::reset() {
  set_.poses.clear();
  have_set_ = false;
  hist_.clear();
  have_tangent_ = false;
  cost_.clear();
}

BeamShape PreimageLocalizer::tip_shape(double m0, double direction) const {
  const double L = solver_.params().length;
  if (std::isnan(direction)) return solver_.solve_moment(m0, L);
  return solver_.solve_moment_fixed(m0, direction, L);
}

Pose2 mean_pose(const PoseSet& s, double* spread) {
  Pose2 m;
  if (s.empty()) {
    if (spread) *spread = std::numeric_limits<double>::quiet_NaN();
    return Pose2{std::nan(""), std::nan(""), std::nan("")};
  }
  double c = 0.0, sn = 0.0;
  for (const auto& q : s.poses) {
    m.x += q.x;
    m.y += q.y;
    c += std::cos(q.theta);
    sn += std::sin(q.theta);
  }
  m.x /= static_cast<double>(s.size());
  m.y /= static_cast<double>(s.size());
  m.theta = std::atan2(sn, c);
  if (spread) {
    double r = 0.0;
    for (const auto& q : s.poses) r = std::max(r, std::hypot(q.x - m.x, q.y - m.y));
    *spread = r;
  }
  return m;
}

namespace {
/// Mean of the poses within `radius` of pose `centre` of s; *spread = the
/// largest distance of any pose of s from that mean.
Pose2 mean_near(const PoseSet& s, std::size_t centre, double radius, double* spread) {
  PoseSet near;
  for (const auto& q : s.poses) {
    if (std::hypot(q.x - s.poses[centre].x, q.y - s.poses[centre].y) <= radius) near.poses.push_back(q);
  }
  Pose2 m = mean_pose(near, nullptr);
  if (spread) {
    double r = 0.0;
    for (const auto& q : s.poses) r = std::max(r, std::hypot(q.x - m.x, q.y - m.y));
    *spread = r;
  }
  return m;
}
}  // namespace

Pose2 best_pose(const PoseSet& s, double radius, double* spread) {
  if (s.size() > 2000 || s.size() < 3) return mean_pose(s, spread);
  const double r2 = radius * radius;
  std::size_t best = 0, best_n = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::size_t n = 0;
    for (std::size_t j = 0; j < s.size(); ++j) {
      const double dx = s.poses[i].x - s.poses[j].x, dy = s.poses[i].y - s.poses[j].y;
      if (dx * dx + dy * dy <= r2) ++n;
    }
    if (n > best_n) {
      best_n = n;
      best = i;
    }
  }
  return mean_near(s, best, radius, spread);
}

Pose2 best_pose(const PoseSet& s, const std::vector<double>& cost, double radius, double* spread) {
  if (s.empty() || cost.size() != s.size()) return best_pose(s, radius, spread);
  // The most consistent pose (least accumulated residual) and its neighbours.
  const std::size_t best = static_cast<std::size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  return mean_near(s, best, radius, spread);
}

// Contact point of the newest observation and the boundary slope phi_E from
// the recent contact points moved into the current frame (002 Sec. VII-A).
bool PreimageLocalizer::geometry_for(double m0, ContactGeometry& g) {
  double direction = std::nan("");
  if (have_tangent_) direction = last_tangent_ + kPi / 2.0;  // load along the boundary normal
  for (int pass = 0; pass <= params_.refine_passes; ++pass) {
    // Every history sample with the current load direction, moved into the
    // current frame by walking back through the motions.
    std::vector<double> xs, ys;
    Pose2 T{};  // pose of frame j in the current frame
    BeamShape newest;
    for (std::size_t j = hist_.size(); j-- > 0;) {
      const double dir_j = std::isnan(direction) ? direction : direction - T.theta;
      const BeamShape b = tip_shape(hist_[j].m0, dir_j);
      if (!b.ok) return false;
      if (j + 1 == hist_.size()) newest = b;
      hist_[j].cx = b.contact_x;
      hist_[j].cy = b.contact_y;
      const double c = std::cos(T.theta), s = std::sin(T.theta);
      xs.push_back(T.x + c * b.contact_x - s * b.contact_y);
      ys.push_back(T.y + s * b.contact_x + c * b.contact_y);
      const Pose2& mo = hist_[j].motion;
      const double mc = std::cos(mo.theta), ms = std::sin(mo.theta);
      T = compose(T, Pose2{-(mc * mo.x + ms * mo.y), -(-ms * mo.x + mc * mo.y), -mo.theta});
    }
    (void)m0;
    if (hist_.size() < 2) return false;
    // Principal direction of the points (total least squares line).
    double mx = 0.0, my = 0.0;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      mx += xs[i];
      my += ys[i];
    }
    mx /= static_cast<double>(xs.size());
    my /= static_cast<double>(xs.size());
    double sxx = 0.0, syy = 0.0, sxy = 0.0;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      sxx += (xs[i] - mx) * (xs[i] - mx);
      syy += (ys[i] - my) * (ys[i] - my);
      sxy += (xs[i] - mx) * (ys[i] - my);
    }
    if (sxx + syy < 1e-16) return false;  // the contact did not move: no slope
    double line = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
    // Orient it: the load on the whisker points into free space = the left
    // normal of the tangent (free space on the left of the map's polylines).
    const double load = std::atan2(newest.force_y, newest.force_x);
    if (std::cos(line - (load - kPi / 2.0)) < 0.0) line += kPi;
    g.cx = newest.contact_x;
    g.cy = newest.contact_y;
    g.tangent = wrap_angle(line);
    chord_ox_ = xs.back();
    chord_oy_ = ys.back();
    last_tangent_ = g.tangent;
    have_tangent_ = true;
    direction = g.tangent + kPi / 2.0;
  }
  return true;
}

void PreimageLocalizer::tangent_bounds(double tangent, double& lo, double& hi) {
  lo = hi = tangent;
  if (hist_.size() < 2) return;
  const double dir = tangent + kPi / 2.0;
  // Oldest and newest samples at M (1 +- eps), with the load along the estimated normal.
  double ox[2], oy[2], nx[2], ny[2];
  for (int e = 0; e < 2; ++e) {
    const double f = e == 0 ? 1.0 - params_.epsilon : 1.0 + params_.epsilon;
    const BeamShape bo = tip_shape(hist_.front().m0 * f, dir);
    const BeamShape bn = tip_shape(hist_.back().m0 * f, dir);
    if (!bo.ok || !bn.ok) return;
    ox[e] = bo.contact_x;
    oy[e] = bo.contact_y;
    nx[e] = bn.contact_x;
    ny[e] = bn.contact_y;
  }
  // The oldest sample in the current frame.
  Pose2 T{};
  for (std::size_t j = hist_.size(); j-- > 1;) {
    const Pose2& mo = hist_[j].motion;
    const double mc = std::cos(mo.theta), ms = std::sin(mo.theta);
    T = compose(T, Pose2{-(mc * mo.x + ms * mo.y), -(-ms * mo.x + mc * mo.y), -mo.theta});
  }
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const double px = T.x + c * ox[a] - s * oy[a], py = T.y + s * ox[a] + c * oy[a];
      double ang = std::atan2(ny[b] - py, nx[b] - px);
      if (std::cos(ang - tangent) < 0.0) ang += kPi;
      const double d = wrap_angle(ang - tangent);
      lo = std::min(lo, tangent + d);
      hi = std::max(hi, tangent + d);
    }
  }
}

// Preimage of the observation (eq. 22), or of every z' with |z' - z| <= eps |z|
// and every phi_E within its bounds (eq. 24-25), over the whole map.
void PreimageLocalizer::build_preimage(double m0, const ContactGeometry& g) {
  obs_.poses.clear();
  if (!params_.possibilistic || params_.epsilon == 0.0) {
    preimage(map_, g, params_.min_clearance, obs_);
  } else {
    // Bounded error on every observation (eq. 24): the contact points of the
    // oldest and newest history samples move within their +-eps sets, which
    // bounds phi_E; the preimage is the union over both ranges (eq. 25).
    double tlo = g.tangent, thi = g.tangent;
    tangent_bounds(g.tangent, tlo, thi);
    const int n = params_.epsilon_samples;
    for (int i = 0; i < n; ++i) {
      const double f = n == 1 ? 0.0 : -1.0 + 2.0 * i / (n - 1);
      const double mz = m0 * (1.0 + params_.epsilon * f);
      const BeamShape b = tip_shape(mz, g.tangent + kPi / 2.0);
      if (!b.ok) continue;
      for (int j = 0; j < n; ++j) {
        const double ft = n == 1 ? 0.5 : static_cast<double>(j) / (n - 1);
        ContactGeometry gi;
        gi.cx = b.contact_x;
        gi.cy = b.contact_y;
        gi.tangent = tlo + ft * (thi - tlo);
        preimage(map_, gi, params_.min_clearance, obs_);
      }
    }
  }
}

// The set from the preimage of the current observation: heading hypotheses
// about each aligned contact, restricted to the prior region if one is known.
void PreimageLocalizer::seed_set() {
  set_.poses.clear();
  const int n = params_.heading_samples;
  for (const auto& q : obs_.poses) {
    if (have_prior_ && params_.prior_radius > 0.0 &&
        std::hypot(q.x - prior_.x, q.y - prior_.y) > params_.prior_radius) {
      continue;
    }
    // The contact point of q in the world (rotation centre).
    const Pose2 contact = compose(q, Pose2{cands_.front().cx, cands_.front().cy, 0.0});
    for (int i = 0; i < n; ++i) {
      const double d = n == 1 ? 0.0 : params_.heading_spread * (-1.0 + 2.0 * i / (n - 1));
      const double c = std::cos(d), s = std::sin(d);
      const double rx = q.x - contact.x, ry = q.y - contact.y;
      set_.poses.push_back(Pose2{contact.x + c * rx - s * ry, contact.y + s * rx + c * ry, wrap_angle(q.theta + d)});
    }
  }
  cost_.assign(set_.size(), 0.0);
}

PreimageLocalizer::StepResult PreimageLocalizer::step(const Pose2& motion, double m0) {
  StepResult r;
  // Forward projection of the current set (002 Sec. IV-D): T'_k = T_k T_local.
  if (have_set_) {
    for (auto& q : set_.poses) q = compose(q, motion);
  }
  if (have_tangent_) last_tangent_ = wrap_angle(last_tangent_ - motion.theta);
  if (have_prior_) prior_ = compose(prior_, motion);
  if (!std::isfinite(m0) || m0 == 0.0) {
    hist_.clear();
    have_tangent_ = false;
    r.best = mean_pose(set_, &r.spread);
    r.set_size = set_.size();
    return r;
  }
  hist_.push_back(Hist{m0, motion, 0.0, 0.0});
  while (hist_.size() > static_cast<std::size_t>(params_.slope_samples)) hist_.pop_front();
  ContactGeometry g;
  const bool have_geom = geometry_for(m0, g);
  r.contact = true;
  r.geometry = g;
  // 002 Sec. VII-B: a minimum of three observations; we wait for the full
  // slope history so phi_E is estimated from slope_samples points.
  if (!have_geom || hist_.size() < static_cast<std::size_t>(std::max(3, params_.slope_samples))) {
    r.best = mean_pose(set_, &r.spread);
    r.set_size = set_.size();
    return r;
  }
  r.localizing = true;
  cands_.clear();
  if (!params_.possibilistic || params_.epsilon == 0.0) {
    cands_.push_back(Cand{g.cx, g.cy, g.tangent, 0.0});
  } else {
    double tlo = g.tangent, thi = g.tangent;
    tangent_bounds(g.tangent, tlo, thi);
    const int n = std::max(2, params_.epsilon_samples * 2);
    for (int i = 0; i < n; ++i) {
      const double f = -1.0 + 2.0 * i / (n - 1);
      const BeamShape b = tip_shape(m0 * (1.0 + params_.epsilon * f), g.tangent + kPi / 2.0);
      if (b.ok) cands_.push_back(Cand{b.contact_x, b.contact_y, 0.5 * (tlo + thi), 0.5 * (thi - tlo)});
    }
  }
  if (!have_set_) {
    build_preimage(m0, g);
    r.preimage_size = obs_.size();
    seed_set();
    have_set_ = true;
  } else {
    // Intersection of the forward-projected set with the preimage of the new
    // observation: a forward-projected pose q is in h^-1(z) (eq. 16, 25) if
    // the observed contact point, placed by q, lies on the map boundary
    // (within contact_tolerance) with the observed boundary slope (within
    // match_angle). The observed slope is a line through the contacts of
    // the last slope_samples observations, so it is compared with the map's
    // chord between the oldest and newest of them as placed by q, not with
    // the tangent at the newest (which a line fit lags by half the window
    // times the curvature, and which made the truth fail the test where the
    // curvature changes). Survivors keep their own motion-propagated value,
    // so a wrong hypothesis accumulates its inconsistency instead of being
    // re-anchored on the discretised preimage; its squared residuals are
    // summed (cost_) and the best estimate is the least-cost pose.
    std::vector<char> keep(set_.size(), 0);
    std::vector<double> res(set_.size(), 0.0);
    for (std::size_t j = 0; j < set_.size(); ++j) {
      const auto& q = set_.poses[j];
      const double c = std::cos(q.theta), s = std::sin(q.theta);
      // The oldest history contact placed by q, on the map: with the newest
      // one it gives the map's chord over the history window.
      double obx = 0.0, oby = 0.0;
      map_.signed_distance(q.x + c * chord_ox_ - s * chord_oy_, q.y + s * chord_ox_ + c * chord_oy_, &obx, &oby);
      // Distance of a contact (robot frame) placed by q to the map, and the
      // error of the observed slope against the map's slope over the same
      // stretch of boundary (its chord; the local tangent if the contact did
      // not move along the boundary).
      auto residual = [&](double cx, double cy, double slope, double& d, double& err) {
        const double wx = q.x + c * cx - s * cy, wy = q.y + s * cx + c * cy;
        double tan = 0.0, nbx = 0.0, nby = 0.0;
        d = map_.signed_distance(wx, wy, &nbx, &nby, &tan);
        double map_slope = tan;
        if (std::hypot(nbx - obx, nby - oby) > 2.0 * map_.spacing()) {
          map_slope = std::atan2(nby - oby, nbx - obx);
          if (std::cos(map_slope - tan) < 0.0) map_slope += kPi;
        }
        err = wrap_angle(map_slope - (q.theta + slope));
      };
      for (const auto& cand : cands_) {
        double d = 0.0, err = 0.0;
        residual(cand.cx, cand.cy, cand.tangent, d, err);
        if (std::fabs(d) <= params_.contact_tolerance &&
            std::fabs(err) <= params_.match_angle + cand.tangent_halfwidth) {
          keep[j] = 1;
          break;
        }
      }
      // Consistency with the observation itself (the middle of the
      // possibilistic band), accumulated for the best estimate.
      double d = 0.0, err = 0.0;
      residual(g.cx, g.cy, g.tangent, d, err);
      const double rd = d / params_.contact_tolerance, ra = err / params_.match_angle;
      res[j] = rd * rd + ra * ra;
    }
    tmp_.poses.clear();
    tmp_cost_.clear();
    for (std::size_t j = 0; j < set_.size(); ++j) {
      if (keep[j]) {
        tmp_.poses.push_back(set_.poses[j]);
        tmp_cost_.push_back(cost_[j] + res[j]);
      }
    }
    if (tmp_.empty()) {  // inconsistent: restart from the new preimage
      build_preimage(m0, g);
      r.preimage_size = obs_.size();
      seed_set();
      r.reset = true;
      ++resets_;
    } else {
      std::swap(set_, tmp_);
      std::swap(cost_, tmp_cost_);
    }
  }
  r.set_size = set_.size();
  r.best = best_pose(set_, cost_, params_.mode_radius, &r.spread);
  return r;
}

}  // namespace whisker_localization
