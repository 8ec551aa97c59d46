// GPIS core (000 eq. 33-40): posterior against a direct dense computation,
// incremental Cholesky against refactorization, gradient/Hessian against
// finite differences, curvature against the divergence of the unit normal
// and a circle, degenerate inputs.
#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "gpis_explorer/gpis.hpp"

using gpis_explorer::AddStatus;
using gpis_explorer::Gpis;
using gpis_explorer::GpisParams;
using Eigen::Vector2d;

namespace {

Gpis random_gpis(int n, unsigned seed, GpisParams p = {}) {
  p.max_points = static_cast<std::size_t>(std::max(n, 1));
  Gpis g(p);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(g.add_point({u(rng), u(rng)}, (i % 3 == 0) ? -1.0 : 0.0), AddStatus::kAdded);
  }
  return g;
}

}  // namespace

TEST(GpisParams, ValidateNamesField) {
  GpisParams p;
  p.beta = 0.0;
  try {
    p.validate();
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GpisParams.beta"), std::string::npos) << e.what();
  }
  p = GpisParams{};
  p.noise = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = GpisParams{};
  p.max_points = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_NO_THROW(GpisParams{}.validate());
}

TEST(Gpis, KernelIsInverseMultiquadric) {
  Gpis g(GpisParams{});
  // (1 + 3^2 + 4^2)^-0.5 = 26^-0.5 (000 eq. 33, beta 0.5, c 1)
  EXPECT_NEAR(g.kernel({0, 0}, {3, 4}), 1.0 / std::sqrt(26.0), 1e-15);
  EXPECT_DOUBLE_EQ(g.prior_variance(), 1.0);
  GpisParams p;
  p.beta = 1.5;
  p.c = 0.5;
  Gpis h(p);
  EXPECT_NEAR(h.kernel({1, 0}, {0, 0}), std::pow(1.25, -1.5), 1e-15);
  EXPECT_NEAR(h.prior_variance(), std::pow(0.25, -1.5), 1e-12);
}

TEST(Gpis, PosteriorMatchesDenseInverse) {
  const int n = 30;
  Gpis g = random_gpis(n, 3);
  Eigen::MatrixXd K(n, n);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    y(i) = g.label(static_cast<std::size_t>(i));
    for (int j = 0; j < n; ++j) K(i, j) = g.kernel(g.point(static_cast<std::size_t>(i)), g.point(static_cast<std::size_t>(j)));
  }
  const Eigen::MatrixXd A = (K + 1e-2 * Eigen::MatrixXd::Identity(n, n)).inverse();  // 000 eq. 34-35
  for (const Vector2d& q : {Vector2d(0.1, 0.2), Vector2d(-1.0, 1.3), Vector2d(3.0, -2.0)}) {
    Eigen::VectorXd k(n);
    for (int i = 0; i < n; ++i) k(i) = g.kernel(q, g.point(static_cast<std::size_t>(i)));
    double m = 0, v = 0;
    g.predict(q, &m, &v);
    EXPECT_NEAR(m, k.dot(A * y), 1e-9);
    EXPECT_NEAR(v, 1.0 - k.dot(A * k), 1e-9);
    EXPECT_NEAR(g.mean(q), m, 1e-12);
  }
  // Batch prediction equals the point-wise one.
  Eigen::Matrix2Xd Q = Eigen::Matrix2Xd::Random(2, 1100) * 2.0;
  Eigen::VectorXd bm, bv;
  g.predict_batch(Q, bm, bv);
  for (Eigen::Index j = 0; j < Q.cols(); j += 37) {
    double m = 0, v = 0;
    g.predict(Q.col(j), &m, &v);
    EXPECT_NEAR(bm(j), m, 1e-12);
    EXPECT_NEAR(bv(j), v, 1e-12);
  }
}

