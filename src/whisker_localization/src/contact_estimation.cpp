#include "whisker_localization/contact_estimation.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

#include "whisker_localization/root_finding.hpp"

namespace whisker_localization {

void ContactSet::clear() {
  x.clear();
  y.clear();
  s_a.clear();
  force.clear();
  phi_a.clear();
}

void ContactSet::push(const BeamShape& b) {
  x.push_back(b.contact_x);
  y.push_back(b.contact_y);
  s_a.push_back(b.s_a);
  force.push_back(b.force);
  phi_a.push_back(b.phi_a);
}

void ContactSetParams::validate() const {
  if (!(s_min_fraction > 0.0 && s_min_fraction < 1.0))
    throw std::invalid_argument("ContactSetParams.s_min_fraction: must be in (0, 1), got " + std::to_string(s_min_fraction));
  if (!(ds > 0.0) || !std::isfinite(ds)) throw std::invalid_argument("ContactSetParams.ds: must be finite and > 0, got " + std::to_string(ds));
  if (force_samples < 3) throw std::invalid_argument("ContactSetParams.force_samples: must be >= 3, got " + std::to_string(force_samples));
  if (!(f_max > 0.0) || !std::isfinite(f_max)) throw std::invalid_argument("ContactSetParams.f_max: must be finite and > 0, got " + std::to_string(f_max));
}

VirtualSensors::VirtualSensors(const ElasticaSolver& solver, const ContactSetParams& params)
    : solver_(solver), params_(params) {
  params_.validate();
}

std::vector<double> VirtualSensors::s_grid() const {
  const double L = solver_.params().length;
  const double s0 = params_.s_min_fraction * L;
  const int n = std::max(2, static_cast<int>(std::ceil((L - s0) / params_.ds)) + 1);
  std::vector<double> g(n);
  for (int i = 0; i < n; ++i) g[i] = s0 + (L - s0) * i / (n - 1);
  return g;
}

ContactSet VirtualSensors::load(double force) const {
  ContactSet out;  // 002 eq. 10: every s_a with this F
  for (double s : s_grid()) {
    const BeamShape b = solver_.solve_normal(force, s);
    if (b.ok && std::fabs(b.phi_a) <= ElasticaSolver::kMaxSlope) out.push(b);
  }
  return out;
}

ContactSet VirtualSensors::strip(double s_a) const {
  ContactSet out;  // 002 eq. 12: every F in [-F_max, F_max] at this s_a
  const int n = params_.force_samples;
  for (int i = 0; i < n; ++i) {
    const double F = -params_.f_max + 2.0 * params_.f_max * i / (n - 1);
    const BeamShape b = solver_.solve_normal(F, s_a);
    if (b.ok && std::fabs(b.phi_a) <= ElasticaSolver::kMaxSlope) out.push(b);
  }
  return out;
}

ContactSet VirtualSensors::end_slope(double phi_a) const {
  ContactSet out;  // 002 eq. 13: pairs (s_a, F) with this end slope
  if (!std::isfinite(phi_a) || std::fabs(phi_a) > ElasticaSolver::kMaxSlope) return out;
  const double sgn = phi_a >= 0.0 ? 1.0 : -1.0;
  const double target = std::fabs(phi_a);
  for (double s : s_grid()) {
    if (target == 0.0) {
      out.push(solver_.solve_normal(0.0, s));
      continue;
    }
    auto f = [&](double F) { return solver_.solve_normal(F, s).phi_a - target; };
    // Small-angle guess phi_a = F s^2 / (2 E I).
    double hi = 2.0 * solver_.params().ei_base() * target / (s * s), lo = 0.0, flo = -target, fhi = f(hi);
    for (int i = 0; i < 60 && fhi < 0.0; ++i) {
      lo = hi;
      flo = fhi;
      hi *= 1.5;
      fhi = f(hi);
    }
    if (!(fhi >= 0.0)) continue;
    auto F = brent_root(f, lo, hi, flo, fhi, 1e-13 * hi, 200);
    if (!F) continue;
    if (hi > params_.f_max && *F > params_.f_max) continue;  // beyond the load limit
    out.push(solver_.solve_normal(sgn * *F, s));
  }
  return out;
}

ContactSet VirtualSensors::moment(double m0) const {
  ContactSet out;  // 002 eq. 17: normal load with base moment M(0), large-angle model
  for (double s : s_grid()) {
    const BeamShape b = solver_.solve_moment(m0, s);
    if (b.ok) out.push(b);
  }
  return out;
}

ContactSet VirtualSensors::moment_small_angle(double m0) const {
  ContactSet out;  // 002 eq. 15: F = M(0) / s_a; shape from eq. 1-2 (vertical load)
  constexpr double kHalfPi = 1.57079632679489661923;
  for (double s : s_grid()) {
    const double F = m0 / s;
    const BeamShape b = solver_.solve_fixed(std::fabs(F), F >= 0.0 ? kHalfPi : -kHalfPi, s);
    if (b.ok && std::fabs(b.phi_a) <= ElasticaSolver::kMaxSlope) out.push(b);
  }
  return out;
}

std::vector<SetIntersection> intersect_sets(const ContactSet& a, const ContactSet& b, double bx, double by) {
  std::vector<SetIntersection> out;
  if (a.size() < 2 || b.size() < 2) return out;
  for (std::size_t i = 0; i + 1 < a.size(); ++i) {
    const double ax0 = a.x[i], ay0 = a.y[i], adx = a.x[i + 1] - ax0, ady = a.y[i + 1] - ay0;
    const double aminx = std::fmin(ax0, a.x[i + 1]), amaxx = std::fmax(ax0, a.x[i + 1]);
    const double aminy = std::fmin(ay0, a.y[i + 1]), amaxy = std::fmax(ay0, a.y[i + 1]);
    for (std::size_t j = 0; j + 1 < b.size(); ++j) {
      const double bx0 = b.x[j] + bx, by0 = b.y[j] + by;
      const double bx1 = b.x[j + 1] + bx, by1 = b.y[j + 1] + by;
      if (std::fmax(bx0, bx1) < aminx || std::fmin(bx0, bx1) > amaxx || std::fmax(by0, by1) < aminy ||
          std::fmin(by0, by1) > amaxy) {
        continue;
      }
      const double bdx = bx1 - bx0, bdy = by1 - by0;
      const double den = adx * bdy - ady * bdx;
      if (std::fabs(den) < 1e-30) continue;
      const double ex = bx0 - ax0, ey = by0 - ay0;
      const double t = (ex * bdy - ey * bdx) / den;
      const double u = (ex * ady - ey * adx) / den;
      // Half-open on the first segment end so a crossing at a shared vertex counts once.
      if (t < 0.0 || t >= 1.0 || u < 0.0 || u > 1.0) continue;
      SetIntersection p;
      p.x = ax0 + t * adx;
      p.y = ay0 + t * ady;
      p.s_a = a.s_a[i] + t * (a.s_a[i + 1] - a.s_a[i]);
      p.force = a.force[i] + t * (a.force[i + 1] - a.force[i]);
      p.phi_a = a.phi_a[i] + t * (a.phi_a[i + 1] - a.phi_a[i]);
      out.push_back(p);
    }
  }
  return out;
}

void TemporalFilterParams::validate() const {
  if (!(contact_threshold >= 0.0) || !std::isfinite(contact_threshold))
    throw std::invalid_argument("TemporalFilterParams.contact_threshold: must be finite and >= 0, got " + std::to_string(contact_threshold));
  if (!(tip_threshold >= contact_threshold) || !std::isfinite(tip_threshold))
    throw std::invalid_argument("TemporalFilterParams.tip_threshold: must be finite and >= contact_threshold, got " + std::to_string(tip_threshold));
}

TemporalContactFilter::TemporalContactFilter(const VirtualSensors& sensors, const TemporalFilterParams& params)
    : sensors_(sensors), params_(params) {
  params_.validate();
}

void TemporalContactFilter::reset() {
  have_prev_ = false;
  prev_.clear();
}

void TemporalContactFilter::start_from_touch() {
  prev_ = sensors_.moment(0.0);
  have_prev_ = true;
}

ContactEstimate TemporalContactFilter::update(double m0, double dx, double dy) {
  ContactEstimate e;
  if (!std::isfinite(m0) || std::fabs(m0) < params_.contact_threshold) {
    reset();
    return e;
  }
  ContactSet cur = sensors_.moment(m0);
  if (!have_prev_) {
    prev_ = std::move(cur);
    have_prev_ = true;
    e.status = ContactEstimate::Status::kFirst;
    return e;
  }
  // A world-fixed contact c has sensor coordinates c_prev in the previous frame
  // and c_prev - d in the current one: intersect P_t+1 with P_t moved by -d (eq. 21).
  const auto hits = intersect_sets(cur, prev_, -dx, -dy);
  e.n_intersections = hits.size();
  if (hits.empty()) {
    e.status = std::fabs(m0) >= params_.tip_threshold ? ContactEstimate::Status::kTipContact
                                                      : ContactEstimate::Status::kSlip;
  } else {
    // Several crossings: the one nearest the tip (the sets meet at shallow angles near the base).
    const SetIntersection* best = &hits.front();
    for (const auto& h : hits) {
      if (h.s_a > best->s_a) best = &h;
    }
    e.status = ContactEstimate::Status::kEstimated;
    e.x = best->x;
    e.y = best->y;
    e.s_a = best->s_a;
    e.force = best->force;
    e.phi_a = best->phi_a;
  }
  prev_ = std::move(cur);
  return e;
}

HallCalibration HallCalibration::fit(const std::vector<double>& flux, const std::vector<double>& moment, int degree) {
  if (degree < 1 || degree > 9) throw std::invalid_argument("HallCalibration.degree: must be in [1, 9], got " + std::to_string(degree));
  if (flux.size() != moment.size())
    throw std::invalid_argument("HallCalibration.pairs: flux and moment sizes differ (" + std::to_string(flux.size()) +
                                " vs " + std::to_string(moment.size()) + ")");
  const std::size_t n = flux.size();
  if (n < static_cast<std::size_t>(degree) + 1)
    throw std::invalid_argument("HallCalibration.pairs: need >= degree + 1 = " + std::to_string(degree + 1) + " pairs, got " +
                                std::to_string(n));
  Eigen::MatrixXd A(n, degree + 1);
  Eigen::VectorXd b(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(flux[i]) || !std::isfinite(moment[i]))
      throw std::invalid_argument("HallCalibration.pairs[" + std::to_string(i) + "]: not finite");
    double p = 1.0;
    for (int k = 0; k <= degree; ++k) {
      A(static_cast<Eigen::Index>(i), k) = p;
      p *= flux[i];
    }
    b(static_cast<Eigen::Index>(i)) = moment[i];
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  HallCalibration h;
  h.coeffs_.assign(c.data(), c.data() + c.size());
  h.rms_ = std::sqrt((A * c - b).squaredNorm() / static_cast<double>(n));
  return h;
}

double HallCalibration::moment(double flux) const {
  double m = 0.0;
  for (auto it = coeffs_.rbegin(); it != coeffs_.rend(); ++it) m = m * flux + *it;
  return m;
}

void ProfileEstimator::add(double base_x, double base_y, double base_yaw, double cx, double cy) {
  const double c = std::cos(base_yaw), s = std::sin(base_yaw);
  x_.push_back(base_x + c * cx - s * cy);  // 002 Sec. VI-B: union over t of the world contact points
  y_.push_back(base_y + s * cx + c * cy);
}

}  // namespace whisker_localization
