// EKF of 004 eq. 20-25: analytic Jacobians against finite differences,
// covariance symmetric positive definite, NEES consistency on a run that
// follows the filter's own model and noise, recovery from a 0.5 s dropout.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <cstdlib>
#include <random>

#include "wall_effect_ekf/indi_controller.hpp"
#include "wall_effect_ekf/wall_ekf.hpp"

using namespace wall_effect_ekf;

namespace {

WallState sample_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  WallState x;
  x.y = 0.17 + 0.05 * u(rng);
  x.z = 1.0 + 0.2 * u(rng);
  x.v = Vec3(0.3 * u(rng), 0.2 * u(rng), 0.1 * u(rng));
  x.R = so3_exp(Vec3(0.15 * u(rng), 0.15 * u(rng), M_PI * u(rng)));
  x.omega = Vec3(0.5 * u(rng), 0.5 * u(rng), 0.3 * u(rng));
  return x;
}

ErrVec unit(int j, double h) {
  ErrVec e = ErrVec::Zero();
  e[j] = h;
  return e;
}

/// One forward-Euler step of eq. 21 (the filter's propagation) without noise.
WallState euler_step(const WallState& x, const Vec4& T, const VehicleParams& v, double dt) {
  const StateDerivative d = dynamics(x, T, v);
  WallState o = x;
  o.y += d.y_dot * dt;
  o.z += d.z_dot * dt;
  o.v += d.v_dot * dt;
  o.R = x.R * so3_exp(x.omega * dt);
  o.omega += d.omega_dot * dt;
  return o;
}

bool symmetric_pd(const ErrMat& P) {
  if (!(P - P.transpose()).isZero(1e-12)) return false;
  Eigen::SelfAdjointEigenSolver<ErrMat> es(P);
  return es.eigenvalues().minCoeff() > 0.0;
}

}  // namespace

TEST(Jacobians, MeasurementModelsMatchCentralDifferences) {
  std::mt19937_64 rng(7);
  const VehicleParams v;
  const Vec4 T(0.66, 0.70, 0.68, 0.71);
  for (int trial = 0; trial < 20; ++trial) {
    const WallState x = sample_state(rng);
    const ModelJacobians J = jacobians(x, T, v);
    const double h = 1e-6;
    for (int j = 0; j < kErrorDim; ++j) {
      const WallState xp = boxplus(x, unit(j, h)), xm = boxplus(x, unit(j, -h));
      const Vec3 da = (predict_accel(xp, T, v) - predict_accel(xm, T, v)) / (2 * h);
      const Vec2 dn = (predict_flow(xp) - predict_flow(xm)) / (2 * h);
      const double dr = (predict_tof(xp) - predict_tof(xm)) / (2 * h);
      EXPECT_LT((J.H_accel.col(j) - da).norm(), 1e-6 * (1.0 + da.norm())) << "accel col " << j;
      EXPECT_LT((J.H_flow.col(j) - dn).norm(), 1e-6 * (1.0 + dn.norm())) << "flow col " << j;
      EXPECT_NEAR(J.H_tof(0, j), dr, 1e-6 * (1.0 + std::abs(dr))) << "tof col " << j;
    }
  }
}

TEST(Jacobians, DynamicsMatchFiniteDifferences) {
  std::mt19937_64 rng(11);
  const VehicleParams v;
  const Vec4 T(0.66, 0.70, 0.68, 0.71);
  for (int trial = 0; trial < 20; ++trial) {
    const WallState x = sample_state(rng);
    const ModelJacobians J = jacobians(x, T, v);
    // Rows of y, z, v, omega: derivative of dynamics() along each error direction.
    const double h = 1e-6;
    for (int j = 0; j < kErrorDim; ++j) {
      const StateDerivative a = dynamics(boxplus(x, unit(j, h)), T, v);
      const StateDerivative b = dynamics(boxplus(x, unit(j, -h)), T, v);
      ErrVec col = ErrVec::Zero();
      col[idx::kY] = (a.y_dot - b.y_dot) / (2 * h);
      col[idx::kZ] = (a.z_dot - b.z_dot) / (2 * h);
      col.segment<3>(idx::kV) = (a.v_dot - b.v_dot) / (2 * h);
      col.segment<3>(idx::kOmega) = (a.omega_dot - b.omega_dot) / (2 * h);
      ErrVec ana = J.F.col(j);
      ana.segment<3>(idx::kTheta).setZero();
      EXPECT_LT((ana - col).norm(), 1e-5 * (1.0 + col.norm())) << "F col " << j << "\n" << ana.transpose() << "\n" << col.transpose();
    }
    // Attitude rows: through the discrete propagation (error of order dt).
    const double dt = 1e-5, g = 1e-4;
    const WallState x1 = euler_step(x, T, v, dt);
    for (int j = 0; j < kErrorDim; ++j) {
      const ErrVec d = boxminus(euler_step(boxplus(x, unit(j, g)), T, v, dt), x1) / g;
      const Vec3 fd = (d.segment<3>(idx::kTheta) - unit(j, 1.0).segment<3>(idx::kTheta)) / dt;
      EXPECT_LT((J.F.block<3, 1>(idx::kTheta, j) - fd).norm(), 2e-3 * (1.0 + fd.norm())) << "theta row, col " << j;
    }
  }
}