TEST(Gpis, IncrementalCholeskyEqualsRefactorization) {
  GpisParams p;
  p.max_points = 600;  // crosses the 256 initial capacity (growth path)
  Gpis g = random_gpis(600, 5, p);
  const Eigen::MatrixXd L1 = g.cholesky();
  const Eigen::VectorXd a1 = g.alpha();
  g.refactorize();
  EXPECT_LT((L1 - g.cholesky()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((a1 - g.alpha()).cwiseAbs().maxCoeff() / a1.cwiseAbs().maxCoeff(), 1e-6);
}

TEST(Gpis, GradientAndHessianMatchFiniteDifferences) {
  for (double beta : {0.5, 1.0, 1.7}) {
    GpisParams p;
    p.beta = beta;
    p.c = 0.7;
    Gpis g = random_gpis(25, 11, p);
    const double h = 1e-5;
    for (const Vector2d& x : {Vector2d(0.3, -0.2), Vector2d(1.1, 0.9), Vector2d(-2.0, 0.5)}) {
      Eigen::Vector2d grad;
      Eigen::Matrix2d H;
      g.derivatives(x, &grad, &H);
      for (int d = 0; d < 2; ++d) {
        const Vector2d e = Vector2d::Unit(d) * h;
        const double fd = (g.mean(x + e) - g.mean(x - e)) / (2 * h);
        EXPECT_NEAR(grad(d), fd, 1e-7 * std::max(1.0, std::abs(fd))) << "beta " << beta;
        const Vector2d gfd = (g.gradient(x + e) - g.gradient(x - e)) / (2 * h);
        EXPECT_NEAR(H(0, d), gfd(0), 1e-6 * std::max(1.0, gfd.norm())) << "beta " << beta;
        EXPECT_NEAR(H(1, d), gfd(1), 1e-6 * std::max(1.0, gfd.norm())) << "beta " << beta;
      }
      EXPECT_NEAR(H(0, 1), H(1, 0), 1e-12);
      EXPECT_TRUE(g.gradient(x).isApprox(grad));
      EXPECT_TRUE(g.hessian(x).isApprox(H));
    }
  }
}

TEST(Gpis, CurvatureIsMinusDivergenceOfUnitNormal) {
  // eq. 40 = -div(grad f / |grad f|), checked by finite differences of the normal.
  Gpis g = random_gpis(20, 17);
  const double h = 1e-4;
  for (const Vector2d& x : {Vector2d(0.2, 0.1), Vector2d(-0.7, 0.4)}) {
    auto normal = [&](const Vector2d& p) { return Vector2d(g.gradient(p).normalized()); };
    const double div = (normal(x + Vector2d(h, 0)).x() - normal(x - Vector2d(h, 0)).x()) / (2 * h) +
                       (normal(x + Vector2d(0, h)).y() - normal(x - Vector2d(0, h)).y()) / (2 * h);
    EXPECT_NEAR(g.curvature(x), -div, 1e-4 * std::max(1.0, std::abs(div)));
  }
}

TEST(Gpis, CircleOfSurfacePointsHasCurvatureMinusOneOverR) {
  // Room-like closed surface: interior -1 at the centre, surface 0 on a circle.
  GpisParams p;
  p.max_points = 100;
  Gpis g(p);
  const double R = 0.8;
  for (int i = 0; i < 36; ++i) {
    const double a = 2 * M_PI * i / 36;
    ASSERT_EQ(g.add_point({R * std::cos(a), R * std::sin(a)}, 0.0), AddStatus::kAdded);
  }
  ASSERT_EQ(g.add_point({0, 0}, -1.0), AddStatus::kAdded);
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / 8;
    const Vector2d x(R * std::cos(a), R * std::sin(a));
    EXPECT_NEAR(g.mean(x), 0.0, 0.02);
    EXPECT_NEAR(g.curvature(x), -1.0 / R, 0.15 / R) << "angle " << a;
    EXPECT_GT(g.gradient(x).dot(x), 0.0);  // mean grows outward
  }
  // Variance is small on the data and larger away from it.
  double v_on = 0, v_far = 0;
  g.predict({R, 0.0}, nullptr, &v_on);
  g.predict({5.0, 5.0}, nullptr, &v_far);
  EXPECT_LT(v_on, 0.02);
  EXPECT_GT(v_far, 0.5);
}

TEST(Gpis, DegenerateInputs) {
  GpisParams p;
  p.max_points = 4;
  Gpis g(p);
  // No points: prior.
  double m = 1, v = 0;
  g.predict({0, 0}, &m, &v);
  EXPECT_EQ(m, 0.0);
  EXPECT_EQ(v, 1.0);
  EXPECT_TRUE(std::isnan(g.curvature({0, 0})));  // zero gradient
  EXPECT_EQ(g.add_point({NAN, 0}, 0.0), AddStatus::kNonFinite);
  EXPECT_EQ(g.add_point({0, 0}, NAN), AddStatus::kBadLabel);
  EXPECT_EQ(g.add_point({0, 0}, 0.0), AddStatus::kAdded);
  EXPECT_EQ(g.add_point({0, 0}, 0.0), AddStatus::kDuplicate);
  EXPECT_EQ(g.add_point({0, 0}, -1.0), AddStatus::kAdded);  // conflicting label: the noise term averages
  EXPECT_TRUE(g.alpha().allFinite());
  EXPECT_EQ(g.add_point({1, 0}, 0.0), AddStatus::kAdded);
  EXPECT_EQ(g.add_point({2, 0}, 0.0), AddStatus::kAdded);
  EXPECT_EQ(g.add_point({3, 0}, 0.0), AddStatus::kBudgetFull);
  EXPECT_EQ(g.size(), 4u);
  EXPECT_EQ(g.surface_count(), 3u);
  g.clear();
  EXPECT_TRUE(g.empty());
  EXPECT_EQ(g.add_point({3, 0}, 0.0), AddStatus::kAdded);
}

TEST(Gpis, CollinearPoints) {
  Eigen::Matrix2Xd line(2, 5);
  line << 0, 1, 2, 3, 4, 0, 0.5, 1, 1.5, 2;
  EXPECT_TRUE(gpis_explorer::points_collinear(line));
  line(1, 2) = 1.3;
  EXPECT_FALSE(gpis_explorer::points_collinear(line));
  EXPECT_TRUE(gpis_explorer::points_collinear(line.leftCols(2)));
  // Collinear training points still give a finite posterior.
  Gpis g(GpisParams{});
  for (int i = 0; i < 5; ++i) ASSERT_EQ(g.add_point({i * 0.3, 0.0}, 0.0), AddStatus::kAdded);
  double m = 0, v = 0;
  g.predict({0.5, 0.5}, &m, &v);
  EXPECT_TRUE(std::isfinite(m) && std::isfinite(v));
}

TEST(Gpis, OnboardStateBytes) {
  Gpis g(GpisParams{});
  // 50 points: 2*50 + 50 + 50 + 50 + 50*50 doubles = 2750 * 8 bytes.
  EXPECT_EQ(g.state_bytes(), 2750u * 8u);
}

TEST(Gpis, BatchFitEqualsIncrementalAndPopBackUndoesAdd) {
  Gpis inc = random_gpis(40, 23);
  Eigen::Matrix2Xd X(2, 42);
  Eigen::VectorXd y(42);
  for (int i = 0; i < 40; ++i) {
    X.col(i) = inc.point(static_cast<std::size_t>(i));
    y(i) = inc.label(static_cast<std::size_t>(i));
  }
  X.col(40) = X.col(3);  // duplicate: skipped
  y(40) = y(3);
  X.col(41) << NAN, 0.0;  // non-finite: skipped
  y(41) = 0.0;
  GpisParams p;
  p.max_points = 40;
  Gpis batch(p);
  EXPECT_EQ(batch.fit(X, y), 40u);
  EXPECT_LT((batch.cholesky() - inc.cholesky()).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((batch.alpha() - inc.alpha()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_EQ(batch.surface_count(), inc.surface_count());
  EXPECT_THROW(batch.fit(X, y.head(3)), std::invalid_argument);
  // pop_back restores the posterior of the first n-1 points.
  Gpis g = random_gpis(10, 29);
  const double m10 = g.mean({0.2, 0.3});
  GpisParams q;
  q.max_points = 10;
  Gpis first9(q);
  for (std::size_t i = 0; i < 9; ++i) ASSERT_EQ(first9.add_point(g.point(i), g.label(i)), AddStatus::kAdded);
  g.pop_back();
  EXPECT_EQ(g.size(), 9u);
  EXPECT_NEAR(g.mean({0.2, 0.3}), first9.mean({0.2, 0.3}), 1e-12);
  EXPECT_NE(m10, g.mean({0.2, 0.3}));
  Gpis e(GpisParams{});
  e.pop_back();
  EXPECT_TRUE(e.empty());
}

// remove(i) gives the posterior of the other points, fitted afresh (the later
// points move up one index); out of range changes nothing.
TEST(Gpis, RemoveEqualsAFitWithoutThePoint) {
  Gpis g = random_gpis(12, 31);
  GpisParams q;
  q.max_points = 12;
  Gpis rest(q);
  for (std::size_t i = 0; i < 12; ++i) {
    if (i != 4) {
      ASSERT_EQ(rest.add_point(g.point(i), g.label(i)), AddStatus::kAdded);
    }
  }
  const Vector2d x5 = g.point(5);
  const std::size_t surfaces = g.surface_count();
  const bool removed_surface = g.label(4) == 0.0;
  g.remove(4);
  EXPECT_EQ(g.size(), 11u);
  EXPECT_EQ(g.surface_count(), surfaces - (removed_surface ? 1u : 0u));
  EXPECT_EQ(g.point(4), x5);
  for (const Vector2d& x : {Vector2d(0.2, 0.3), Vector2d(-1.0, 0.7), Vector2d(1.4, -1.2)}) {
    double m = 0, v = 0, mr = 0, vr = 0;
    g.predict(x, &m, &v);
    rest.predict(x, &mr, &vr);
    EXPECT_NEAR(m, mr, 1e-10);
    EXPECT_NEAR(v, vr, 1e-10);
  }
  g.remove(11);  // out of range (11 points left)
  EXPECT_EQ(g.size(), 11u);
  // The freed slot takes a new point.
  EXPECT_EQ(g.add_point({0.9, 0.9}, 0.0), AddStatus::kAdded);
  EXPECT_EQ(g.size(), 12u);
}
