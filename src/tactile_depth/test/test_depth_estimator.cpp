// Process model (000 eq. 21-25), Kalman filter (eq. 27-30) and the estimator.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "tactile_depth/depth_estimator.hpp"
#include "test_models.hpp"

using namespace tactile_depth;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Planar wall: the line through `p0` with direction angle `alpha` (world).
struct Wall {
  double px, py, alpha;
};

double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Exact depth, computed from the wall line: the ray from the whisker base
// along body x, B + t u, meets W0 + s dir at t = cross(W0 - B, dir) / cross(u, dir).
double geometric_depth(const Wall& w, const Pose2& p, const Point2& base) {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const double bx = p.x + c * base.x - s * base.y;
  const double by = p.y + s * base.x + c * base.y;
  const double dx = std::cos(w.alpha), dy = std::sin(w.alpha);
  return cross(w.px - bx, w.py - by, dx, dy) / cross(c, s, dx, dy);
}

const Point2 kLeft{0.05, 0.025};
const Point2 kRight{0.05, -0.025};
constexpr double kS = 0.05;

// Runs the full process model along `poses` against the wall: at each step
// the depths and wall angle at k come from the geometry, the prediction for
// k+1 must equal the geometric depth at k+1.
void check_full_model(const Wall& wall, const std::vector<Pose2>& poses) {
  for (std::size_t k = 0; k + 1 < poses.size(); ++k) {
    const double dl = geometric_depth(wall, poses[k], kLeft);
    const double dr = geometric_depth(wall, poses[k], kRight);
    const double theta = ProcessModel::wall_angle(dl, dr, kS);  // eq. 22
    double pl = 0, pr = 0;
    ASSERT_TRUE(ProcessModel::predict_full(dl, theta, poses[k], poses[k + 1], kLeft, pl));
    ASSERT_TRUE(ProcessModel::predict_full(dr, theta, poses[k], poses[k + 1], kRight, pr));
    EXPECT_NEAR(pl, geometric_depth(wall, poses[k + 1], kLeft), 1e-12) << "step " << k;
    EXPECT_NEAR(pr, geometric_depth(wall, poses[k + 1], kRight), 1e-12) << "step " << k;
  }
}

}  // namespace

TEST(ProcessModel, WallAngleMatchesGeometry) {
  // Wall direction 80 deg: its normal into the wall is at -10 deg, so for
  // yaw psi the wall angle in the body frame is psi + 10 deg (eq. 21-22, our sign).
  const Wall wall{1.0, 0.0, 80.0 * kPi / 180.0};
  for (double yaw : {0.0, 0.2, -0.3}) {
    const Pose2 p{0.85, 0.01, yaw};
    const double th = ProcessModel::wall_angle(geometric_depth(wall, p, kLeft), geometric_depth(wall, p, kRight), kS);
    EXPECT_NEAR(th, yaw + 10.0 * kPi / 180.0, 1e-12);
  }
}

TEST(ProcessModel, TranslatingParallelToTiltedWall) {
  const Wall wall{1.0, 0.0, 80.0 * kPi / 180.0};
  std::vector<Pose2> poses;
  for (int k = 0; k < 50; ++k) {  // 0.2 m/s along the wall at 50 Hz
    const double t = 0.004 * k;
    poses.push_back({0.85 + t * std::cos(wall.alpha), 0.0 + t * std::sin(wall.alpha), 0.05});
  }
  check_full_model(wall, poses);
  // Depth along a parallel sweep is constant: the prediction keeps it.
  EXPECT_NEAR(geometric_depth(wall, poses.front(), kLeft), geometric_depth(wall, poses.back(), kLeft), 1e-12);
}

TEST(ProcessModel, ApproachingTiltedWall) {
  const Wall wall{1.0, 0.0, 75.0 * kPi / 180.0};
  std::vector<Pose2> poses;
  for (int k = 0; k < 40; ++k) poses.push_back({0.80 + 0.003 * k, -0.001 * k, -0.1});
  check_full_model(wall, poses);
}

TEST(ProcessModel, RotatingInPlace) {
  const Wall wall{1.0, 0.0, 95.0 * kPi / 180.0};
  std::vector<Pose2> poses;
  for (int k = 0; k < 40; ++k) poses.push_back({0.85, 0.02, -0.4 + 0.02 * k});
  check_full_model(wall, poses);
}

