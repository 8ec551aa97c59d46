// Core tests of xplorer_force_est: every equation of 001 eq. 2-7 and the
// yaw-torque observer against hand computations or an independent
// simulation of the modelled physics.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "xplorer_force_est/filters.hpp"
#include "xplorer_force_est/force_estimator.hpp"

using namespace xplorer_force_est;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();
Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
}  // namespace

// --- filters (001 Sec. V-A2) ----------------------------------------------------------
TEST(Filters, MedianRemovesSpikeAndMatchesHandValues) {
  MedianFilter m(5);
  // Hand: medians of the growing window [1], [1,100], [1,100,2], [1,100,2,3], [1,100,2,3,4], [100,2,3,4,5]
  EXPECT_DOUBLE_EQ(m.update(1), 1.0);
  EXPECT_DOUBLE_EQ(m.update(100), 50.5);
  EXPECT_DOUBLE_EQ(m.update(2), 2.0);
  EXPECT_DOUBLE_EQ(m.update(3), 2.5);
  EXPECT_DOUBLE_EQ(m.update(4), 3.0);
  EXPECT_DOUBLE_EQ(m.update(5), 4.0);
  EXPECT_THROW(MedianFilter(4), std::invalid_argument);
  EXPECT_THROW(MedianFilter(17), std::invalid_argument);
}

TEST(Filters, LowPassAlphaAndStep) {
  LowPassFilter f(2.0, 50.0);
  const double a = 1.0 - std::exp(-2.0 * M_PI * 2.0 / 50.0);
  EXPECT_NEAR(f.alpha(), a, 1e-15);
  EXPECT_DOUBLE_EQ(f.update(0.0), 0.0);  // initialises
  EXPECT_NEAR(f.update(1.0), a, 1e-15);
  EXPECT_NEAR(f.update(1.0), a + a * (1 - a), 1e-15);
}

TEST(Filters, BandStopCoefficientsUnityDcAndNotch) {
  const double fs = 50.0, f0 = 4.68, q = 0.7;
  BandStopFilter n(f0, q, fs);
  const double w0 = 2 * M_PI * f0 / fs, al = std::sin(w0) / (2 * q);
  EXPECT_NEAR(n.b()[0], 1.0 / (1 + al), 1e-15);
  EXPECT_NEAR(n.b()[1], -2 * std::cos(w0) / (1 + al), 1e-15);
  EXPECT_NEAR(n.a()[2], (1 - al) / (1 + al), 1e-15);
  // DC passes unchanged from the first sample (initialised in steady state).
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(n.update(0.3), 0.3, 1e-12);
  // A sinusoid at f0 is removed (after the transient), one at 0.5 Hz is not.
  BandStopFilter a(f0, q, fs), b(f0, q, fs);
  double amp_f0 = 0, amp_low = 0;
  for (int k = 0; k < 2000; ++k) {
    const double ya = a.update(std::sin(2 * M_PI * f0 * k / fs));
    const double yb = b.update(std::sin(2 * M_PI * 0.5 * k / fs));
    if (k > 1000) {
      amp_f0 = std::max(amp_f0, std::abs(ya));
      amp_low = std::max(amp_low, std::abs(yb));
    }
  }
  EXPECT_LT(amp_f0, 1e-3);
  EXPECT_GT(amp_low, 0.95);
  EXPECT_THROW(BandStopFilter(30.0, q, fs), std::invalid_argument);
}

// --- 001 eq. 2-3 ----------------------------------------------------------------------
TEST(ArmForceObserver, StaticDeflectionConvergesGeometricallyToKThetaOverL) {
  const double J = 0.0015, b = 0.009, k = 1.307, l = 0.075, K = 20.0, dt = 0.02, th = 0.04;
  ArmForceObserver o(J, b, k, l, K);
  for (int n = 1; n <= 60; ++n) {
    const double f = o.update(th, 0.0, dt);
    // Hand: r_n = r_{n-1} + K dt (k th - r_{n-1})  =>  r_n = k th (1 - (1 - K dt)^n)
    const double r = k * th * (1.0 - std::pow(1.0 - K * dt, n));
    ASSERT_NEAR(f, r / l, 1e-12) << "n = " << n;
  }
  EXPECT_NEAR(o.force(), k * th / l, 1e-6);  // 1.307 * 0.04 / 0.075 = 0.6971 N
}

