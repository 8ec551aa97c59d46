// Flow-deck estimator: scale error -> distance error, gyro bias -> yaw drift,
// ToF height, sample rates, determinism, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "tactile_sim/flow_deck.hpp"

namespace tactile_sim {
namespace {

constexpr double kDt = 0.001;

RigidBodyState moving(double x, double vx, double z) {
  RigidBodyState s;
  s.position = Vec3(x, 0.0, z);
  s.velocity = Vec3(vx, 0.0, 0.0);
  return s;
}

TEST(FlowDeck, ScaleErrorScalesTravelledDistance) {
  FlowDeckParams p;
  p.gyro_bias = 0.0;  // isolate the flow scale error
  FlowDeckEstimator est(p, 3);
  RigidBodyState truth = moving(0.0, 0.3, 0.5);
  est.reset(truth);
  for (int i = 0; i < 20000; ++i) {  // 20 s at 0.3 m/s: 6 m
    truth.position.x() += truth.velocity.x() * kDt;
    est.step(kDt, truth, Vec3::Zero(), 0.0);
  }
  // x_est = (1 + scale error) x_true, up to the noise random walk.
  EXPECT_NEAR(est.estimate().position.x() / truth.position.x(), 1.0 + p.flow_scale_error, 0.005);
  EXPECT_NEAR(est.estimate().velocity.x(), 0.3 * (1.0 + p.flow_scale_error), 0.01);
  EXPECT_NEAR(est.estimate().position.y(), 0.0, 0.02);
  EXPECT_NEAR(est.height(), 0.5, 0.01);
  EXPECT_NEAR(est.estimate().position.z(), 0.5, 0.01);
}

TEST(FlowDeck, GyroBiasMakesYawDriftLinearly) {
  FlowDeckParams p;
  FlowDeckEstimator est(p, 5);
  RigidBodyState truth = moving(0.0, 0.0, 0.4);
  est.reset(truth);
  for (int i = 0; i < 30000; ++i) est.step(kDt, truth, Vec3::Zero(), 0.0);
  // 30 s x 0.0035 rad/s = 0.105 rad; white noise adds ~ 2.4e-4 sqrt(30) = 1.3e-3 rad.
  EXPECT_NEAR(est.estimate().yaw(), p.gyro_bias * 30.0, 0.006);
  // Hovering: the position barely moves (flow noise random walk only).
  EXPECT_LT(est.estimate().position.head<2>().norm(), 0.03);
}

TEST(FlowDeck, SampleRatesAndInvalidFlowOnTheFloor) {
  FlowDeckParams p;
  FlowDeckEstimator est(p, 1);
  RigidBodyState truth = moving(0.0, 0.0, 0.4);
  est.reset(truth);
  int flows = 0, ranges = 0;
  for (int i = 0; i < 1000; ++i) {
    est.step(kDt, truth, Vec3::Zero(), 0.0);
    flows += est.flow_updated();
    ranges += est.range_updated();
  }
  EXPECT_EQ(flows, 100);
  EXPECT_EQ(ranges, 50);
  EXPECT_TRUE(est.last_flow().valid);
  EXPECT_NEAR(est.last_range(), 0.4, 0.02);
  // Below the PMW3901's 80 mm the flow is invalid.
  truth.position.z() = 0.03;
  for (int i = 0; i < 20; ++i) est.step(kDt, truth, Vec3::Zero(), 0.0);
  EXPECT_FALSE(est.last_flow().valid);
}

TEST(FlowDeck, Deterministic) {
  FlowDeckParams p;
  FlowDeckEstimator a(p, 9), b(p, 9), c(p, 10);
  RigidBodyState truth = moving(0.0, 0.2, 0.5);
  a.reset(truth);
  b.reset(truth);
  c.reset(truth);
  for (int i = 0; i < 3000; ++i) {
    truth.position.x() += 0.2 * kDt;
    a.step(kDt, truth, Vec3::Zero(), 0.0);
    b.step(kDt, truth, Vec3::Zero(), 0.0);
    c.step(kDt, truth, Vec3::Zero(), 0.0);
  }
  EXPECT_EQ(a.estimate().position, b.estimate().position);
  EXPECT_NE(a.estimate().position, c.estimate().position);
}

// IMU + ToF only (000 Fig. 6, darkness): no flow samples, the velocity is the
// integrated accelerometer. A constant-velocity flight with the estimate
// reset to the truth stays on it up to the noise random walk; a horizontal
// accelerometer bias b makes the velocity estimate wrong by b t and the
// position by b t^2 / 2 (hand computation), in the seeded body direction.
TEST(FlowDeck, ImuOnlyIntegratesTheAccelerometerAndItsBias) {
  FlowDeckParams p;
  p.use_flow = false;
  p.gyro_bias = 0.0;
  FlowDeckEstimator est(p, 7);
  RigidBodyState truth = moving(0.0, 0.3, 0.5);
  est.reset(truth);
  int flows = 0;
  for (int i = 0; i < 10000; ++i) {  // 10 s at 0.3 m/s
    truth.position.x() += truth.velocity.x() * kDt;
    est.step(kDt, truth, Vec3::Zero(), 0.0);
    flows += est.flow_updated();
  }
  EXPECT_EQ(flows, 0);
  // Random walk of 1.6e-3 m/s^2/sqrt(Hz) over 10 s: sigma_v = 5e-3 m/s.
  EXPECT_NEAR(est.estimate().velocity.x(), 0.3, 0.02);
  EXPECT_NEAR(est.estimate().position.x(), truth.position.x(), 0.1);
  EXPECT_NEAR(est.height(), 0.5, 0.01);  // the ToF still corrects the height

  p.accel_bias = 0.02;
  p.accel_noise_density = 0.0;
  FlowDeckEstimator biased(p, 7);
  truth = moving(0.0, 0.0, 0.5);
  biased.reset(truth);
  for (int i = 0; i < 10000; ++i) biased.step(kDt, truth, Vec3::Zero(), 0.0);
  const Vec2 v = biased.estimate().velocity.head<2>();
  const Vec2 x = biased.estimate().position.head<2>();
  EXPECT_NEAR(v.norm(), 0.02 * 10.0, 1e-6);
  EXPECT_NEAR(x.norm(), 0.5 * 0.02 * 100.0, 1e-3);
  EXPECT_NEAR(std::abs(v.normalized().dot(x.normalized())), 1.0, 1e-9);  // same direction
  p.accel_bias = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(FlowDeck, ValidateRejectsBadParams) {
  FlowDeckParams p;
  EXPECT_NO_THROW(p.validate());
  p.flow_scale_error = 0.9;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = FlowDeckParams{};
  p.gyro_noise_density = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = FlowDeckParams{};
  p.flow.rate_hz = 0.0;
  EXPECT_THROW(FlowDeckEstimator(p, 1), std::invalid_argument);
}

}  // namespace
}  // namespace tactile_sim