TEST(ProcessModel, RandomMotionNearWall) {
  const Wall wall{0.3, 1.2, 170.0 * kPi / 180.0};  // a wall ahead along world +y
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-0.005, 0.005), turn(-0.03, 0.03);
  std::vector<Pose2> poses{{0.3, 1.05, kPi / 2}};
  for (int k = 0; k < 200; ++k) {
    Pose2 p = poses.back();
    p.x += step(rng);
    p.y += step(rng);
    p.yaw += turn(rng);
    if (p.yaw > kPi / 2 + 0.5 || p.yaw < kPi / 2 - 0.5) p.yaw = kPi / 2;
    poses.push_back(p);
  }
  check_full_model(wall, poses);
}

TEST(ProcessModel, PrintedEq25WithBaseAtOrigin) {
  // With the whisker base at the odometry origin our prediction is eq. 25 as
  // printed, with theta^W of eq. 25 the wall's direction angle
  // theta^W_t = psi_k - theta^D_k - pi/2 and atan(Dy/Dx) taken as atan2.
  const Point2 origin{0.0, 0.0};
  const Pose2 a{0.2, -0.1, 0.3};
  const Pose2 b{0.207, -0.096, 0.33};
  const double d = 0.09, theta = 0.12;
  double ours = 0;
  ASSERT_TRUE(ProcessModel::predict_full(d, theta, a, b, origin, ours));
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double dp = std::sqrt(dx * dx + dy * dy);         // eq. 23
  const double theta_w_t = a.yaw - theta - kPi / 2;
  const double theta_k1 = b.yaw - (a.yaw - theta);        // eq. 24
  const double printed = (dp * std::sin(theta_w_t - std::atan2(dy, dx)) + d * std::cos(theta)) / std::cos(theta_k1);
  EXPECT_NEAR(ours, printed, 1e-15);
}

TEST(ProcessModel, ParallelWhiskerIsNotPredicted) {
  double out = 0;
  // theta^D_k+1 = pi/2: whisker parallel to the wall.
  EXPECT_FALSE(ProcessModel::predict_full(0.08, 0.0, {0, 0, 0}, {0, 0, kPi / 2}, kLeft, out));
  EXPECT_EQ(out, 0.08);
}

TEST(ProcessModel, SimplifiedIsForwardTranslation) {
  // Wall perpendicular to the heading (yaw 0.3): exact for any translation.
  const double yaw = 0.3;
  const Wall wall{1.0, 0.5, yaw + kPi / 2};
  const Pose2 a{0.85, 0.45, yaw};
  const Pose2 b{0.86, 0.43, yaw};
  const double d = geometric_depth(wall, a, kLeft);
  EXPECT_NEAR(ProcessModel::predict_simplified(d, a, b), geometric_depth(wall, b, kLeft), 1e-12);
  // Hand: forward displacement = cos(0.3)*0.01 + sin(0.3)*(-0.02).
  EXPECT_NEAR(ProcessModel::predict_simplified(0.1, a, b), 0.1 - (std::cos(0.3) * 0.01 - std::sin(0.3) * 0.02), 1e-15);
}

TEST(DepthKalmanFilter, HandComputedSequence) {
  // q = 1, r = 2, p0 = 4 (eq. 27-30 by hand, fractions):
  DepthKalmanFilter kf(1.0, 2.0, 4.0);
  EXPECT_FALSE(kf.initialized());
  kf.initialize(10.0);
  EXPECT_TRUE(kf.initialized());
  EXPECT_EQ(kf.depth(), 10.0);
  EXPECT_EQ(kf.variance(), 4.0);
  kf.predict(11.0);  // P- = 5
  EXPECT_DOUBLE_EQ(kf.variance(), 5.0);
  kf.update(14.0);   // K = 5/7, d = 11 + 15/7, P = 10/7
  EXPECT_DOUBLE_EQ(kf.gain(), 5.0 / 7.0);
  EXPECT_DOUBLE_EQ(kf.depth(), 11.0 + 15.0 / 7.0);
  EXPECT_DOUBLE_EQ(kf.variance(), 10.0 / 7.0);
  kf.predict(12.0);  // P- = 17/7
  kf.update(9.0);    // K = 17/31, d = 12 - 51/31, P = 34/31
  EXPECT_DOUBLE_EQ(kf.gain(), 17.0 / 31.0);
  EXPECT_DOUBLE_EQ(kf.depth(), 12.0 - 51.0 / 31.0);
  EXPECT_DOUBLE_EQ(kf.variance(), 34.0 / 31.0);
  kf.predict(10.0);  // P- = 65/31
  kf.update(10.0);   // K = 65/127, d = 10, P = 130/127
  EXPECT_DOUBLE_EQ(kf.gain(), 65.0 / 127.0);
  EXPECT_DOUBLE_EQ(kf.depth(), 10.0);
  EXPECT_DOUBLE_EQ(kf.variance(), 130.0 / 127.0);
  kf.reset();
  EXPECT_FALSE(kf.initialized());
}

