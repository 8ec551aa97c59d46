// The local solver (local_gpis.hpp: local GPs over a quadtree with overlap
// blending, after GPisMap) against the exact GPIS of 000 eq. 33-40 (class
// Gpis), and its incremental update against a rebuild.
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "gpis_explorer/explorer.hpp"
#include "gpis_explorer/local_gpis.hpp"
#include "room_points.hpp"

using gpis_explorer::ExplorerParams;
using gpis_explorer::Gpis;
using gpis_explorer::GpisExplorer;
using gpis_explorer::GpisParams;
using gpis_explorer::GpisSolver;
using gpis_explorer::LocalGpis;
using gpis_explorer::LocalGpisParams;
using Eigen::Vector2d;
using gpis_explorer::test::room_points;

namespace {

Gpis store_of(const GpisParams& gp, const Eigen::Matrix2Xd& X, const Eigen::VectorXd& y) {
  Gpis s(gp, false);
  for (Eigen::Index i = 0; i < X.cols(); ++i) s.add_point(X.col(i), y(i));
  return s;
}

Eigen::Matrix2Xd grid_nodes(int cells, double size = 4.0) {
  Eigen::Matrix2Xd Q(2, cells * cells);
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      Q.col(j * cells + i) = Vector2d(-size / 2 + size * i / (cells - 1), -size / 2 + size * j / (cells - 1));
    }
  }
  return Q;
}

const Eigen::AlignedBox2d kCover(Vector2d(-2, -2), Vector2d(2, 2));

}  // namespace

TEST(LocalGpis, ParamsAreValidated) {
  LocalGpisParams p;
  EXPECT_NO_THROW(p.validate());
  p.min_leaf_size = 0.2;  // < 2 overlap (0.25)
  try {
    p.validate();
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("LocalGpisParams.min_leaf_size: must be >= 2 overlap"), std::string::npos)
        << e.what();
  }
  p = LocalGpisParams{};
  p.overlap = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = LocalGpisParams{};
  p.leaf_points = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_THROW(gpis_explorer::solver_from_string("sparse"), std::invalid_argument);
  EXPECT_EQ(gpis_explorer::solver_from_string("local"), GpisSolver::kLocal);
}

TEST(LocalGpis, AStoreOfPointsOnlyRefusesToPredict) {
  GpisParams gp;
  Gpis s(gp, false);
  EXPECT_EQ(s.add_point({0, 0}, 0.0), gpis_explorer::AddStatus::kAdded);
  EXPECT_EQ(s.add_point({0, 0}, 0.0), gpis_explorer::AddStatus::kDuplicate);
  EXPECT_EQ(s.size(), 1u);
  EXPECT_THROW(s.mean({0, 0}), std::logic_error);
  EXPECT_LT(s.state_bytes(), Gpis(gp).state_bytes());
}

// While every point fits in one leaf the local solver is the exact GP: the
// same mean, variance and curvature, bit for bit (the shipped rooms' budgets).
TEST(LocalGpis, OneLeafIsTheExactGp) {
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(200, 7, X, y);
  GpisParams gp;
  gp.max_points = 200;
  Gpis exact(gp);
  exact.fit(X, y);
  const Gpis store = store_of(gp, X, y);
  LocalGpis local(gp, LocalGpisParams{});
  local.sync(store, kCover);
  ASSERT_EQ(local.leaf_count(), 1u);
  const Eigen::Matrix2Xd Q = grid_nodes(30);
  Eigen::VectorXd me, ve, ml, vl, ke, kl;
  exact.predict_batch(Q, me, ve);
  local.predict_batch(Q, ml, vl);
  exact.curvature_batch(Q, ke);
  local.curvature_batch(Q, kl);
  for (Eigen::Index j = 0; j < Q.cols(); ++j) {
    ASSERT_EQ(ml(j), me(j)) << j;
    ASSERT_EQ(vl(j), ve(j)) << j;
    if (std::isfinite(ke(j))) {
      ASSERT_EQ(kl(j), ke(j)) << j;
    }
  }
  Eigen::VectorXd mb, eb;
  exact.mean_batch(Q, eb);
  local.mean_batch(Q, mb);
  for (Eigen::Index j = 0; j < Q.cols(); ++j) ASSERT_EQ(mb(j), eb(j)) << j;
}

