#include "whisker_localization/elastica.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "whisker_localization/root_finding.hpp"

namespace whisker_localization {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string num(double v) { return std::to_string(v); }

}  // namespace

void BeamParams::validate() const {
  if (!std::isfinite(length) || length <= 0.0) throw std::invalid_argument("BeamParams.length: must be finite and > 0, got " + num(length));
  if (!std::isfinite(youngs_modulus) || youngs_modulus <= 0.0)
    throw std::invalid_argument("BeamParams.youngs_modulus: must be finite and > 0, got " + num(youngs_modulus));
  if (!std::isfinite(moment_of_inertia) || moment_of_inertia <= 0.0)
    throw std::invalid_argument("BeamParams.moment_of_inertia: must be finite and > 0, got " + num(moment_of_inertia));
  if (!std::isfinite(taper_ratio) || taper_ratio <= 0.0 || taper_ratio > 1.0)
    throw std::invalid_argument("BeamParams.taper_ratio: must be in (0, 1], got " + num(taper_ratio));
  if (n_segments < 4 || n_segments > 100000)
    throw std::invalid_argument("BeamParams.n_segments: must be in [4, 100000], got " + std::to_string(n_segments));
}

double BeamParams::ei_at(double s) const {
  if (taper_ratio == 1.0) return ei_base();
  const double k = 1.0 - (1.0 - taper_ratio) * (s / length);
  return ei_base() * k * k * k * k;
}

ElasticaSolver::ElasticaSolver(const BeamParams& params) : params_(params) { params_.validate(); }

// Backward RK4 from the load point (u = 0, s = s_a) to the base (u = s_a).
// State: phi, M, X = x - x_a, Y = y - y_a. For a normal load the state uses
// phi_rel = phi - phi_a and the load frame (rotated by phi_a at the end).
BeamShape ElasticaSolver::integrate(double fx, double fy, double force, double s_a, bool normal, double phi_a,
                                    bool with_nodes) const {
  BeamShape out;
  out.force = force;
  out.s_a = s_a;
  const int n = params_.n_segments;
  const double h = s_a / n;
  using State = std::array<double, 4>;
  auto deriv = [&](double u, const State& v) -> State {
    const double s = s_a - u;
    const double c = std::cos(v[0]), sn = std::sin(v[0]);
    // 002 eq. 4: dM/ds = -F_y cos(phi) + F_x sin(phi); u runs backward.
    const double dm = normal ? force * c : (fy * c - fx * sn);
    return State{-v[1] / params_.ei_at(s), dm, -c, -sn};
  };
  State v{normal ? 0.0 : phi_a, 0.0, 0.0, 0.0};
  if (with_nodes) {
    out.s.resize(n + 1);
    out.x.resize(n + 1);
    out.y.resize(n + 1);
    out.phi.resize(n + 1);
  }
  // Node k of the backward sweep is s = s_a - k h; stored at index n - k.
  auto store = [&](int k, const State& st) {
    if (!with_nodes) return;
    const int i = n - k;
    out.s[i] = s_a - k * h;
    out.phi[i] = st[0];
    out.x[i] = st[2];
    out.y[i] = st[3];
  };
  store(0, v);
  for (int k = 0; k < n; ++k) {
    const double u = k * h;
    const State k1 = deriv(u, v);
    State t;
    for (int j = 0; j < 4; ++j) t[j] = v[j] + 0.5 * h * k1[j];
    const State k2 = deriv(u + 0.5 * h, t);
    for (int j = 0; j < 4; ++j) t[j] = v[j] + 0.5 * h * k2[j];
    const State k3 = deriv(u + 0.5 * h, t);
    for (int j = 0; j < 4; ++j) t[j] = v[j] + h * k3[j];
    const State k4 = deriv(u + h, t);
    for (int j = 0; j < 4; ++j) v[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    store(k + 1, v);
  }
  double pa = phi_a;
  double rx = 0.0, ry = 0.0;  // base (X, Y) in the sensor frame
  double ca = 1.0, sa = 0.0;
  if (normal) {
    pa = -v[0];  // phi(0) = phi_a + phi_rel(0) = 0
    ca = std::cos(pa);
    sa = std::sin(pa);
    rx = ca * v[2] - sa * v[3];
    ry = sa * v[2] + ca * v[3];
    fx = -force * sa;
    fy = force * ca;
  } else {
    rx = v[2];
    ry = v[3];
  }
  out.phi_a = pa;
  out.force_x = fx;
  out.force_y = fy;
  out.contact_x = -rx;  // x(0) = 0 = x_a + X(base)
  out.contact_y = -ry;
  out.base_moment = v[1];
  out.base_force_x = -fx;
  out.base_force_y = -fy;
  const double rest = params_.length - s_a;  // 002 eq. 3: straight beyond s_a
  out.tip_x = out.contact_x + rest * std::cos(pa);
  out.tip_y = out.contact_y + rest * std::sin(pa);
  if (with_nodes) {
    for (int i = 0; i <= n; ++i) {
      double X = out.x[i], Y = out.y[i], ph = out.phi[i];
      if (normal) {
        const double X2 = ca * X - sa * Y;
        Y = sa * X + ca * Y;
        X = X2;
        ph += pa;
      }
      out.x[i] = X + out.contact_x;
      out.y[i] = Y + out.contact_y;
      out.phi[i] = ph;
    }
  }
  out.ok = std::isfinite(out.base_moment) && std::isfinite(out.contact_x) && std::isfinite(out.contact_y);
  if (!normal) out.ok = out.ok && std::fabs(v[0]) < 1e-6;
  return out;
}

BeamShape ElasticaSolver::solve_normal(double force, double s_a, bool with_nodes) const {
  if (!std::isfinite(force) || !std::isfinite(s_a) || s_a <= 0.0 || s_a > params_.length * (1.0 + 1e-12)) {
    return BeamShape{};
  }
  return integrate(0.0, 0.0, force, std::fmin(s_a, params_.length), true, 0.0, with_nodes);
}

BeamShape ElasticaSolver::solve_fixed(double force, double direction, double s_a, bool with_nodes) const {
  if (!std::isfinite(force) || force < 0.0 || !std::isfinite(direction) || !std::isfinite(s_a) || s_a <= 0.0 ||
      s_a > params_.length * (1.0 + 1e-12)) {
    return BeamShape{};
  }
  s_a = std::fmin(s_a, params_.length);
  const double fx = force * std::cos(direction), fy = force * std::sin(direction);
  if (force == 0.0) return integrate(0.0, 0.0, 0.0, s_a, false, 0.0, with_nodes);
  // Residual phi(0; phi_a) via a slim integration (phi and M only).
  const int n = params_.n_segments;
  const double h = s_a / n;
  auto phi_base = [&](double pa) {
    double phi = pa, m = 0.0;
    auto d = [&](double u, double p, double mm, double& dp, double& dmm) {
      dp = -mm / params_.ei_at(s_a - u);
      dmm = fy * std::cos(p) - fx * std::sin(p);
    };
    for (int k = 0; k < n; ++k) {
      const double u = k * h;
      double a1, b1, a2, b2, a3, b3, a4, b4;
      d(u, phi, m, a1, b1);
      d(u + 0.5 * h, phi + 0.5 * h * a1, m + 0.5 * h * b1, a2, b2);
      d(u + 0.5 * h, phi + 0.5 * h * a2, m + 0.5 * h * b2, a3, b3);
      d(u + h, phi + h * a3, m + h * b3, a4, b4);
      phi += h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4);
      m += h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4);
    }
    return phi;
  };
  // Bend toward the side the load's lateral component pushes; scan phi_a
  // outward from 0 for the first sign change (fundamental solution).
  const double sign = (fy >= 0.0) ? 1.0 : -1.0;
  const double step = 0.05;
  double a = 0.0, fa = phi_base(0.0);
  if (fa == 0.0) return integrate(fx, fy, force, s_a, false, 0.0, with_nodes);
  for (double t = step; t < kPi - 1e-9; t += step) {
    const double b = sign * t;
    const double fb = phi_base(b);
    if (!std::isfinite(fb)) break;
    if ((fa > 0.0) != (fb > 0.0)) {
      auto root = brent_root(phi_base, a, b, fa, fb, 1e-13, 200);
      if (!root) break;
      return integrate(fx, fy, force, s_a, false, *root, with_nodes);
    }
    a = b;
    fa = fb;
  }
  return BeamShape{};
}