TEST(Params, DefaultsAndValidation) {
  Params p;
  EXPECT_EQ(p.model, EstimatorModel::kKfFull);
  EXPECT_EQ(p.q_mm2, 0.01);
  EXPECT_EQ(p.r_mm2, 1.0);
  EXPECT_EQ(p.p0_mm2, 50.0);
  EXPECT_EQ(p.whisker_spacing, 0.05);
  EXPECT_NO_THROW(p.validate());
  p.q_mm2 = 0.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TactileDepthParams.q_mm2: must be finite and > 0, got 0");
  }
  p = Params{};
  p.whisker_spacing = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = Params{};
  p.whisker_base_x = NAN;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  // Slip gate (issue 17): off by default; fraction in [0, 1), window 1-100 (kMaxSlipWindow), R > 0.
  EXPECT_EQ(Params{}.slip_fraction, 0.0);
  EXPECT_EQ(Params{}.slip_window_samples, 25);
  EXPECT_EQ(Params{}.slip_r_mm2, 1.0e4);
  p = Params{};
  p.slip_fraction = 1.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TactileDepthParams.slip_fraction: must be in [0, 1) (0 = off), got 1");
  }
  p.slip_fraction = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.slip_fraction = NAN;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = Params{};
  p.slip_window_samples = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.slip_window_samples = 101;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = Params{};
  p.slip_r_mm2 = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  // Slip run limit (0 = none, up to kMaxSlipWindow) and saturated contact (off by default).
  EXPECT_EQ(Params{}.slip_max_samples, 0);
  EXPECT_EQ(Params{}.saturation_sum_pa, 0.0);
  EXPECT_EQ(Params{}.saturation_r_mm2, 1.0e4);
  p = Params{};
  p.slip_max_samples = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.slip_max_samples = 101;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.slip_max_samples = 100;
  EXPECT_NO_THROW(p.validate());
  p = Params{};
  p.saturation_sum_pa = -1.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TactileDepthParams.saturation_sum_pa: must be finite and >= 0 (0 = off), got -1");
  }
  p.saturation_sum_pa = NAN;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = Params{};
  p.saturation_r_mm2 = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_EQ(estimator_model_from_string("kf_simplified"), EstimatorModel::kKfSimplified);
  EXPECT_THROW(estimator_model_from_string("kf"), std::invalid_argument);
}

namespace {

TickInput tick(double m_left_mm, double m_right_mm, bool cl, bool cr, Pose2 pose = {}, bool pose_valid = true) {
  TickInput in;
  in.sp_left = {{m_left_mm, 0, 0}};  // linear_mlp: depth = 1e-3 * S_p[0]
  in.sp_right = {{m_right_mm, 0, 0}};
  in.contact_left = cl;
  in.contact_right = cr;
  in.pose = pose;
  in.pose_valid = pose_valid;
  return in;
}

}  // namespace

