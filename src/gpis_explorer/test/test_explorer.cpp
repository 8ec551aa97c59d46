// Corner clustering, penalty, acquisition and target selection (000 eq. 41-46)
// and the degenerate inputs of an exploration update.
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "gpis_explorer/explorer.hpp"

using gpis_explorer::AddStatus;
using gpis_explorer::cluster_corners;
using gpis_explorer::corner_penalty;
using gpis_explorer::ExplorerParams;
using gpis_explorer::GpisExplorer;
using gpis_explorer::UpdateStatus;
using Eigen::Vector2d;

namespace {

std::vector<Vector2d> line_points(int n) {
  std::vector<Vector2d> p;
  for (int i = 0; i < n; ++i) p.emplace_back(i, 0.0);
  return p;
}

/// Surface points on the walls of a square room of half side h centred at 0,
/// leaving out |x| < gap/2 on the top wall, and interior points inside.
void add_room(GpisExplorer& ex, double h, double gap, double step = 0.2) {
  for (double s = -h; s <= h + 1e-9; s += step) {
    ASSERT_NE(ex.add_point({s, -h}, 0.0), AddStatus::kBudgetFull);
    if (std::abs(s) >= gap / 2) {
      ASSERT_NE(ex.add_point({s, h}, 0.0), AddStatus::kBudgetFull);
    }
    ASSERT_NE(ex.add_point({-h, s}, 0.0), AddStatus::kBudgetFull);
    ASSERT_NE(ex.add_point({h, s}, 0.0), AddStatus::kBudgetFull);
  }
  for (double x : {-0.5 * h, 0.0, 0.5 * h}) {
    for (double y : {-0.5 * h, 0.0, 0.5 * h}) ASSERT_EQ(ex.add_point({x, y}, -1.0), AddStatus::kAdded);
  }
}

}  // namespace

TEST(ClusterCorners, RunsCentroidsAndWrapMerge) {
  const auto P = line_points(10);
  // Two runs: indices 2-3 and 6-8.
  const std::vector<double> k{0, 0, -2, -3, 0, 0, -2, -2, -2, 0};
  auto c = cluster_corners(P, k, false, -1.0);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[0].x(), 2.5);  // eq. 42
  EXPECT_DOUBLE_EQ(c[1].x(), 7.0);
  // Runs at both ends of a closed contour are one corner: (c_1 + c_m)/2 (eq. 43).
  const std::vector<double> w{-2, -2, 0, 0, -5, 0, 0, 0, -2, -2};
  c = cluster_corners(P, w, true, -1.0);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[0].x(), 0.5 * (0.5 + 8.5));
  EXPECT_DOUBLE_EQ(c[1].x(), 4.0);
  // Open contour: no merge.
  EXPECT_EQ(cluster_corners(P, w, false, -1.0).size(), 3u);
  // NaN breaks a run and is never a corner; threshold is strict.
  const std::vector<double> nanrun{-2, NAN, -2, -1.0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(cluster_corners(P, nanrun, false, -1.0).size(), 2u);
  // All points in one run of a closed contour: a single centroid.
  EXPECT_EQ(cluster_corners(P, std::vector<double>(10, -3.0), true, -1.0).size(), 1u);
  EXPECT_TRUE(cluster_corners({}, {}, true, -1.0).empty());
  EXPECT_THROW(cluster_corners(P, {1.0}, true, -1.0), std::invalid_argument);
}

TEST(CornerPenalty, HandValues) {
  EXPECT_EQ(corner_penalty({0, 0}, {}, 0.2), 0.0);
  const std::vector<Vector2d> cs{{0, 0}, {1, 0}};
  EXPECT_DOUBLE_EQ(corner_penalty({0, 0}, cs, 0.2), -1.0);
  // 0.2 from the first corner: -exp(-0.04/0.08) = -exp(-0.5) (eq. 45)
  EXPECT_NEAR(corner_penalty({0.2, 0}, cs, 0.2), -std::exp(-0.5), 1e-15);
  // min over corners = the nearest one dominates
  EXPECT_NEAR(corner_penalty({0.9, 0}, cs, 0.2), -std::exp(-0.01 / 0.08), 1e-15);
}

TEST(ExplorerParams, ValidateAndBudgets) {
  EXPECT_NO_THROW(ExplorerParams::onboard().validate());
  EXPECT_EQ(ExplorerParams::onboard().gpis.max_points, 50u);
  EXPECT_EQ(ExplorerParams::onboard().grid_cells, 10u);
  EXPECT_EQ(ExplorerParams::ground().grid_cells, 100u);
  ExplorerParams p;
  p.corner_curvature = 0.5;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ExplorerParams.corner_curvature"), std::string::npos);
  }
}