// The documented accuracy (README "Local solver"): on seeded rooms of 1000
// and 2000 points (10-40 leaves), at the grid nodes within 5 cm of a surface
// point (where the contour and the target are taken), the blended mean and
// variance against the exact GP. With 8 label neighbours instead of 96 the
// mean bound fails (max 0.077 at 2000 points).
TEST(LocalGpis, MeanAndVarianceNearTheSurfaceWithinTheDocumentedBound) {
  constexpr double kMeanMax = 0.025, kMeanAvg = 0.005;  // label units (surface 0, interior -1)
  constexpr double kVarMax = 2.5e-4, kVarAvg = 2.5e-5;  // prior variance 1
  for (int n : {1000, 2000}) {
    for (unsigned seed : {1u, 2u, 3u}) {
      Eigen::Matrix2Xd X;
      Eigen::VectorXd y;
      room_points(n, seed, X, y, 0.2 * seed);
      GpisParams gp;
      gp.max_points = static_cast<std::size_t>(n);
      Gpis exact(gp);
      exact.fit(X, y);
      const Gpis store = store_of(gp, X, y);
      LocalGpis local(gp, LocalGpisParams{});
      local.sync(store, kCover);
      ASSERT_GT(local.leaf_count(), 1u);
      const Eigen::Matrix2Xd G = grid_nodes(100);
      std::vector<Eigen::Index> near;
      for (Eigen::Index j = 0; j < G.cols(); ++j) {
        for (Eigen::Index i = 0; i < X.cols(); ++i) {
          if (y(i) == 0.0 && (X.col(i) - G.col(j)).norm() < 0.05) {
            near.push_back(j);
            break;
          }
        }
      }
      Eigen::Matrix2Xd Q(2, static_cast<Eigen::Index>(near.size()));
      for (std::size_t k = 0; k < near.size(); ++k) Q.col(static_cast<Eigen::Index>(k)) = G.col(near[k]);
      Eigen::VectorXd me, ve, ml, vl;
      exact.predict_batch(Q, me, ve);
      local.predict_batch(Q, ml, vl);
      const Eigen::ArrayXd em = (ml - me).array().abs(), ev = (vl - ve).array().abs();
      // A local GP conditions on a subset of the points: its variance is never
      // below the exact one, nor is a convex blend of such variances.
      EXPECT_GE((vl - ve).minCoeff(), -1e-12);
      std::printf("n %d seed %u: %zu leaves (largest local GP %zu points), %zu nodes near the surface: mean error "
                  "max %.2e avg %.2e variance error max %.2e avg %.2e (exact "
                  "variance %.1e..%.1e)\n",
                  n, seed, local.leaf_count(), local.largest_local(), near.size(), em.maxCoeff(), em.mean(),
                  ev.maxCoeff(), ev.mean(), ve.minCoeff(), ve.maxCoeff());
      EXPECT_LE(em.maxCoeff(), kMeanMax);
      EXPECT_LE(em.mean(), kMeanAvg);
      EXPECT_LE(ev.maxCoeff(), kVarMax);
      EXPECT_LE(ev.mean(), kVarAvg);
    }
  }
}