TEST(So3, LogInvertsExp) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100; ++i) {
    Vec3 phi(u(rng), u(rng), u(rng));
    phi *= (i % 3 == 0 ? 3.1 : 1.5) * u(rng) / phi.norm();
    EXPECT_LT((so3_log(so3_exp(phi)) - phi).norm(), 1e-7) << phi.transpose();
  }
}

TEST(EkfParams, ValidateNamesTheField) {
  EkfParams p;
  p.y_max = p.y_min;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("EkfParams.y_max"), std::string::npos);
  }
  p = EkfParams{};
  p.r_accel = -1.0;
  EXPECT_THROW(WallEkf{p}, std::invalid_argument);
}

namespace {

/// A flight that follows the filter's own model (eq. 20 integrated at 1 ms,
/// process noise of the filter's Q, measurement noise of its R), hovering
/// near the wall under the INDI controller with perfect feedback.
struct ModelRun {
  EkfParams p;
  std::mt19937_64 rng{42};
  std::normal_distribution<double> n01{0.0, 1.0};
  WallState truth;
  IndiController ctl{IndiParams{}};
  Vec4 thrust = Vec4::Constant(0.28 * kGravity / 4.0);

  ModelRun() {
    // Process noise of the truth (and the filter): a calm flight.
    p.q_velocity = 0.1;
    p.q_rate = 0.5;
    p.r_accel_z = p.r_accel;  // the truth has the same accelerometer noise on every axis
    truth.y = 0.18;
    truth.z = 1.0;
    truth.R = so3_exp(Vec3(0, 0, 0.3));
  }
  Vec3 gauss3(double s) { return s * Vec3(n01(rng), n01(rng), n01(rng)); }

  /// Advances the truth by p.dt and returns the thrusts used.
  Vec4 step(double y_setpoint) {
    IndiSetpoint sp;
    sp.position = Vec3(0.0, y_setpoint, 1.0);
    sp.yaw = 0.3;
    IndiFeedback fb;
    fb.position = Vec3(0.0, truth.y, truth.z);
    fb.velocity = truth.v;
    fb.R = truth.R;
    fb.specific_force = predict_accel(truth, thrust, p.vehicle);
    ctl.outer(sp, fb, p.dt);
    const Vec3 x_b = truth.R.col(0);
    const auto t = ctl.inner(truth.omega, std::atan2(x_b.y(), x_b.x()), 0.3);
    thrust = Vec4(t[0], t[1], t[2], t[3]);
    const int n = 10;
    const double h = p.dt / n;
    for (int i = 0; i < n; ++i) {
      truth = euler_step(truth, thrust, p.vehicle, h);
      truth.v += gauss3(p.q_velocity * std::sqrt(h));
      truth.omega += gauss3(p.q_rate * std::sqrt(h));
    }
    return thrust;
  }
};

}  // namespace