TEST(Explorer, DegenerateStatuses) {
  GpisExplorer ex(ExplorerParams::onboard());
  EXPECT_EQ(ex.update().status, UpdateStatus::kNoPoints);
  EXPECT_FALSE(ex.last().has_target);
  // Open space: probes in four directions found no wall, only interior points.
  for (const Vector2d& p : {Vector2d(1, 0), Vector2d(0, 1), Vector2d(-1, 0), Vector2d(0, -1)}) {
    ASSERT_EQ(ex.add_point(p, -1.0), AddStatus::kAdded);
  }
  EXPECT_EQ(ex.update().status, UpdateStatus::kNoSurfacePoints);
  // Surface points far off the grid: no contour on it.
  ex.clear();
  ASSERT_EQ(ex.add_point({30, 30}, 0.0), AddStatus::kAdded);
  ASSERT_EQ(ex.add_point({0, 0}, -1.0), AddStatus::kAdded);
  EXPECT_EQ(ex.update().status, UpdateStatus::kNoContour);
  // All points on a line: flagged, still an answer (open contour).
  ex.clear();
  for (int i = 0; i < 5; ++i) ASSERT_EQ(ex.add_point({-1.0 + 0.5 * i, 1.0}, 0.0), AddStatus::kAdded);
  for (int i = 0; i < 5; ++i) ASSERT_EQ(ex.add_point({-1.0 + 0.5 * i, 0.0}, -1.0), AddStatus::kAdded);
  const auto& r = ex.update();
  EXPECT_FALSE(r.collinear);  // two parallel lines are not one line
  ex.clear();
  for (int i = 0; i < 5; ++i) ASSERT_EQ(ex.add_point({-1.0 + 0.5 * i, 0.5}, i % 2 ? 0.0 : -1.0), AddStatus::kAdded);
  const auto& r2 = ex.update();
  EXPECT_TRUE(r2.collinear);
  for (const auto& c : r2.contours) EXPECT_FALSE(c.contour.closed);
  EXPECT_EQ(r2.closed_contours, 0u);
  EXPECT_EQ(ex.updates(), 5u);
}

TEST(Explorer, ClosedRoomHasFourCornersAndTargetAwayFromThem) {
  ExplorerParams p = ExplorerParams::ground();
  p.grid_cells = 60;
  GpisExplorer ex(p);
  add_room(ex, 1.0, 0.0);
  const auto& r = ex.update();
  ASSERT_EQ(r.status, UpdateStatus::kOk);
  ASSERT_GE(r.closed_contours, 1u);
  // The contour of the room follows the walls.
  const auto& room = r.contours.front();
  double max_dev = 0;
  for (const auto& q : room.contour.points) {
    if (q.cwiseAbs().maxCoeff() > 1.6) continue;  // other contours outside
    max_dev = std::max(max_dev, std::abs(q.cwiseAbs().maxCoeff() - 1.0));
  }
  EXPECT_LT(max_dev, 0.15);
  ASSERT_EQ(r.corners.size(), 4u);
  for (const auto& c : r.corners) {
    EXPECT_NEAR(std::abs(c.x()), 0.9, 0.15) << c.transpose();
    EXPECT_NEAR(std::abs(c.y()), 0.9, 0.15) << c.transpose();
  }
  ASSERT_TRUE(r.has_target);
  for (const auto& c : r.corners) EXPECT_GE((r.target - c).norm(), p.corner_exclusion);
}

TEST(Explorer, RoomWithExitTargetsTheOpening) {
  for (const auto& base : {ExplorerParams::onboard(), ExplorerParams::ground()}) {
    ExplorerParams p = base;
    p.gpis.max_points = 200;
    GpisExplorer ex(p);
    add_room(ex, 1.0, 0.8, 0.25);
    const auto& r = ex.update();
    ASSERT_EQ(r.status, UpdateStatus::kOk) << to_string(r.status);
    ASSERT_TRUE(r.has_target);
    // The most uncertain safe contour point is in front of / beyond the 80 cm gap.
    EXPECT_LT(std::abs(r.target.x()), 0.5) << r.target.transpose() << " grid " << p.grid_cells;
    EXPECT_GT(r.target.y(), 0.9) << r.target.transpose() << " grid " << p.grid_cells;
  }
}

TEST(Explorer, StateBytesOfTheOnboardBudget) {
  GpisExplorer ex(ExplorerParams::onboard());
  // GPIS 2750 doubles + 10x10 mean and variance.
  EXPECT_EQ(ex.state_bytes(), (2750u + 200u) * 8u);
}

