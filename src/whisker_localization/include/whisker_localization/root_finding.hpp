// Bracketed scalar root finder (Brent's method) used by the elastica solver
// and the contact-set builders. Robust: converges for any sign change, falls
// back to bisection when interpolation misbehaves.
#pragma once

#include <cmath>
#include <optional>
#include <utility>

namespace whisker_localization {

/// Root of f in [a, b] given f(a) = fa and f(b) = fb of opposite signs (or
/// one of them zero). Stops when the bracket is below `xtol` or after
/// `max_iter`. Returns nullopt if [a, b] is not a bracket.
template <typename F>
std::optional<double> brent_root(F&& f, double a, double b, double fa, double fb, double xtol,
                                 int max_iter = 100) {
  if (!(std::isfinite(fa) && std::isfinite(fb))) return std::nullopt;
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  if ((fa > 0.0) == (fb > 0.0)) return std::nullopt;
  double c = a, fc = fa, d = b - a, e = d;
  for (int it = 0; it < max_iter; ++it) {
    if ((fb > 0.0) == (fc > 0.0)) {
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (std::fabs(fc) < std::fabs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double tol = 2.0 * 1e-15 * std::fabs(b) + 0.5 * xtol;
    const double m = 0.5 * (c - b);
    if (std::fabs(m) <= tol || fb == 0.0) return b;
    if (std::fabs(e) >= tol && std::fabs(fa) > std::fabs(fb)) {
      double p, q, r;
      const double s = fb / fa;
      if (a == c) {
        p = 2.0 * m * s;
        q = 1.0 - s;
      } else {
        q = fa / fc;
        r = fb / fc;
        p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
        q = (q - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0.0) q = -q;
      p = std::fabs(p);
      if (2.0 * p < std::fmin(3.0 * m * q - std::fabs(tol * q), std::fabs(e * q))) {
        e = d;
        d = p / q;
      } else {
        d = m;
        e = m;
      }
    } else {
      d = m;
      e = m;
    }
    a = b;
    fa = fb;
    b += (std::fabs(d) > tol) ? d : (m > 0.0 ? tol : -tol);
    fb = f(b);
    if (!std::isfinite(fb)) return std::nullopt;
  }
  return b;
}

}  // namespace whisker_localization
