// Virtual sensors, set intersections (002 eq. 19-21), tip/slip detection,
// Hall calibration and the Table I protocol in SITL.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "whisker_localization/contact_estimation.hpp"
#include "whisker_localization/stage_sim.hpp"

using namespace whisker_localization;

namespace {
const ElasticaSolver& solver() {
  static const ElasticaSolver s{BeamParams{}};
  return s;
}
const VirtualSensors& sensors() {
  static const VirtualSensors v{solver(), ContactSetParams{}};
  return v;
}
}  // namespace

TEST(VirtualSensors, EverySetPointReproducesTheObservation) {
  const ContactSet load = sensors().load(0.02);
  ASSERT_GT(load.size(), 50u);
  for (std::size_t i = 0; i < load.size(); ++i) EXPECT_DOUBLE_EQ(load.force[i], 0.02);
  const ContactSet m = sensors().moment(3e-4);
  ASSERT_GT(m.size(), 50u);
  for (std::size_t i = 0; i < m.size(); i += 10) {
    EXPECT_NEAR(solver().solve_point(m.x[i], m.y[i]).base_moment, 3e-4, 1e-9);  // eq. 17 via point mode
  }
  const ContactSet slope = sensors().end_slope(0.4);
  ASSERT_GT(slope.size(), 50u);
  for (std::size_t i = 0; i < slope.size(); i += 10) EXPECT_NEAR(slope.phi_a[i], 0.4, 1e-9);
  const ContactSet strip = sensors().strip(0.05);
  ASSERT_GT(strip.size(), 10u);
  for (std::size_t i = 0; i < strip.size(); ++i) EXPECT_DOUBLE_EQ(strip.s_a[i], 0.05);
  // Small-angle model (eq. 15) agrees with the large-angle one for a tiny moment.
  const ContactSet ms = sensors().moment_small_angle(1e-6);
  const ContactSet ml = sensors().moment(1e-6);
  ASSERT_EQ(ms.size(), ml.size());
  EXPECT_NEAR(ms.y.back(), ml.y.back(), 1e-3 * ml.y.back());
  // ... and over-estimates the deflection reach when the deflection is large
  // (the large-angle set is shorter in x, 002 Sec. IV-B4).
  const ContactSet bs = sensors().moment_small_angle(2e-3), bl = sensors().moment(2e-3);
  ASSERT_FALSE(bl.empty());
  EXPECT_LT(bl.x.back(), bs.x.back());
}

TEST(VirtualSensors, SpatialFilterLoadAndStripFindTheContact) {
  // 002 eq. 19: P_load(F) n P_strip(s_a) is the true contact point.
  const BeamShape truth = solver().solve_normal(0.03, 0.0525);
  const auto hits = intersect_sets(sensors().load(0.03), sensors().strip(0.0525));
  ASSERT_FALSE(hits.empty());
  EXPECT_NEAR(hits.front().x, truth.contact_x, 2e-4);
  EXPECT_NEAR(hits.front().y, truth.contact_y, 2e-4);
}

TEST(VirtualSensors, SpatialFilterTwoMomentSensors) {
  // Two whiskers 4.2 mm apart (002 Fig. 10a) touching the same point: their
  // moment sets intersect at it.
  const double sep = 0.0042, px = 0.05, py = 0.006;
  const BeamShape a = solver().solve_point(px, py);
  const BeamShape b = solver().solve_point(px, py - sep);  // second base at y = +sep
  ASSERT_TRUE(a.ok && b.ok);
  const auto hits = intersect_sets(sensors().moment(a.base_moment), sensors().moment(b.base_moment), 0.0, sep);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_NEAR(hits[0].x, px, 1e-5);
  EXPECT_NEAR(hits[0].y, py, 1e-5);
}

