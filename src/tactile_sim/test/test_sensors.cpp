// IMU, ToF and flow models: hand-computed expectations (004 eq. 9-10, 23).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "tactile_sim/sensors.hpp"

using namespace tactile_sim;

namespace {
Quat yaw_q(double a) { return Quat(Eigen::AngleAxisd(a, Vec3::UnitZ())); }
Quat roll_q(double a) { return Quat(Eigen::AngleAxisd(a, Vec3::UnitX())); }
}  // namespace

TEST(Imu, AtRestReadsPlusGUpAndZeroRateWithinNoise) {
  ImuParams p;
  ImuModel imu(p, 7);
  const int n = 5000;
  Vec3 sa = Vec3::Zero(), sg = Vec3::Zero(), sa2 = Vec3::Zero();
  for (int k = 0; k < n; ++k) {
    const ImuSample s = imu.sample(Vec3(0, 0, kGravity), Vec3::Zero());
    sa += s.accel;
    sg += s.gyro;
    sa2 += (s.accel - Vec3(0, 0, kGravity)).cwiseAbs2();
  }
  const Vec3 ma = sa / n, mg = sg / n;
  const double sigma_a = p.accel_noise_density * std::sqrt(p.rate_hz);  // 0.038 m/s^2
  const double sigma_g = p.gyro_noise_density * std::sqrt(p.rate_hz);
  // Mean within 5 sigma/sqrt(n) plus the bias walk over 10 s (rw * sqrt(10) * 3).
  const double tol_a = 5 * sigma_a / std::sqrt(n) + 3 * p.accel_bias_random_walk * std::sqrt(10.0);
  const double tol_g = 5 * sigma_g / std::sqrt(n) + 3 * p.gyro_bias_random_walk * std::sqrt(10.0);
  EXPECT_NEAR(ma.x(), 0.0, tol_a);
  EXPECT_NEAR(ma.y(), 0.0, tol_a);
  EXPECT_NEAR(ma.z(), 9.81, tol_a);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(mg[i], 0.0, tol_g);
  // Noise std matches density * sqrt(rate) within 10 %.
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(std::sqrt(sa2[i] / n), sigma_a, 0.1 * sigma_a);
}

TEST(Imu, NoiselessPassesTruthAndSeedIsDeterministic) {
  ImuParams z;
  z.gyro_noise_density = z.accel_noise_density = 0.0;
  z.gyro_bias_random_walk = z.accel_bias_random_walk = 0.0;
  ImuModel clean(z, 1);
  const ImuSample s = clean.sample(Vec3(1, 2, 3), Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(s.accel, Vec3(1, 2, 3));
  EXPECT_EQ(s.gyro, Vec3(0.1, 0.2, 0.3));

  ImuModel a(ImuParams{}, 42), b(ImuParams{}, 42), c(ImuParams{}, 43);
  bool differs = false;
  for (int k = 0; k < 100; ++k) {
    const ImuSample sa = a.sample(Vec3::Zero(), Vec3::Zero());
    const ImuSample sb = b.sample(Vec3::Zero(), Vec3::Zero());
    const ImuSample sc = c.sample(Vec3::Zero(), Vec3::Zero());
    EXPECT_EQ(sa.accel, sb.accel);
    EXPECT_EQ(sa.gyro, sb.gyro);
    differs |= sa.accel != sc.accel;
  }
  EXPECT_TRUE(differs);
}

TEST(Imu, BiasRandomWalkGrowsLikeSqrtTime) {
  // Var(b(t)) = rw^2 t. 400 independent IMUs, 20 s each: std within 15 %.
  ImuParams p;
  p.rate_hz = 100.0;
  const int m = 400, steps = 2000;
  double var = 0.0;
  for (int j = 0; j < m; ++j) {
    ImuModel imu(p, 1000 + j);
    for (int k = 0; k < steps; ++k) imu.sample(Vec3::Zero(), Vec3::Zero());
    var += imu.gyro_bias().x() * imu.gyro_bias().x();
  }
  const double expect = p.gyro_bias_random_walk * std::sqrt(20.0);
  EXPECT_NEAR(std::sqrt(var / m), expect, 0.15 * expect);
}

TEST(Range, ReadsHeightAndTiltAndConventions) {
  RangeParams p;
  p.noise_std = 0.0;
  p.noise_proportional = 0.0;
  RangeModel r(p, 3);
  EXPECT_DOUBLE_EQ(r.sample(0.5, Quat::Identity()), 0.5);
  EXPECT_DOUBLE_EQ(r.sample(0.5, yaw_q(1.0)), 0.5);
  EXPECT_NEAR(r.sample(0.5, roll_q(0.3)), 0.5 / std::cos(0.3), 1e-12);
  EXPECT_EQ(r.sample(5.0, Quat::Identity()), std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.sample(0.005, Quat::Identity()), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.sample(0.5, roll_q(1.4)), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(r.sample(std::numeric_limits<double>::quiet_NaN(), Quat::Identity())));
}

TEST(Range, NoiseStdMatchesModel) {
  RangeParams p;
  RangeModel r(p, 9);
  const double h = 1.0, n = 4000;
  double s = 0.0, s2 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double m = r.sample(h, Quat::Identity());
    s += m;
    s2 += (m - h) * (m - h);
  }
  const double sigma = p.noise_std + p.noise_proportional * h;  // 7 mm
  EXPECT_NEAR(s / n, h, 5 * sigma / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(s2 / n), sigma, 0.1 * sigma);
}