// Gradient and Hessian of the blended mean (weights' derivatives included)
// against central differences of the blended mean, in the overlap ramps.
TEST(LocalGpis, BlendedDerivativesMatchFiniteDifferences) {
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(1500, 4, X, y);
  GpisParams gp;
  gp.max_points = 1500;
  const Gpis store = store_of(gp, X, y);
  LocalGpisParams lp;
  lp.leaf_points = 64;
  LocalGpis local(gp, lp);
  local.sync(store, kCover);
  ASSERT_GT(local.leaf_count(), 8u);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  // Central differences; the gradient's with a small step: the smoothstep is
  // C2, not C3, so the Hessian has kinks at the ramps' ends.
  const double h = 1e-4, hh = 1e-6;
  int checked = 0;
  for (int k = 0; k < 200; ++k) {
    const Vector2d x(u(rng), u(rng));
    double m;
    Vector2d g;
    Eigen::Matrix2d H;
    local.derivatives(x, &m, &g, &H);
    const Vector2d ex(h, 0), ey(0, h);
    const Vector2d gfd((local.mean(x + ex) - local.mean(x - ex)) / (2 * h),
                       (local.mean(x + ey) - local.mean(x - ey)) / (2 * h));
    EXPECT_NEAR(g.x(), gfd.x(), 1e-5 * (1 + g.norm())) << x.transpose();
    EXPECT_NEAR(g.y(), gfd.y(), 1e-5 * (1 + g.norm())) << x.transpose();
    const Vector2d hx(hh, 0), hy(0, hh);
    const Vector2d gx = (local.gradient(x + hx) - local.gradient(x - hx)) / (2 * hh);
    const Vector2d gy = (local.gradient(x + hy) - local.gradient(x - hy)) / (2 * hh);
    EXPECT_NEAR(H(0, 0), gx.x(), 1e-4 * (1 + H.norm())) << x.transpose();
    EXPECT_NEAR(H(0, 1), gy.x(), 1e-4 * (1 + H.norm())) << x.transpose();
    EXPECT_NEAR(H(1, 1), gy.y(), 1e-4 * (1 + H.norm())) << x.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, 200);
}

// Points appended in batches (incremental Cholesky rows, splits, refits of
// displaced label neighbours) give the local GPs of a rebuild from scratch.
TEST(LocalGpis, IncrementalSyncEqualsARebuild) {
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(1200, 9, X, y);
  GpisParams gp;
  gp.max_points = 1200;
  Gpis store(gp, false);
  LocalGpisParams lp;
  lp.leaf_points = 100;
  LocalGpis inc(gp, lp);
  int partial = 0;
  for (Eigen::Index i = 0; i < X.cols(); ++i) {
    store.add_point(X.col(i), y(i));
    if (i % 37 == 36 || i == X.cols() - 1) partial += inc.sync(store, kCover) ? 0 : 1;
  }
  EXPECT_GT(partial, 20);  // appended, not rebuilt
  LocalGpis scratch(gp, lp);
  EXPECT_TRUE(scratch.sync(store, kCover));
  EXPECT_EQ(inc.leaf_count(), scratch.leaf_count());
  const Eigen::Matrix2Xd Q = grid_nodes(60);
  Eigen::VectorXd m1, v1, m2, v2;
  inc.predict_batch(Q, m1, v1);
  scratch.predict_batch(Q, m2, v2);
  EXPECT_LT((m1 - m2).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((v1 - v2).cwiseAbs().maxCoeff(), 1e-9);
}

// The explorer with the local solver: an update after 5 added points (only
// the changed local GPs' grid nodes recomputed) equals a from-scratch update.
TEST(GpisExplorerLocal, IncrementalUpdateEqualsFromScratch) {
  Eigen::Matrix2Xd X;
  Eigen::VectorXd y;
  room_points(2000, 11, X, y);
  ExplorerParams p = ExplorerParams::ground();
  p.solver = GpisSolver::kLocal;
  p.gpis.max_points = 2000;
  p.grid_cells = 120;
  GpisExplorer inc(p);
  inc.fit(X.leftCols(1995), y.head(1995));
  inc.update();
  for (Eigen::Index i = 1995; i < 2000; ++i) inc.add_point(X.col(i), y(i));
  const auto& a = inc.update();
  GpisExplorer scratch(p);
  scratch.fit(X, y);
  const auto& b = scratch.update();
  ASSERT_EQ(a.status, gpis_explorer::UpdateStatus::kOk);
  ASSERT_EQ(a.has_target, b.has_target);
  EXPECT_LT((a.target - b.target).norm(), 1e-9);
  double dm = 0.0, dv = 0.0;
  for (std::size_t k = 0; k < inc.grid_mean().size(); ++k) {
    dm = std::max(dm, std::abs(inc.grid_mean()[k] - scratch.grid_mean()[k]));
    dv = std::max(dv, std::abs(inc.grid_variance()[k] - scratch.grid_variance()[k]));
  }
  EXPECT_LT(dm, 1e-9);
  EXPECT_LT(dv, 1e-9);
  EXPECT_FALSE(inc.gpis().factorized());
}