TEST(Explorer, GridVarianceOffGivesTheSameTarget) {
  ExplorerParams p = ExplorerParams::onboard();
  p.gpis.max_points = 200;
  GpisExplorer a(p);
  p.grid_variance = false;
  GpisExplorer b(p);
  add_room(a, 1.0, 0.8, 0.25);
  add_room(b, 1.0, 0.8, 0.25);
  const auto ra = a.update();
  const auto& rb = b.update();
  ASSERT_TRUE(ra.has_target && rb.has_target);
  // The room is mirror-symmetric: equal acquisition (a tie may pick the mirror point).
  EXPECT_NEAR(ra.target_acquisition, rb.target_acquisition, 1e-9);
  EXPECT_NEAR(std::abs(ra.target.x()), std::abs(rb.target.x()), 1e-9);
  EXPECT_NEAR(ra.target.y(), rb.target.y(), 1e-9);
  EXPECT_EQ(ra.corners.size(), rb.corners.size());
  EXPECT_TRUE(std::isnan(b.grid_variance()[0]));
  for (std::size_t k = 0; k < a.grid_mean().size(); ++k) EXPECT_NEAR(a.grid_mean()[k], b.grid_mean()[k], 1e-12);
}

// The coarse variance map (variance_cells) is kept between updates: the rows of
// points added since (incremental Cholesky rows) extend L^-1 k(X, q); after
// pop_back and new points, and against a map computed from scratch and the
// exact variance at its nodes (000 eq. 35).
TEST(Explorer, VarianceMapKeptBetweenUpdatesEqualsFromScratch) {
  ExplorerParams p = ExplorerParams::onboard();
  p.gpis.max_points = 300;
  p.grid_cells = 41;
  p.variance_cells = 11;
  GpisExplorer inc(p), scratch(p);
  std::vector<std::pair<Vector2d, double>> pts;
  for (int i = 0; i < 120; ++i) {
    const double t = -1.0 + 2.0 * (i / 4 + 0.5) / 30.0;
    const Vector2d q = i % 4 == 0 ? Vector2d(t, -1.0) : i % 4 == 1 ? Vector2d(t, 1.0) : i % 4 == 2 ? Vector2d(-1.0, t) : Vector2d(1.0, t);
    pts.emplace_back(Eigen::Rotation2Dd(0.3) * q, 0.0);
    if (i % 10 == 9) pts.emplace_back(Vector2d(0.05 * (i / 10) - 0.3, 0.03 * (i / 10) - 0.15), -1.0);
  }
  const std::size_t half = pts.size() / 2;
  for (std::size_t i = 0; i < half; ++i) ASSERT_EQ(inc.add_point(pts[i].first, pts[i].second), AddStatus::kAdded);
  inc.update();
  for (int k = 0; k < 3; ++k) inc.pop_back();
  for (std::size_t i = half - 3; i < pts.size(); ++i) ASSERT_EQ(inc.add_point(pts[i].first, pts[i].second), AddStatus::kAdded);
  inc.update();
  for (const auto& [q, l] : pts) ASSERT_EQ(scratch.add_point(q, l), AddStatus::kAdded);
  scratch.update();
  ASSERT_EQ(inc.grid_variance().size(), 41u * 41u);
  for (std::size_t k = 0; k < inc.grid_variance().size(); ++k) {
    EXPECT_NEAR(inc.grid_variance()[k], scratch.grid_variance()[k], 1e-10) << k;
  }
  // Grid nodes that are map nodes (every 4th: 40 / 10) carry the exact variance.
  Eigen::VectorXd m, v;
  inc.gpis().predict_batch(inc.variance_nodes(), m, v);
  for (uint32_t b = 0; b < 11; ++b) {
    for (uint32_t a = 0; a < 11; ++a) {
      EXPECT_NEAR(inc.grid_variance()[(4 * b) * 41 + 4 * a], v(b * 11 + a), 1e-10);
    }
  }
  // The target does not depend on the map (exact variance at the contour points).
  p.variance_cells = 0;
  GpisExplorer full(p);
  for (const auto& [q, l] : pts) ASSERT_EQ(full.add_point(q, l), AddStatus::kAdded);
  const auto& rf = full.update();
  ASSERT_TRUE(rf.has_target && inc.last().has_target);
  EXPECT_NEAR((rf.target - inc.last().target).norm(), 0.0, 1e-12);
  EXPECT_NEAR(rf.target_variance, inc.last().target_variance, 1e-12);
}

TEST(Explorer, VarianceCellsValidated) {
  ExplorerParams p = ExplorerParams::onboard();
  p.variance_cells = 1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.variance_cells = 2;
  EXPECT_NO_THROW(p.validate());
}