TEST(ArmForceObserver, DynamicArmUnderTorqueStepRecoversTorqueOverL) {
  // Independent simulation of 001 eq. 2 at 10 kHz (semi-implicit Euler), the
  // observer sampling angle and rate at 50 Hz.
  const double J = 0.0015, b = 0.009, k = 1.307, l = 0.075, tau = 0.06;
  ArmForceObserver o(J, b, k, l, 20.0);
  double th = 0.0, w = 0.0, f = 0.0;
  const double h = 1e-4;
  std::vector<double> est;
  for (int s = 0; s < 100; ++s) {  // 2 s of 50 Hz samples
    for (int i = 0; i < 200; ++i) {
      const double acc = (tau - b * w - k * th) / J;
      w += acc * h;
      th += w * h;
    }
    f = o.update(th, w, 0.02);
    est.push_back(f);
  }
  EXPECT_NEAR(f, tau / l, 0.01 * tau / l);  // 0.8 N within 1 %
  // Faster than the lightly damped arm itself (zeta = 0.10 rings for ~1 s):
  // the momentum form uses the rate, so the estimate is within 5 % after 0.3 s.
  EXPECT_NEAR(est[15], tau / l, 0.05 * tau / l);
}

// --- 001 eq. 4 ---------------------------------------------------------------------------
TEST(ArmForceWorld, HandRotations) {
  const double s = std::sqrt(0.5);
  // Arm 0 at -45 deg, undeflected, level body: +1 N across the arm = (sin45, cos45, 0).
  Vec3 f = arm_force_world(1.0, -M_PI / 4, 0.0, Mat3::Identity());
  EXPECT_NEAR(f.x(), s, 1e-12);
  EXPECT_NEAR(f.y(), s, 1e-12);
  EXPECT_NEAR(f.z(), 0.0, 1e-12);
  // Body yawed +90 deg: (x, y) -> (-y, x).
  f = arm_force_world(1.0, -M_PI / 4, 0.0, rot_z(M_PI / 2));
  EXPECT_NEAR(f.x(), -s, 1e-12);
  EXPECT_NEAR(f.y(), s, 1e-12);
  // Deflection +45 deg turns the arm to 0 deg: force along +y.
  f = arm_force_world(2.0, -M_PI / 4, M_PI / 4, Mat3::Identity());
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 2.0, 1e-12);
}

TEST(ArmForceWorld, FaceContactOnTwoArmsSumsToTheFaceForceWithTheCalibratedLeverArm) {
  // A 1 N push along -x on the front face, shared by arms 0 and 1 at the motor
  // (0.15 m from the hinge): static hinge torque tau_i = (rho_i x F_i)_z, theta_i = tau_i / k.
  Params p;
  const double lg = 0.15, F = 1.0;
  Vec3 sum = Vec3::Zero();
  for (int i : {0, 1}) {
    const double d = p.arm_directions[i];
    const Vec3 rho(lg * std::cos(d), lg * std::sin(d), 0.0);
    const double tau = rho.cross(Vec3(-F / 2, 0, 0)).z();
    sum += arm_force_world(tau / p.lever_arm, d, 0.0, Mat3::Identity());  // undeflected arms: exact
  }
  EXPECT_NEAR(sum.x(), -F, 1e-12);
  EXPECT_NEAR(sum.y(), 0.0, 1e-12);
}

// --- 001 eq. 5 ---------------------------------------------------------------------------
TEST(ComForce, HandValues) {
  const double m = 1.12, g = 9.81;
  // Hover: accelerometer reads g along body z, thrust m g -> no external force.
  EXPECT_NEAR(com_force_raw(Vec3(0, 0, g), Mat3::Identity(), m * g, m).norm(), 0.0, 1e-12);
  // Level, hovering thrust, accelerometer 0.5 m/s^2 along x: 0.56 N along x.
  const Vec3 f = com_force_raw(Vec3(0.5, 0, g), Mat3::Identity(), m * g, m);
  EXPECT_NEAR(f.x(), 0.56, 1e-12);
  EXPECT_NEAR(f.z(), 0.0, 1e-12);
}

TEST(ComForce, RecoversExternalForceOfTheRigidBodyModel) {
  // 001 eq. 1a in ENU: m a = f R e3 - m g e3 + delta; IMU: a_imu = R^T (a + g e3).
  const double m = 1.12, g = 9.81, thrust = 12.0;
  const Mat3 R = (Eigen::AngleAxisd(0.2, Vec3::UnitX()) * Eigen::AngleAxisd(-0.1, Vec3::UnitY()) *
                  Eigen::AngleAxisd(1.0, Vec3::UnitZ())).toRotationMatrix();
  const Vec3 delta(-1.0, 0.4, 0.2);
  const Vec3 a = (thrust * R * Vec3::UnitZ() - m * g * Vec3::UnitZ() + delta) / m;
  const Vec3 imu = R.transpose() * (a + g * Vec3::UnitZ());
  EXPECT_NEAR((com_force_raw(imu, R, thrust, m) - delta).norm(), 0.0, 1e-12);
}

