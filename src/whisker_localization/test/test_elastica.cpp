// Elastica solver against independent references: Euler-Bernoulli small
// deflection, the elliptic-integral form of 002 eq. 1-2 (own quadrature, no
// ODE), a tapered beam by virtual work, force -> point mode round trips.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

#include "whisker_localization/elastica.hpp"

using namespace whisker_localization;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Composite Gauss-Legendre (5 points) on n panels.
double integrate(const std::function<double(double)>& f, double a, double b, int n = 400) {
  static const double xg[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640, 0.9061798459386640};
  static const double wg[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665, 0.2369268850561891,
                               0.2369268850561891};
  double sum = 0.0;
  const double h = (b - a) / n;
  for (int i = 0; i < n; ++i) {
    const double m = a + (i + 0.5) * h;
    for (int k = 0; k < 5; ++k) sum += 0.5 * h * wg[k] * f(m + 0.5 * h * xg[k]);
  }
  return sum;
}

// 002 eq. 1-2 for a vertical load F with end slope phi_a: the substitution
// phi = phi_a - t^2 removes the inverse-square-root singularity at phi_a.
struct Elliptic {
  double s_a, x_a, y_a;
};
Elliptic elliptic(double F, double ei, double phi_a) {
  const double k = std::sqrt(ei / (2.0 * F));
  const double tmax = std::sqrt(phi_a);
  auto w = [&](double t) {
    const double phi = phi_a - t * t;
    const double den = std::sqrt(std::sin(phi_a) - std::sin(phi));
    return t == 0.0 ? 2.0 / std::sqrt(std::cos(phi_a)) : 2.0 * t / den;
  };
  Elliptic e;
  e.s_a = k * integrate([&](double t) { return w(t); }, 0.0, tmax);                          // eq. 2
  e.x_a = k * integrate([&](double t) { return w(t) * std::cos(phi_a - t * t); }, 0.0, tmax);  // eq. 1
  e.y_a = k * integrate([&](double t) { return w(t) * std::sin(phi_a - t * t); }, 0.0, tmax);  // eq. 1
  return e;
}

}  // namespace

TEST(Elastica, DefaultsAreThePaperSensor) {
  const BeamParams p;
  EXPECT_DOUBLE_EQ(p.length, 0.075);
  EXPECT_DOUBLE_EQ(p.youngs_modulus, 52e9);
  EXPECT_DOUBLE_EQ(p.moment_of_inertia, 5.555e-15);
  // I = pi d^4 / 64 with d = 0.58 mm (002 Sec. V-A).
  EXPECT_NEAR(kPi * std::pow(0.58e-3, 4) / 64.0, p.moment_of_inertia, 1e-17);
}

TEST(Elastica, ValidateNamesTheField) {
  BeamParams p;
  p.length = -1.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("BeamParams.length"), std::string::npos);
  }
  p = BeamParams{};
  p.taper_ratio = 1.5;
  EXPECT_THROW(ElasticaSolver{p}, std::invalid_argument);
  p = BeamParams{};
  p.n_segments = 2;
  EXPECT_THROW(ElasticaSolver{p}, std::invalid_argument);
}

TEST(Elastica, SmallDeflectionMatchesEulerBernoulli) {
  const ElasticaSolver solver{BeamParams{}};
  const double ei = solver.params().ei_base();
  for (double s_a : {0.03, 0.05, 0.075}) {
    const double F = 1e-5;  // tip deflection ~ 1e-4 L at 75 mm
    for (const BeamShape& b : {solver.solve_normal(F, s_a), solver.solve_fixed(F, kPi / 2, s_a)}) {
      ASSERT_TRUE(b.ok);
      EXPECT_NEAR(b.base_moment, F * s_a, 1e-4 * F * s_a);  // 002 eq. 15
      EXPECT_NEAR(b.contact_y, euler_bernoulli_deflection(F, s_a, ei), 1e-3 * euler_bernoulli_deflection(F, s_a, ei));
      EXPECT_NEAR(b.phi_a, F * s_a * s_a / (2 * ei), 1e-3 * F * s_a * s_a / (2 * ei));
    }
  }
  // Tip load: tip deflection F L^3 / 3EI.
  const BeamShape tip = solver.solve_normal(1e-5, 0.075);
  EXPECT_NEAR(tip.tip_y, 1e-5 * std::pow(0.075, 3) / (3 * ei), 1e-3 * tip.tip_y);
}