TEST(Estimator, InitialisationAndReset) {
  TactileDepthEstimator est(Params{}, test_models::linear_mlp(), test_models::linear_mlp());
  // One whisker in contact: sensor model only, variance R = 1 mm^2.
  TickOutput o = est.update(tick(80, 90, true, false));
  EXPECT_FALSE(o.filter_initialized);
  EXPECT_DOUBLE_EQ(o.depth[0], 0.080);
  EXPECT_DOUBLE_EQ(o.depth[1], 0.090);
  EXPECT_DOUBLE_EQ(o.variance[0], 1e-6);
  EXPECT_TRUE(o.contact[0]);
  EXPECT_FALSE(o.contact[1]);
  // Both: initialised at m with P0 = 50 mm^2.
  o = est.update(tick(85, 85, true, true));
  EXPECT_TRUE(o.filter_initialized);
  EXPECT_DOUBLE_EQ(o.depth[0], 0.085);
  EXPECT_DOUBLE_EQ(o.variance[0], 50e-6);
  // Next: drone 4 mm forward (perpendicular wall: theta = 0), m = 80 mm.
  o = est.update(tick(80, 80, true, true, {0.004, 0, 0}));
  const double pm = 50e-6 + 0.01e-6;         // eq. 27
  const double k = pm / (pm + 1e-6);          // eq. 28
  EXPECT_NEAR(o.depth[0], 0.081 + k * (0.080 - 0.081), 1e-15);  // eq. 29
  EXPECT_NEAR(o.variance[0], (1 - k) * pm, 1e-18);            // eq. 30
  EXPECT_NEAR(o.wall_angle, 0.0, 1e-12);
  // Right whisker loses contact: reset.
  o = est.update(tick(80, 80, true, false, {0.004, 0, 0}));
  EXPECT_FALSE(o.filter_initialized);
  EXPECT_FALSE(est.filter(0).initialized());
  EXPECT_DOUBLE_EQ(o.depth[0], 0.080);
  // Both again: a fresh start at m.
  o = est.update(tick(70, 75, true, true, {0.004, 0, 0}));
  EXPECT_TRUE(o.filter_initialized);
  EXPECT_DOUBLE_EQ(o.depth[1], 0.075);
  EXPECT_DOUBLE_EQ(o.variance[1], 50e-6);
  // No valid odometry: reset as well.
  o = est.update(tick(70, 75, true, true, {}, false));
  EXPECT_FALSE(o.filter_initialized);
  o = est.update(tick(70, 75, true, true, {0.004, 0, 0}));
  EXPECT_TRUE(o.filter_initialized);
  EXPECT_DOUBLE_EQ(o.variance[1], 50e-6);
}

// Slip gate by hand: drone still (d^- = d), linear models (m = 1e-3 S[0]); the
// input sum S[0] + S[1] + S[2] is set through S[2] independently of m.
TEST(Estimator, SlipGateUsesLargeRBelowFractionOfRecentPeak) {
  auto in = [](double m_left_mm, double sum_left, double m_right_mm, double sum_right) {
    TickInput t;
    t.sp_left = {{m_left_mm, 0, sum_left - m_left_mm}};
    t.sp_right = {{m_right_mm, 0, sum_right - m_right_mm}};
    t.contact_left = t.contact_right = true;
    return t;
  };
  Params p;
  p.slip_fraction = 0.5;
  p.slip_window_samples = 3;
  p.slip_r_mm2 = 1e4;
  TactileDepthEstimator est(p, test_models::linear_mlp(), test_models::linear_mlp());
  TactileDepthEstimator off(Params{}, test_models::linear_mlp(), test_models::linear_mlp());
  const double q = 0.01e-6, r = 1e-6, r_slip = 1e4 * 1e-6;
  // Tick 1: initialised at m (80 mm), P0; input sums 1000 / 600.
  TickOutput o = est.update(in(80, 1000, 90, 600));
  off.update(in(80, 1000, 90, 600));
  EXPECT_DOUBLE_EQ(o.depth[0], 0.080);
  EXPECT_FALSE(est.slipping(0));
  // Tick 2: sum 1100 (peak of the window), normal update toward 100 mm.
  o = est.update(in(100, 1100, 90, 600));
  off.update(in(100, 1100, 90, 600));
  double pm = 50e-6 + q;
  double k = pm / (pm + r);
  double d = 0.080 + k * (0.100 - 0.080);
  double pv = (1 - k) * pm;
  EXPECT_FALSE(est.slipping(0));
  EXPECT_NEAR(o.depth[0], d, 1e-15);
  // Tick 3: the left sum drops to 500 < 0.5 x 1100 (a slip); the MLP reads
  // 120 mm. Left: R = 1e4 mm^2, the depth hardly moves. Right (600 of 600):
  // normal update.
  o = est.update(in(120, 500, 90, 600));
  const TickOutput o_off = off.update(in(120, 500, 90, 600));
  EXPECT_TRUE(est.slipping(0));
  EXPECT_FALSE(est.slipping(1));
  pm = pv + q;
  k = pm / (pm + r_slip);
  const double d_slip = d + k * (0.120 - d);
  EXPECT_NEAR(o.depth[0], d_slip, 1e-15);
  EXPECT_NEAR(o.variance[0], (1 - k) * pm, 1e-18);
  EXPECT_NEAR(est.filter(0).gain(), pm / (pm + r_slip), 1e-15);
  EXPECT_LT(o.depth[0] - d, 0.0002);           // < 0.2 mm toward the slip's 120 mm
  EXPECT_GT(o_off.depth[0] - d, 0.005);         // off: follows it (K ~ 0.5, ~10 mm)
  EXPECT_DOUBLE_EQ(o.depth[1], o_off.depth[1]);
  // Tick 4: 540 is still below 550 (the 1100 of tick 2 is in the 3-tick window).
  est.update(in(120, 540, 90, 600));
  EXPECT_TRUE(est.slipping(0));
  // Tick 5: window = ticks 3-5 (500, 540, 560): 560 >= 0.5 x 560, normal update.
  const double v4 = est.filter(0).variance();
  est.update(in(120, 560, 90, 600));
  EXPECT_FALSE(est.slipping(0));
  EXPECT_NEAR(est.filter(0).gain(), (v4 + q) / (v4 + q + r), 1e-12);  // R = 1 mm^2 again
  // Off (slip_fraction 0): never slipping.
  EXPECT_FALSE(off.slipping(0));
  // reset() empties the window: a low sum right after is not a slip.
  est.reset();
  est.update(in(120, 100, 90, 600));
  EXPECT_FALSE(est.slipping(0));
}