TEST(TemporalFilter, FixedContactIsFoundAndSlipIsDetected) {
  TemporalContactFilter f(sensors(), TemporalFilterParams{});
  const BeamShape b0 = solver().solve_point(0.06, 0.004);
  const BeamShape b1 = solver().solve_point(0.06, 0.005);
  EXPECT_EQ(f.update(0.0, 0.0, 0.0).status, ContactEstimate::Status::kNoContact);
  EXPECT_EQ(f.update(b0.base_moment, 0.0, 0.0).status, ContactEstimate::Status::kFirst);
  const ContactEstimate e = f.update(b1.base_moment, 0.0, -0.001);
  ASSERT_EQ(e.status, ContactEstimate::Status::kEstimated);
  EXPECT_NEAR(e.x, 0.06, 2e-5);
  EXPECT_NEAR(e.y, 0.005, 2e-5);
  EXPECT_NEAR(e.s_a, b1.s_a, 1e-4);
  // The base moves away by 20 mm while the moment barely changes: the sets
  // cannot share a world-fixed point -> slip / lost contact (small moment) or
  // tip contact (large moment).
  EXPECT_EQ(f.update(b1.base_moment * 1.01, 0.0, 0.02).status, ContactEstimate::Status::kTipContact);
  TemporalFilterParams high;
  high.tip_threshold = 1.0;
  TemporalContactFilter g(sensors(), high);
  g.update(b1.base_moment, 0.0, 0.0);
  EXPECT_EQ(g.update(b1.base_moment * 1.01, 0.0, 0.02).status, ContactEstimate::Status::kSlip);
  // NaN reading = no contact, the filter restarts.
  EXPECT_EQ(g.update(std::nan(""), 0.0, 0.0).status, ContactEstimate::Status::kNoContact);
  TemporalFilterParams bad;
  bad.tip_threshold = -1.0;
  EXPECT_THROW(TemporalContactFilter(sensors(), bad), std::invalid_argument);
}

TEST(HallCalibration, RecoversThePolynomialAndRejectsBadPairs) {
  std::vector<double> B, M;
  for (int i = 0; i < 1000; ++i) {  // n = 1000 pairs (002 Sec. V-B)
    const double b = -5.0 + 10.0 * i / 999.0;  // mT
    B.push_back(b);
    M.push_back(1e-4 * b + 3e-6 * b * b + 1e-7 * std::sin(17.0 * i));
  }
  const HallCalibration h = HallCalibration::fit(B, M, 2);
  EXPECT_NEAR(h.coefficients()[1], 1e-4, 1e-8);
  EXPECT_NEAR(h.coefficients()[2], 3e-6, 1e-8);
  EXPECT_NEAR(h.moment(2.0), 2e-4 + 1.2e-5, 1e-7);
  EXPECT_LT(h.rms_residual(), 1e-7);
  EXPECT_THROW(HallCalibration::fit({1, 2}, {1}, 1), std::invalid_argument);
  EXPECT_THROW(HallCalibration::fit({1, 2}, {1, 2}, 2), std::invalid_argument);
  EXPECT_THROW(HallCalibration::fit({1, std::nan(""), 3}, {1, 2, 3}, 1), std::invalid_argument);
}

TEST(Profile, SweepUnionInWorldFrame) {
  ProfileEstimator p;
  p.add(1.0, 2.0, 3.14159265358979 / 2, 0.05, 0.01);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p.x()[0], 1.0 - 0.01, 1e-12);
  EXPECT_NEAR(p.y()[0], 2.0 + 0.05, 1e-12);
}

TEST(Table1, SitlContactEstimationBeatsPaperAndBaselineAtLargeDeflection) {
  Table1Params p;
  p.trials = 8;
  const auto rows = run_table1(p);
  ASSERT_EQ(rows.size(), 15u);
  for (const auto& r : rows) {
    std::printf("p_x %.0f mm t_y %.0f mm M0 %.3f mNm phi_a %.2f: ours %.2f mm (%.2f %%), eq.5 %.2f mm (%.2f %%)\n",
                r.p_x * 1e3, r.t_y * 1e3, r.m0 * 1e3, r.phi_a, r.ours_mean * 1e3, r.ours_error_pct,
                r.baseline_mean * 1e3, r.baseline_error_pct);
    EXPECT_EQ(r.ours_failures, 0);
    EXPECT_LE(r.ours_error_pct, 1.0) << r.p_x;  // issue goal: <= 1 % (paper 0.3-2.1 %)
    if (r.t_y == 0.001) {
      // Table I moments: 0.19 mN m at 70 mm ... 0.63 mN m at 35 mm (same order).
      EXPECT_GT(r.m0, 1e-4);
      EXPECT_LT(r.m0, 1e-3);
    } else {
      EXPECT_LT(r.ours_error_pct, r.baseline_error_pct) << r.p_x;  // large deflection
    }
  }
  Table1Params bad;
  bad.contacts = {0.09};
  EXPECT_THROW(run_table1(bad), std::invalid_argument);
}