TEST(Elastica, VerticalLoadMatchesEllipticIntegralsAtLargeAngles) {
  const ElasticaSolver solver{BeamParams{}};
  const double ei = solver.params().ei_base();
  for (double phi_a : {0.3, 0.7, 1.0, 1.3}) {
    // eq. 2: s_a scales as F^-1/2; pick F so the load sits at s_a = 60 mm.
    const double F = std::pow(elliptic(1.0, ei, phi_a).s_a / 0.06, 2);
    const Elliptic e = elliptic(F, ei, phi_a);
    ASSERT_NEAR(e.s_a, 0.06, 1e-9);
    ASSERT_LE(e.s_a, 0.075);
    const BeamShape b = solver.solve_fixed(F, kPi / 2, e.s_a, true);
    ASSERT_TRUE(b.ok) << phi_a;
    EXPECT_NEAR(b.phi_a, phi_a, 1e-6) << phi_a;
    EXPECT_NEAR(b.contact_x, e.x_a, 1e-7) << phi_a;
    EXPECT_NEAR(b.contact_y, e.y_a, 1e-7) << phi_a;
    EXPECT_NEAR(b.base_moment, F * e.x_a, 1e-9);  // 002 eq. 4 at s = 0: M(0) = F x(s_a)
    // Large angle: the horizontal deflection is far from negligible.
    if (phi_a >= 1.0) {
      EXPECT_GT(e.s_a - e.x_a, 0.1 * e.s_a);
    }
    // Node output: first node is the clamped base, last is the contact point.
    EXPECT_NEAR(b.x.front(), 0.0, 1e-12);
    EXPECT_NEAR(b.phi.front(), 0.0, 1e-6);
    EXPECT_NEAR(b.x.back(), e.x_a, 1e-7);
  }
}

TEST(Elastica, NormalLoadEquilibrium) {
  const ElasticaSolver solver{BeamParams{}};
  const BeamShape b = solver.solve_normal(0.1, 0.06, true);
  ASSERT_TRUE(b.ok);
  // Load normal to the whisker at s_a.
  EXPECT_NEAR(b.force_x * std::cos(b.phi_a) + b.force_y * std::sin(b.phi_a), 0.0, 1e-12);
  EXPECT_NEAR(std::hypot(b.force_x, b.force_y), 0.1, 1e-12);
  EXPECT_GT(b.phi_a, 0.5);  // large deflection
  // Base moment of the load about the base (002 eq. 4 with both components).
  EXPECT_NEAR(b.base_moment, b.contact_x * b.force_y - b.contact_y * b.force_x, 1e-8 * std::fabs(b.base_moment));
  EXPECT_DOUBLE_EQ(b.base_force_x, -b.force_x);
  // Curvature at the base equals M(0)/EI: finite difference of the node slopes.
  const double h = b.s[1] - b.s[0];
  EXPECT_NEAR((b.phi[1] - b.phi[0]) / h, b.base_moment / solver.params().ei_base(), 0.02 * b.base_moment / solver.params().ei_base());
  // Mirror symmetry of a negative load.
  const BeamShape m = solver.solve_normal(-0.1, 0.06);
  EXPECT_NEAR(m.contact_y, -b.contact_y, 1e-12);
  EXPECT_NEAR(m.base_moment, -b.base_moment, 1e-12);
}

TEST(Elastica, TaperedBeamMatchesVirtualWork) {
  BeamParams p;
  p.taper_ratio = 0.5;
  const ElasticaSolver solver{p};
  const double F = 2e-6, L = p.length;
  // Small deflection: delta = int_0^L F (L - s)^2 / EI(s) ds.
  const double ref = integrate([&](double s) { return F * (L - s) * (L - s) / p.ei_at(s); }, 0.0, L);
  const BeamShape b = solver.solve_normal(F, L);
  EXPECT_NEAR(b.contact_y, ref, 2e-3 * ref);
  // Softer than the uniform whisker under the same load.
  EXPECT_GT(b.contact_y, ElasticaSolver{BeamParams{}}.solve_normal(F, L).contact_y * 1.5);
}