TEST(WallEkf, ConsistentOnItsOwnModelAndCovarianceStaysPositiveDefinite) {
  ModelRun run;
  run.p.q_distance = 1e-4;  // truth has no wall-geometry or floor random walk
  run.p.q_height = 1e-4;
  run.p.q_attitude = 0.003;  // the 10 ms Euler step of the attitude (truth at 1 ms)
  WallEkf ekf(run.p);
  ErrMat P0 = ErrMat::Identity() * 1e-4;
  P0(idx::kY, idx::kY) = 0.02 * 0.02;
  P0(idx::kTheta + 2, idx::kTheta + 2) = 0.1 * 0.1;
  WallState x0 = run.truth;
  x0.y += 0.01;
  ekf.reset(x0, P0);
  double nees_sum = 0.0, nees2_sum = 0.0;
  ErrVec comp = ErrVec::Zero();
  int n = 0;
  const int steps = 3000;  // 30 s at 100 Hz
  for (int k = 0; k < steps; ++k) {
    const double y_sp = 0.18 - 0.03 * std::sin(0.01 * k);
    const Vec4 T = run.step(y_sp);
    ekf.predict(T);
    const auto& p = run.p;
    ekf.update_accel(predict_accel(run.truth, T, p.vehicle) + run.gauss3(p.r_accel));
    ekf.update_gyro(run.truth.omega + run.gauss3(p.r_gyro));
    ekf.update_flow(predict_flow(run.truth) + Vec2(p.r_flow * run.n01(run.rng), p.r_flow * run.n01(run.rng)));
    ekf.update_tof(predict_tof(run.truth) + p.r_tof * run.n01(run.rng));
    ASSERT_TRUE(symmetric_pd(ekf.covariance())) << "step " << k;
    if (k < 200) continue;
    const ErrVec e = boxminus(run.truth, ekf.state());
    nees_sum += e.dot(ekf.covariance().ldlt().solve(e));
    for (int i = 0; i < kErrorDim; ++i) comp[i] += e[i] * e[i] / ekf.covariance()(i, i);
    const Eigen::Vector2d e2(e[idx::kY], e[idx::kTheta + 2]);
    Eigen::Matrix2d P2;
    P2 << ekf.covariance()(0, 0), ekf.covariance()(0, 7), ekf.covariance()(7, 0), ekf.covariance()(7, 7);
    nees2_sum += e2.dot(P2.ldlt().solve(e2));
    ++n;
  }
  const double nees = nees_sum / n, nees2 = nees2_sum / n;
  if (std::getenv("WE_DEBUG")) std::cout << "per-component " << (comp / n).transpose() << std::endl;
  // Expected 11 (full error state) and 2 (distance, yaw); the samples are
  // correlated in time, so the bounds are wide but still reject a filter
  // that is over- or under-confident by a factor of ~2.
  EXPECT_GT(nees, 11.0 * 0.5) << nees;
  EXPECT_LT(nees, 11.0 * 1.6) << nees;
  EXPECT_GT(nees2, 2.0 * 0.3) << nees2;
  EXPECT_LT(nees2, 2.0 * 2.0) << nees2;
  EXPECT_LT(std::abs(ekf.state().y - run.truth.y), 0.02);
}

TEST(WallEkf, RecoversFromHalfSecondSensorDropout) {
  ModelRun run;
  WallEkf ekf(run.p);
  ErrMat P0 = ErrMat::Identity() * 1e-4;
  P0(idx::kY, idx::kY) = 0.02 * 0.02;
  ekf.reset(run.truth, P0);
  double err_before = 0.0, err_after = 0.0, sigma_in = 0.0, sigma_before = 0.0;
  for (int k = 0; k < 1500; ++k) {
    const Vec4 T = run.step(0.17);
    ekf.predict(T);
    const bool dropout = k >= 800 && k < 850;  // 0.5 s without any measurement
    if (!dropout) {
      const auto& p = run.p;
      ekf.update_accel(predict_accel(run.truth, T, p.vehicle) + run.gauss3(p.r_accel));
      ekf.update_gyro(run.truth.omega + run.gauss3(p.r_gyro));
      ekf.update_flow(predict_flow(run.truth) + Vec2(p.r_flow * run.n01(run.rng), p.r_flow * run.n01(run.rng)));
      ekf.update_tof(predict_tof(run.truth) + p.r_tof * run.n01(run.rng));
    }
    const double e = std::abs(ekf.state().y - run.truth.y);
    if (std::getenv("WE_DEBUG") && k % 10 == 0) printf("%d y %.4f yh %.4f sy %.4f psi %.3f psih %.3f reacq %lu\n", k, run.truth.y, ekf.state().y, std::sqrt(ekf.covariance()(0,0)), run.truth.wall_direction(), ekf.state().wall_direction(), (unsigned long)ekf.stats().reacquisitions);
    if (k >= 600 && k < 800) err_before = std::max(err_before, e);
    if (k == 799) sigma_before = std::sqrt(ekf.covariance()(0, 0));
    if (k == 849) sigma_in = std::sqrt(ekf.covariance()(0, 0));
    if (k >= 1050) err_after = std::max(err_after, e);  // 2 s after the dropout
    ASSERT_TRUE(symmetric_pd(ekf.covariance()));
  }
  EXPECT_GT(sigma_in, sigma_before);  // the filter knows it is blind
  EXPECT_LT(err_after, 0.02) << "before " << err_before;
}

TEST(WallEkf, NonFiniteInputsAreCountedAndDropped) {
  WallEkf ekf(EkfParams{});
  ekf.reset(1.0);
  const WallState before = ekf.state();
  ekf.predict(Vec4(NAN, 0.7, 0.7, 0.7));
  ekf.update_accel(Vec3(0, NAN, 9.8));
  ekf.update_flow(Vec2(INFINITY, 0));
  ekf.update_tof(NAN);
  EXPECT_EQ(ekf.stats().nonfinite_inputs, 4u);
  EXPECT_EQ(ekf.stats().predictions, 0u);
  EXPECT_EQ(ekf.state().y, before.y);
}