BeamShape ElasticaSolver::solve_moment(double moment, double s_a, bool with_nodes) const {
  if (!std::isfinite(moment) || !std::isfinite(s_a) || s_a <= 0.0 || s_a > params_.length * (1.0 + 1e-12)) {
    return BeamShape{};
  }
  if (moment == 0.0) return solve_normal(0.0, s_a, with_nodes);
  const double sgn = moment > 0.0 ? 1.0 : -1.0;
  const double target = std::fabs(moment);
  auto f = [&](double F) { return solve_normal(F, s_a).base_moment - target; };
  double lo = 0.0, flo = -target;
  double hi = target / s_a, fhi = 0.0;  // small-angle guess M = F s_a (002 eq. 15)
  for (int i = 0; i < 60; ++i) {
    const BeamShape b = solve_normal(hi, s_a);
    if (!b.ok || std::fabs(b.phi_a) > kMaxSlope) return BeamShape{};
    fhi = b.base_moment - target;
    if (fhi >= 0.0) break;
    lo = hi;
    flo = fhi;
    hi *= 1.5;
  }
  if (fhi < 0.0) return BeamShape{};
  auto root = brent_root(f, lo, hi, flo, fhi, 1e-14 * hi + 1e-18, 200);
  if (!root) return BeamShape{};
  BeamShape out = solve_normal(sgn * *root, s_a, with_nodes);
  if (std::fabs(out.phi_a) > kMaxSlope) return BeamShape{};
  return out;
}