// Slip run limit by hand: the gate of the test above with slip_max_samples = 1.
// A sum that stays below the fraction is no longer a slip after one tick (the
// whisker leaving the wall, which the MLP reads right): normal R again.
TEST(Estimator, SlipGateEndsAfterSlipMaxSamples) {
  auto in = [](double m_mm, double sum) {
    TickInput t;
    t.sp_left = {{m_mm, 0, sum - m_mm}};
    t.sp_right = {{90, 0, 600 - 90}};
    t.contact_left = t.contact_right = true;
    return t;
  };
  Params p;
  p.slip_fraction = 0.5;
  p.slip_window_samples = 3;
  p.slip_max_samples = 1;
  TactileDepthEstimator est(p, test_models::linear_mlp(), test_models::linear_mlp());
  p.slip_max_samples = 0;  // the gate without the limit
  TactileDepthEstimator unlimited(p, test_models::linear_mlp(), test_models::linear_mlp());
  const double q = 0.01e-6, r = 1e-6;
  for (TactileDepthEstimator* e : {&est, &unlimited}) {
    e->update(in(80, 1000));
    e->update(in(100, 1100));
    e->update(in(120, 500));  // 500 < 0.5 x 1100: a slip, first tick of the run
    EXPECT_TRUE(e->slipping(0));
  }
  // Second tick below 550: the limit (1 tick) is over, normal update (R = 1 mm^2).
  const double v = est.filter(0).variance();
  est.update(in(120, 540));
  unlimited.update(in(120, 540));
  EXPECT_FALSE(est.slipping(0));
  EXPECT_NEAR(est.filter(0).gain(), (v + q) / (v + q + r), 1e-12);
  EXPECT_TRUE(unlimited.slipping(0));  // without the limit still gated
  // A tick over the fraction ends the run; a new drop is a slip again.
  est.update(in(100, 1200));
  est.update(in(120, 100));
  EXPECT_TRUE(est.slipping(0));
}