// --- 001 eq. 6 ---------------------------------------------------------------------------
TEST(ContactIndicator, SumOfAbsoluteAnglesOverValidArms) {
  const std::array<bool, 4> all{true, true, true, true};
  EXPECT_FALSE(contact_indicator({0.01, -0.01, 0.005, 0.004}, all, 0.03));  // 0.029
  EXPECT_TRUE(contact_indicator({0.01, -0.01, 0.005, 0.006}, all, 0.03));
  EXPECT_TRUE(contact_indicator({-0.04, 0.0, 0.0, 0.0}, all, 0.03));
  EXPECT_FALSE(contact_indicator({-0.04, 0.0, 0.0, 0.0}, {false, true, true, true}, 0.03));
}

// --- 001 eq. 7 ---------------------------------------------------------------------------
TEST(Fusion, HandValues) {
  const Vec3 com(2.0, -1.0, 0.5), arm(1.0, 1.0, 0.0);
  // No contact: the CoM estimate whatever kappa.
  EXPECT_NEAR((fuse(com, arm, Vec3(0.3, 0.3, 0.3), false) - com).norm(), 0.0, 1e-15);
  // Contact, kappa = 0: the arms.
  EXPECT_NEAR((fuse(com, arm, Vec3::Zero(), true) - arm).norm(), 0.0, 1e-15);
  // Contact, kappa = (0.5, 1, 0.25): x = 0.5*2 + 0.5*1 = 1.5; y = -1; z = 0.25*0.5 = 0.125.
  const Vec3 f = fuse(com, arm, Vec3(0.5, 1.0, 0.25), true);
  EXPECT_NEAR(f.x(), 1.5, 1e-15);
  EXPECT_NEAR(f.y(), -1.0, 1e-15);
  EXPECT_NEAR(f.z(), 0.125, 1e-15);
  // kappa = xi |signal| element-wise, clamped to 1.
  const Vec3 k = adaptive_gain(0.1, Vec3(-3.0, 20.0, 0.0));
  EXPECT_NEAR(k.x(), 0.3, 1e-15);
  EXPECT_NEAR(k.y(), 1.0, 1e-15);
  EXPECT_NEAR(k.z(), 0.0, 1e-15);
}

// --- yaw-torque observer ---------------------------------------------------------------------
TEST(YawTorqueObserver, FirstStepsByHandAndConvergence) {
  const double I = 0.015, K = 10.0, dt = 0.002, tau_e = 0.05, tau_c = -0.01;
  YawTorqueObserver o(I, K);
  double w = 0.0, r = 0.0, S = 0.0;
  for (int k = 0; k < 2000; ++k) {
    // Hand recursion of the observer on the exact yaw dynamics I w_dot = tau_c + tau_e.
    const double est = o.update(w, tau_c, dt);
    S += dt * (tau_c + r);
    r = K * (I * w - S);
    ASSERT_NEAR(est, r, 1e-12);
    w += (tau_c + tau_e) / I * dt;
  }
  EXPECT_NEAR(o.value(), tau_e, 1e-3 * tau_e);
  EXPECT_NEAR(rotor_yaw_torque({3, 2, 3, 2}, {1, -1, 1, -1}, 0.016), 0.016 * 2.0, 1e-15);
}

// --- parameters --------------------------------------------------------------------------------
TEST(Params, ValidateNamesTheField) {
  Params p;
  EXPECT_NO_THROW(p.validate());
  auto expect_field = [](Params q, const char* field) {
    try {
      q.validate();
      FAIL() << "no error for " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("Params.") + field), std::string::npos) << e.what();
    }
  };
  Params q = p; q.arm_stiffness = 0; expect_field(q, "arm_stiffness");
  q = p; q.observer_gain = 60; expect_field(q, "observer_gain");
  q = p; q.arm_median_window = 4; expect_field(q, "arm_median_window");
  q = p; q.arm_bandstop_hz = 30; expect_field(q, "arm_bandstop_hz");
  q = p; q.lever_arm = kNaN; expect_field(q, "lever_arm");
  q = p; q.spin_sign[2] = 0.5; expect_field(q, "spin_sign[2]");
  q = p; q.xi_f = -1; expect_field(q, "xi_f");
  EXPECT_THROW(kappa_mode_from_string("fast"), std::invalid_argument);
}

// --- the estimator ------------------------------------------------------------------------------
namespace {
// A level vehicle at rest pushed by `F` (world) shared by the arms that touch:
// static arm angles theta_i = (rho_i x F_i)_z / k, accelerometer sees delta / m.
struct StaticPush {
  Params p;
  std::array<double, 4> theta{};
  Vec3 imu;
  StaticPush(const Vec3& F, std::vector<int> arms) {
    const double lg = 0.15;
    for (int i : arms) {
      // Static equilibrium with the deflected arm (as the simulator): theta = (rho(theta) x F_i)_z / k.
      for (int it = 0; it < 50; ++it) {
        const double d = p.arm_directions[i] + theta[i];
        const Vec3 rho(lg * std::cos(d), lg * std::sin(d), 0.0);
        theta[i] = rho.cross(F / static_cast<double>(arms.size())).z() / p.arm_stiffness;
      }
    }
    imu = F / p.mass + Vec3(0, 0, p.gravity);  // thrust m g balances gravity
  }
};
}  // namespace