TEST(Flow, MatchesEq9Eq10HandComputed) {
  // 004 eq. 9-10: n_x = v_bx / z - w_y, n_y = v_by / z + w_x.
  // Case 1: level, v = (0.5, 0, 0), z = 1, no rotation -> (0.5, 0).
  Vec2 n = FlowModel::ideal(Vec3(0.5, 0, 0), Quat::Identity(), Vec3::Zero(), 1.0);
  EXPECT_NEAR(n.x(), 0.5, 1e-12);
  EXPECT_NEAR(n.y(), 0.0, 1e-12);
  // Case 2: v = (0.2, -0.4, 0), z = 0.5, w = (0.1, 0.3, 0) -> (0.4 - 0.3, -0.8 + 0.1).
  n = FlowModel::ideal(Vec3(0.2, -0.4, 0), Quat::Identity(), Vec3(0.1, 0.3, 0), 0.5);
  EXPECT_NEAR(n.x(), 0.1, 1e-12);
  EXPECT_NEAR(n.y(), -0.7, 1e-12);
  // Case 3: yawed 90 deg: world velocity (0, 1, 0) is body (1, 0, 0); z = 2 -> (0.5, 0).
  n = FlowModel::ideal(Vec3(0, 1, 0), yaw_q(M_PI / 2), Vec3::Zero(), 2.0);
  EXPECT_NEAR(n.x(), 0.5, 1e-12);
  EXPECT_NEAR(n.y(), 0.0, 1e-12);
  // Case 4: pure rotation at rest: n = (-w_y, w_x) = (-0.2, 0.7).
  n = FlowModel::ideal(Vec3::Zero(), Quat::Identity(), Vec3(0.7, 0.2, -1.0), 0.8);
  EXPECT_NEAR(n.x(), -0.2, 1e-12);
  EXPECT_NEAR(n.y(), 0.7, 1e-12);
}

TEST(Flow, SampleNoiseValidityAndSaturation) {
  FlowParams p;
  p.noise_std = 0.0;
  FlowModel f(p, 5);
  FlowSample s = f.sample(Vec3(0.3, 0.0, 0.0), Quat::Identity(), Vec3::Zero(), 0.6);
  ASSERT_TRUE(s.valid);
  EXPECT_NEAR(s.n_x, 0.5, 1e-12);
  EXPECT_NEAR(s.integration_time, 0.01, 1e-15);
  EXPECT_GT(s.quality, 0);
  s = f.sample(Vec3(0.3, 0, 0), Quat::Identity(), Vec3::Zero(), 0.05);  // below min height
  EXPECT_FALSE(s.valid);
  EXPECT_TRUE(std::isnan(s.n_x));
  EXPECT_EQ(s.quality, 0);
  s = f.sample(Vec3(10.0, 0, 0), Quat::Identity(), Vec3::Zero(), 0.5);  // 20 rad/s -> 7.4
  EXPECT_TRUE(s.valid);
  EXPECT_DOUBLE_EQ(s.n_x, p.max_rate);
  // With noise: mean and std over many samples.
  FlowModel g(FlowParams{}, 11);
  double sum = 0, sum2 = 0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    const FlowSample q = g.sample(Vec3(0.3, 0, 0), Quat::Identity(), Vec3::Zero(), 0.6);
    sum += q.n_x;
    sum2 += (q.n_x - 0.5) * (q.n_x - 0.5);
  }
  EXPECT_NEAR(sum / n, 0.5, 5 * 0.02 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.02, 0.002);
}

TEST(Sensors, ParamsValidateNamesField) {
  ImuParams i;
  i.rate_hz = 0.0;
  EXPECT_THROW(ImuModel(i, 1), std::invalid_argument);
  RangeParams r;
  r.max_range = 0.001;
  try {
    r.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("RangeParams.max_range"), std::string::npos);
  }
  FlowParams f;
  f.noise_std = -1.0;
  EXPECT_THROW(f.validate(), std::invalid_argument);
}