// Saturated contact by hand (issue 17): linear models (m = 1e-3 S[0]), input
// sums set through S[2]. Ticks 1-2 unsaturated at 80 / 70 mm (wall angle
// atan(10 mm / 50 mm)); then 10 ticks with both sums >= 500 Pa in which the
// MLP reads 75 / 75 mm (a saturated whisker: angle 0) while the drone moves and
// yaws. Each prediction takes theta^D_k = psi_k - theta^W with theta^W held
// from tick 2 (eq. 24), not eq. 22 on the fused depths, and both updates use
// R = saturation_r_mm2; computed here with ProcessModel / DepthKalmanFilter
// step by step.
TEST(Estimator, SaturatedContactHoldsTheWallAngleAndUsesLargeR) {
  auto in = [](double ml, double sl, double mr, double sr, Pose2 pose) {
    TickInput t;
    t.sp_left = {{ml, 0, sl - ml}};
    t.sp_right = {{mr, 0, sr - mr}};
    t.contact_left = t.contact_right = true;
    t.pose = pose;
    return t;
  };
  Params p;
  p.saturation_sum_pa = 500.0;
  p.saturation_r_mm2 = 100.0;
  TactileDepthEstimator est(p, test_models::linear_mlp(), test_models::linear_mlp());
  TactileDepthEstimator off(Params{}, test_models::linear_mlp(), test_models::linear_mlp());
  const int n_sat = 10;
  auto pose = [](int k) { return k < 2 ? Pose2{0, 0, 0} : Pose2{0.001 * (k - 1), 0.0005 * (k - 1), 0.01 * (k - 1)}; };
  // Reference: the two KFs by hand.
  const double q = 0.01e-6, r = 1e-6, p0 = 50e-6, r_sat = 100e-6, s = 0.05;
  std::array<DepthKalmanFilter, 2> kf = {DepthKalmanFilter(q, r, p0), DepthKalmanFilter(q, r, p0)};
  kf[0].initialize(0.080);
  kf[1].initialize(0.070);
  double pred[2];
  const double theta1 = std::atan((kf[0].depth() - kf[1].depth()) / s);  // eq. 22, unsaturated
  for (int i = 0; i < 2; ++i) ProcessModel::predict_full(kf[i].depth(), theta1, pose(0), pose(1), est.whisker_base(i), pred[i]);
  for (int i = 0; i < 2; ++i) {
    kf[i].predict(pred[i]);
    kf[i].update(i == 0 ? 0.080 : 0.070);
  }
  const double theta_w = pose(1).yaw - std::atan((kf[0].depth() - kf[1].depth()) / s);  // held from tick 2
  double max_eq22_diff = 0.0;
  for (int k = 2; k < 2 + n_sat; ++k) {
    const double theta_held = pose(k - 1).yaw - theta_w;
    max_eq22_diff = std::max(max_eq22_diff, std::fabs(theta_held - std::atan((kf[0].depth() - kf[1].depth()) / s)));
    for (int i = 0; i < 2; ++i) ProcessModel::predict_full(kf[i].depth(), theta_held, pose(k - 1), pose(k), est.whisker_base(i), pred[i]);
    for (int i = 0; i < 2; ++i) {
      kf[i].predict(pred[i]);
      kf[i].update(0.075, r_sat);
    }
  }
  EXPECT_GT(max_eq22_diff, 1e-3);  // eq. 22 on the fused depths would predict differently
  TickOutput o, o_off;
  for (int k = 0; k < 2 + n_sat; ++k) {
    const TickInput t = k < 2 ? in(80, 300, 70, 300, pose(k)) : in(75, 1000, 75, 900, pose(k));
    o = est.update(t);
    o_off = off.update(t);
    EXPECT_EQ(est.saturated(), k >= 2) << k;
  }
  EXPECT_NEAR(o.depth[0], kf[0].depth(), 1e-15);
  EXPECT_NEAR(o.depth[1], kf[1].depth(), 1e-15);
  EXPECT_NEAR(o.variance[0], kf[0].variance(), 1e-18);
  // Off (the paper's KF): follows the saturated 75 / 75 mm; on: the yaw of
  // 0.1 rad toward the wall's angle shows in the depths' difference.
  EXPECT_FALSE(off.saturated());
  EXPECT_LT(std::fabs(o_off.depth[0] - o_off.depth[1]), 0.005);  // 3.0 mm
  EXPECT_GT(std::fabs(o.depth[0] - o.depth[1]), 0.010);          // 14.1 mm
  // One sum below 500 Pa: not saturated, normal update.
  est.update(in(75, 1000, 75, 400, pose(n_sat + 1)));
  EXPECT_FALSE(est.saturated());
  // A contact that starts saturated has no angle to hold: normal updates.
  est.reset();
  est.update(in(75, 1000, 75, 900, pose(0)));
  est.update(in(75, 1000, 75, 900, pose(1)));
  EXPECT_FALSE(est.saturated());
}