TEST(Estimator, StaticFacePushConvergesAndFusionIsFasterThanCom) {
  const Vec3 F(-1.0, 0.0, 0.0);
  StaticPush s(F, {0, 1});
  XplorerForceEstimator est(s.p);
  est.set_thrust(s.p.mass * s.p.gravity);
  double t_fused = -1, t_com = -1;
  for (int k = 0; k < 150; ++k) {  // 3 s at 50 Hz, 10 IMU samples per arm sample
    const bool pushing = k >= 25;  // push starts at 0.5 s
    for (int j = 0; j < 10; ++j)
      est.update_imu(pushing ? s.imu : Vec3(0, 0, s.p.gravity), Vec3::Zero(), Quat::Identity(), 0.002);
    std::array<double, 4> th{};
    if (pushing) th = s.theta;
    const Estimate& e = est.update_arms(th, 0.02);
    const double t = (k - 25) * 0.02;
    if (pushing && t_fused < 0 && std::abs(e.force_world.x() - F.x()) < 0.15) t_fused = t;
    if (pushing && t_com < 0 && std::abs(e.com_world.x() - F.x()) < 0.15) t_com = t;
    if (!pushing) {
      EXPECT_FALSE(e.contact);
    }
  }
  const Estimate& e = est.estimate();
  EXPECT_TRUE(e.contact);
  EXPECT_FALSE(e.degraded);
  // The arms turn 2.3 deg away from the face, so the calibrated projection
  // over-reads by 2 sin^2(47.3 deg) - 1 = 8 % of the arm share (README).
  EXPECT_NEAR(e.force_world.x(), -1.0, 0.1);
  EXPECT_NEAR(e.force_world.y(), 0.0, 0.02);
  EXPECT_NEAR(e.force_body.x(), e.force_world.x(), 1e-12);
  EXPECT_NEAR(e.com_world.x(), -1.0, 0.02);
  ASSERT_GT(t_fused, -1);
  ASSERT_GT(t_com, -1);
  EXPECT_LT(t_fused, t_com) << "fused " << t_fused << " s, CoM only " << t_com << " s";
}

TEST(Estimator, NanSamplesAreHeldThenTheArmIsDroppedAndFlagged) {
  Params p;
  p.arm_hold_samples = 3;
  XplorerForceEstimator est(p);
  std::array<double, 4> th{0.02, 0.02, 0.0, 0.0};
  for (int k = 0; k < 50; ++k) est.update_arms(th, 0.02);
  const double f1 = est.estimate().arm_force[1];
  th[1] = kNaN;
  for (int k = 0; k < 3; ++k) {
    const Estimate& e = est.update_arms(th, 0.02);
    EXPECT_TRUE(e.arm_valid[1]);  // held
    EXPECT_NEAR(e.arm_force[1], f1, 1e-6);
  }
  const Estimate& e = est.update_arms(th, 0.02);
  EXPECT_FALSE(e.arm_valid[1]);
  EXPECT_EQ(e.arms_valid, 3);
  EXPECT_TRUE(e.degraded);
  EXPECT_EQ(e.arm_force[1], 0.0);
  EXPECT_TRUE(std::isfinite(e.force_world.x()));
  // The arm comes back: valid again, re-converges.
  th[1] = 0.02;
  for (int k = 0; k < 50; ++k) est.update_arms(th, 0.02);
  EXPECT_TRUE(est.estimate().arm_valid[1]);
  EXPECT_NEAR(est.estimate().arm_force[1], f1, 1e-3);
}

TEST(Estimator, SpikesInTheArmAngleAreRejectedByTheMedian) {
  Params p;
  XplorerForceEstimator a(p), b(p);
  std::array<double, 4> th{0.02, -0.02, 0.0, 0.0};
  double max_diff = 0;
  for (int k = 0; k < 100; ++k) {
    std::array<double, 4> spiky = th;
    if (k % 10 == 5) spiky[0] = 0.5;  // isolated 0.5 rad spikes
    a.update_arms(th, 0.02);
    b.update_arms(spiky, 0.02);
    max_diff = std::max(max_diff, std::abs(a.estimate().arm_force[0] - b.estimate().arm_force[0]));
  }
  EXPECT_LT(max_diff, 1e-9);
}