TEST(Elastica, ForceModePointModeRoundTrip) {
  for (double taper : {1.0, 0.6}) {
    BeamParams p;
    p.taper_ratio = taper;
    const ElasticaSolver solver{p};
    for (double s_a : {0.035, 0.05, 0.07}) {
      for (double F : {1e-4, 2e-2, 0.1, -0.05}) {
        const BeamShape f = solver.solve_normal(F, s_a);
        if (std::fabs(f.phi_a) > ElasticaSolver::kMaxSlope) continue;
        const BeamShape pt = solver.solve_point(f.contact_x, f.contact_y);
        ASSERT_TRUE(pt.ok) << taper << " " << s_a << " " << F;
        EXPECT_NEAR(pt.s_a, s_a, 1e-8) << taper << " " << s_a << " " << F;
        EXPECT_NEAR(pt.force, F, 1e-6 * std::fabs(F)) << taper << " " << s_a << " " << F;
        EXPECT_NEAR(pt.base_moment, f.base_moment, 1e-6 * std::fabs(f.base_moment));
      }
    }
  }
}

TEST(Elastica, PointModeOutOfReach) {
  const ElasticaSolver solver{BeamParams{}};
  EXPECT_FALSE(solver.solve_point(0.08, 0.0).ok);   // beyond L
  EXPECT_FALSE(solver.solve_point(-0.01, 0.01).ok);  // behind the base
  EXPECT_FALSE(solver.solve_point(0.07, 0.03).ok);  // chord > L
  EXPECT_FALSE(solver.solve_point(std::nan(""), 0.01).ok);
  const BeamShape z = solver.solve_point(0.05, 0.0);
  ASSERT_TRUE(z.ok);
  EXPECT_DOUBLE_EQ(z.base_moment, 0.0);
}

TEST(Elastica, MomentModeInvertsForceMode) {
  const ElasticaSolver solver{BeamParams{}};
  for (double s_a : {0.03, 0.05, 0.075}) {
    const BeamShape f = solver.solve_normal(0.05, s_a);
    const BeamShape m = solver.solve_moment(f.base_moment, s_a);
    ASSERT_TRUE(m.ok);
    EXPECT_NEAR(m.force, 0.05, 1e-9);
    const BeamShape mf = solver.solve_moment_fixed(f.base_moment, f.phi_a + kPi / 2, s_a);
    ASSERT_TRUE(mf.ok);
    EXPECT_NEAR(mf.force, 0.05, 1e-7);  // the same load seen as a fixed direction
    EXPECT_NEAR(mf.phi_a, f.phi_a, 1e-7);
  }
  EXPECT_FALSE(solver.solve_moment(1.0, 0.05).ok);  // far beyond the elastic range
}

TEST(Elastica, BaselineEq5) {
  const double ei = 52e9 * 5.555e-15, d = 0.05, t = 1e-3;
  EXPECT_NEAR(baseline_distance(ei, t, 3 * ei * t / (d * d)), d, 1e-12);
  EXPECT_TRUE(std::isnan(baseline_distance(ei, t, 0.0)));
  EXPECT_TRUE(std::isnan(baseline_distance(ei, -t, 1e-4)));
}

TEST(Elastica, ConvergesWithSegments) {
  BeamParams coarse;
  coarse.n_segments = 16;
  BeamParams fine;
  fine.n_segments = 1024;
  const BeamShape a = ElasticaSolver{coarse}.solve_normal(0.12, 0.07);
  const BeamShape b = ElasticaSolver{fine}.solve_normal(0.12, 0.07);
  EXPECT_GT(std::fabs(a.phi_a), 0.5);
  EXPECT_NEAR(a.contact_y, b.contact_y, 1e-6);  // RK4, h^4: 16 steps already within 1 um
}