TEST(Estimator, MlpModelNeverFilters) {
  Params p;
  p.model = EstimatorModel::kMlp;
  TactileDepthEstimator est(p, test_models::linear_mlp(), test_models::linear_mlp());
  for (int i = 0; i < 3; ++i) {
    const TickOutput o = est.update(tick(80 + i, 60, true, true, {0.001 * i, 0, 0}));
    EXPECT_FALSE(o.filter_initialized);
    EXPECT_DOUBLE_EQ(o.depth[0], 0.001 * (80 + i));
    EXPECT_DOUBLE_EQ(o.variance[1], 1e-6);
    EXPECT_NEAR(o.wall_angle, std::atan((0.020 + 0.001 * i) / 0.05), 1e-12);  // eq. 22
  }
  // var(theta) = (s / (s^2 + diff^2))^2 * (R + R)
  const TickOutput o = est.update(tick(80, 60, true, true));
  const double g = 0.05 / (0.05 * 0.05 + 0.02 * 0.02);
  EXPECT_NEAR(o.wall_angle_variance, g * g * 2e-6, 1e-18);
}

namespace {

struct RunErrors {
  double mlp_rms = 0, kf_rms = 0, max_point_off_wall = 0;
};

// Sweep along a tilted wall while drifting towards it and turning; the MLP
// measures the true depth plus Gaussian noise.
RunErrors sweep(EstimatorModel model, double noise_m, uint32_t seed) {
  Params p;
  p.model = model;
  TactileDepthEstimator est(p, test_models::linear_mlp(), test_models::linear_mlp());
  const Wall wall{1.0, 0.0, 75.0 * kPi / 180.0};
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m);
  double se_m = 0, se_kf = 0;
  int count = 0;
  RunErrors r;
  for (int k = 0; k < 500; ++k) {
    const Pose2 pose{0.86 + 0.0002 * k, -0.004 * k, 0.1 * std::sin(0.02 * k)};
    const double tl = geometric_depth(wall, pose, est.whisker_base(0));
    const double tr = geometric_depth(wall, pose, est.whisker_base(1));
    const TickOutput o = est.update(tick(1e3 * (tl + n(rng)), 1e3 * (tr + n(rng)), true, true, pose));
    if (k >= 50) {  // after the filter settled
      se_m += std::pow(o.measurement[0] - tl, 2) + std::pow(o.measurement[1] - tr, 2);
      se_kf += std::pow(o.depth[0] - tl, 2) + std::pow(o.depth[1] - tr, 2);
      count += 2;
    }
    for (const Point2& c : o.contact_point) {
      const double off = std::fabs(cross(c.x - wall.px, c.y - wall.py, std::cos(wall.alpha), std::sin(wall.alpha)));
      r.max_point_off_wall = std::max(r.max_point_off_wall, off);
    }
  }
  r.mlp_rms = std::sqrt(se_m / count);
  r.kf_rms = std::sqrt(se_kf / count);
  return r;
}

}  // namespace

TEST(Estimator, ExactMeasurementsStayExactAndPointsLieOnWall) {
  const RunErrors r = sweep(EstimatorModel::kKfFull, 1e-15, 1);
  EXPECT_LT(r.kf_rms, 1e-9);
  EXPECT_LT(r.max_point_off_wall, 1e-9);
}

TEST(Estimator, FullKfReducesNoiseAndBeatsSimplifiedOnTiltedWall) {
  const RunErrors full = sweep(EstimatorModel::kKfFull, 0.003, 2);
  const RunErrors simple = sweep(EstimatorModel::kKfSimplified, 0.003, 2);
  EXPECT_NEAR(full.mlp_rms, 0.003, 0.0005);
  EXPECT_LT(full.kf_rms, 0.5 * full.mlp_rms);
  EXPECT_LT(full.kf_rms, simple.kf_rms);
}

TEST(Estimator, StateSizeVsPaperBudget) {
  TactileDepthEstimator est(Params{}, test_models::onboard_shape_mlp(1), test_models::onboard_shape_mlp(2));
  // KF, poses and flags < 512 B, plus the slip gate's window of input sums
  // (2 whiskers x kMaxSlipWindow doubles).
  EXPECT_LT(est.filter_state_bytes(), 512u + 2 * TactileDepthEstimator::kMaxSlipWindow * sizeof(double));
  // One 3-32-32-32-1 network in float32 fits the paper's 9.6 kB (Fig. S6).
  EXPECT_EQ(est.model(0).parameter_bytes_float32(), 9124u);
  EXPECT_LT(est.model(0).parameter_bytes_float32(), TactileDepthEstimator::kPaperBudgetBytes);
  EXPECT_GT(est.state_size_bytes(), 2 * 2281 * sizeof(double));
}