BeamShape ElasticaSolver::solve_moment_fixed(double moment, double direction, double s_a, bool with_nodes) const {
  if (!std::isfinite(moment) || !std::isfinite(direction) || !std::isfinite(s_a) || s_a <= 0.0) return BeamShape{};
  if (moment == 0.0) return solve_fixed(0.0, direction, s_a, with_nodes);
  auto mom = [&](double F) {
    const BeamShape b = solve_fixed(F, direction, s_a);
    return b.ok ? b.base_moment : std::numeric_limits<double>::quiet_NaN();
  };
  const double lever = std::fabs(std::sin(direction)) * s_a;
  double hi = std::fabs(moment) / std::fmax(lever, 0.05 * s_a);
  double lo = 0.0, flo = -moment;
  double fhi = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 60; ++i) {
    const BeamShape b = solve_fixed(hi, direction, s_a);
    if (!b.ok || std::fabs(b.phi_a) > kMaxSlope) return BeamShape{};
    fhi = b.base_moment - moment;
    if ((fhi > 0.0) != (flo > 0.0)) break;
    lo = hi;
    flo = fhi;
    hi *= 1.5;
  }
  if (!std::isfinite(fhi) || (fhi > 0.0) == (flo > 0.0)) return BeamShape{};
  auto root = brent_root([&](double F) { return mom(F) - moment; }, lo, hi, flo, fhi, 1e-14 * hi + 1e-18, 200);
  if (!root) return BeamShape{};
  return solve_fixed(*root, direction, s_a, with_nodes);
}

BeamShape ElasticaSolver::solve_point(double px, double py, bool with_nodes) const {
  const double L = params_.length;
  if (!std::isfinite(px) || !std::isfinite(py) || px <= 0.0) return BeamShape{};
  const double chord = std::hypot(px, py);
  if (chord > L) return BeamShape{};
  const double sgn = py >= 0.0 ? 1.0 : -1.0;
  const double ty = std::fabs(py);
  if (ty < 1e-12 * L) return solve_normal(0.0, px, with_nodes);
  const double ei = params_.ei_base();
  // Inner: F >= 0 with y(s_a) = |p_y| at this s_a. nullopt if unreachable.
  auto force_for = [&](double s_a) -> std::optional<double> {
    auto f = [&](double F) { return solve_normal(F, s_a).contact_y - ty; };
    double lo = 0.0, flo = -ty;
    double hi = 3.0 * ei * ty / (s_a * s_a * s_a);  // Euler-Bernoulli guess
    double fhi = -1.0;
    for (int i = 0; i < 80; ++i) {
      const BeamShape b = solve_normal(hi, s_a);
      if (!b.ok) return std::nullopt;
      fhi = b.contact_y - ty;
      if (fhi >= 0.0) break;
      if (b.phi_a > kMaxSlope) return std::nullopt;
      lo = hi;
      flo = fhi;
      hi *= 1.6;
    }
    if (fhi < 0.0) return std::nullopt;
    return brent_root(f, lo, hi, flo, fhi, 1e-13 * hi + 1e-20, 200);
  };
  // Outer residual: x(s_a) - p_x, increasing in s_a; unreachable = too short.
  auto r = [&](double s_a) {
    const auto F = force_for(s_a);
    if (!F) return -L;
    return solve_normal(*F, s_a).contact_x - px;
  };
  const double lo = chord * (1.0 + 1e-9), hi = L;
  const double rhi = r(hi);
  if (!(rhi >= 0.0)) return BeamShape{};  // not reachable even with the whole whisker
  const double rlo = r(lo);
  auto s_root = brent_root(r, lo, hi, rlo, rhi, 1e-12 * L, 200);
  if (!s_root) return BeamShape{};
  const auto F = force_for(*s_root);
  if (!F) return BeamShape{};
  BeamShape out = solve_normal(sgn * *F, *s_root, with_nodes);
  if (std::fabs(out.phi_a) > kMaxSlope) return BeamShape{};
  return out;
}

void ElasticaSolver::full_shape(const BeamShape& shape, double length, int n, std::vector<double>& xs,
                                std::vector<double>& ys) {
  xs.resize(n);
  ys.resize(n);
  const std::size_t m = shape.s.size();
  std::size_t j = 0;
  for (int i = 0; i < n; ++i) {
    const double s = length * i / (n - 1);
    if (m >= 2 && s <= shape.s_a) {
      while (j + 2 < m && shape.s[j + 1] < s) ++j;
      const double t = (s - shape.s[j]) / (shape.s[j + 1] - shape.s[j]);
      xs[i] = shape.x[j] + t * (shape.x[j + 1] - shape.x[j]);
      ys[i] = shape.y[j] + t * (shape.y[j + 1] - shape.y[j]);
    } else {
      xs[i] = shape.contact_x + (s - shape.s_a) * std::cos(shape.phi_a);
      ys[i] = shape.contact_y + (s - shape.s_a) * std::sin(shape.phi_a);
    }
  }
}

double euler_bernoulli_deflection(double force, double s_a, double ei) { return force * s_a * s_a * s_a / (3.0 * ei); }

double baseline_distance(double ei, double t_y, double moment) {
  const double q = t_y / moment;
  if (!(q > 0.0) || !std::isfinite(q)) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(3.0 * ei * q);  // 002 eq. 5
}

}  // namespace whisker_localization
