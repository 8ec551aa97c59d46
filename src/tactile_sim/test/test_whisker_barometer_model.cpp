#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_sim/whisker_barometer_model.hpp"

using tactile_sim::WhiskerBarometerModel;
using tactile_sim::WhiskerBarometerParams;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 0.02;  // 50 Hz, 000 (Methods: whisker deck at 50 Hz)

// Parameters with every random source and slow drift switched off, so the
// deterministic terms of 000 eq. 1 can be checked exactly.
WhiskerBarometerParams quiet() {
  WhiskerBarometerParams p;
  p.airflow_sigma_c = 0.0;
  p.random_walk_pa_per_sqrt_s = 0.0;
  p.vibration_noise_pa = 0.0;
  p.measurement_noise_pa = 0.0;
  p.pressure_quantum_pa = 0.0;
  p.temperature_noise_c = 0.0;
  p.temperature_quantum_c = 0.0;
  p.heating_delta_c = 0.0;
  return p;
}
}  // namespace

TEST(WhiskerBarometerModel, SameSeedIdenticalDifferentSeedDiffers) {
  WhiskerBarometerParams p;
  WhiskerBarometerModel a(p, 42), b(p, 42), c(p, 43);
  bool differs = false;
  for (int k = 0; k < 3000; ++k) {
    const bool motors = k > 250;
    const double load = (k > 1000 && k < 1100) ? 2e-4 : 0.0;
    const auto sa = a.step(kDt, load, motors);
    const auto sb = b.step(kDt, load, motors);
    const auto sc = c.step(kDt, load, motors);
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(sa.pressure[i], sb.pressure[i]) << "k=" << k;
      ASSERT_EQ(sa.temperature[i], sb.temperature[i]) << "k=" << k;
      differs |= sa.pressure[i] != sc.pressure[i];
    }
  }
  EXPECT_TRUE(differs);
  // The seed in Params is used by the one-argument constructor.
  p.seed = 42;
  WhiskerBarometerModel d(p);
  WhiskerBarometerModel e(p, 42);
  EXPECT_EQ(d.step(kDt, 0, true).pressure[0], e.step(kDt, 0, true).pressure[0]);
}

TEST(WhiskerBarometerModel, MotorsOffNoContactIsOnlyNoise) {
  WhiskerBarometerParams p;  // defaults
  WhiskerBarometerModel m(p, 7);
  const int n = 5000;  // 100 s
  std::vector<double> x(n);
  double tsum = 0.0;
  for (int k = 0; k < n; ++k) {
    const auto s = m.step(kDt, 0.0, false);
    x[k] = s.pressure[1];
    tsum += s.temperature[1];
    ASSERT_GE(s.pressure[1], 30000.0);
    ASSERT_LE(s.pressure[1], 125000.0);
  }
  // No temperature change at rest.
  EXPECT_NEAR(tsum / n, p.board_temperature_c, 0.002);
  // Sample-to-sample differences: white noise sigma_m plus random-walk
  // increments: var(diff) = 2 sigma_m^2 + q^2 dt (+ quantisation q^2/6).
  double m1 = 0, m2 = 0;
  for (int k = 1; k < n; ++k) {
    const double d = x[k] - x[k - 1];
    m1 += d;
    m2 += d * d;
  }
  m1 /= (n - 1);
  const double var = m2 / (n - 1) - m1 * m1;
  const double expected = 2 * p.measurement_noise_pa * p.measurement_noise_pa +
                          p.random_walk_pa_per_sqrt_s * p.random_walk_pa_per_sqrt_s * kDt;
  EXPECT_NEAR(std::sqrt(var), std::sqrt(expected), 0.05 * std::sqrt(expected));
  // Baseline = ambient + preload (no drift at rest apart from the random walk).
  double mean = 0;
  for (double v : x) mean += v;
  mean /= n;
  EXPECT_NEAR(mean, p.ambient_pressure_pa + p.preload_pa[1], 10.0);
}

TEST(WhiskerBarometerModel, TemperatureApproachesCooledValueWithTimeConstant) {
  WhiskerBarometerParams p = quiet();
  p.temperature_noise_c = 0.005;  // keep the BMP390-like temperature noise
  WhiskerBarometerModel m(p, 3);
  const int i = 2;
  const double t_cool = m.cooled_temperature(i);
  EXPECT_DOUBLE_EQ(t_cool, p.board_temperature_c - p.cooling_delta_c[i]);
  const double dT = p.cooling_delta_c[i], tc = p.cooling_tau_s, tp = p.package_tau_s;
  // Two first-order lags in cascade (package tau_p, die tau_c), closed form:
  // T(t) = T_cool + dT (tc e^{-t/tc} - tp e^{-t/tp}) / (tc - tp).
  auto closed = [&](double t) { return t_cool + dT * (tc * std::exp(-t / tc) - tp * std::exp(-t / tp)) / (tc - tp); };
  // Least-squares fit of ln(T - T_cool) = c - t / tau_c once the package lag has
  // died out (t >= 8 tau_p), up to 2 tau_c.
  double st = 0, sy = 0, stt = 0, sty = 0;
  int n = 0;
  const int steps = static_cast<int>(2.0 * tc / kDt);
  double max_err = 0.0;
  for (int k = 1; k <= steps; ++k) {
    const auto s = m.step(kDt, 0.0, true);
    const double t = k * kDt;
    max_err = std::max(max_err, std::fabs(m.components().temperature[i] - closed(t)));
    if (t < 8.0 * tp) continue;
    const double y = std::log(s.temperature[i] - t_cool);
    st += t; sy += y; stt += t * t; sty += t * y; ++n;
  }
  EXPECT_LT(max_err, 0.01 * dT);  // discretisation of the cascade at 50 Hz
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  EXPECT_NEAR(-1.0 / slope, tc, 0.02 * tc);
  // After 8 tau it sits at the cooled temperature.
  for (int k = 0; k < static_cast<int>(6.0 * tc / kDt); ++k) m.step(kDt, 0.0, true);
  EXPECT_NEAR(m.step(kDt, 0.0, true).temperature[i], t_cool, 0.03);
  // Pressure drift = residual coefficient x temperature change (N_td).
  EXPECT_NEAR(m.components().temp_drift[i], -p.temp_coeff_pa_per_c[i] * dT, 0.5);
  // Cooling raises the reading (same direction as a contact): coefficient < 0.
  EXPECT_GT(m.components().temp_drift[i], 100.0);
  // Landing: relaxes back through the same cascade with the re-warming constant.
  const double tr = p.rewarming_tau_s;
  const int land = static_cast<int>(std::lround(tr / kDt));
  for (int k = 0; k < land; ++k) m.step(kDt, 0.0, false);
  const double expected = p.board_temperature_c - dT * (tr * std::exp(-1.0) - tp * std::exp(-tr / tp)) / (tr - tp);
  EXPECT_NEAR(m.components().temperature[i], expected, 0.01 * dT);
}

TEST(WhiskerBarometerModel, ContactLoadGivesPerChannelResponse) {
  WhiskerBarometerParams p = quiet();
  WhiskerBarometerModel m(p, 1);
  std::array<double, 3> base{};
  for (int k = 0; k < 10; ++k) base = m.step(kDt, 0.0, false).pressure;
  for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ(base[i], p.ambient_pressure_pa + p.preload_pa[i]);

  const double load = 2e-4;  // N m, a typical contact
  // First sample after the step: static response plus the ringing kick
  // ringing_gain * load propagated over one step of the damped mode.
  const auto first = m.step(kDt, load, false).pressure;
  const double w = 2 * kPi * p.ringing_freq_hz, z = p.ringing_damping;
  const double wd = w * std::sqrt(1 - z * z);
  const double x0 = p.ringing_gain * load;
  const double ring = std::exp(-z * w * kDt) * (x0 * std::cos(wd * kDt) + z * w * x0 / wd * std::sin(wd * kDt));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(first[i] - base[i], p.sensitivity_pa_per_nm[i] * (load + ring), 1e-6);
  }
  // After the ringing has decayed (10 s >> 1 / (zeta w) = 0.55 s): static response.
  std::array<double, 3> settled{};
  for (int k = 0; k < 500; ++k) settled = m.step(kDt, load, false).pressure;
  const std::array<double, 3> expected_pa = {200.0, 120.0, 70.0};  // sensitivity x 2e-4 N m
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(settled[i] - base[i], expected_pa[i], 1e-6) << i;
  // Typical contacts: 50-500 Pa on the most sensitive channel for 0.5..5e-4 N m.
  EXPECT_GE(p.sensitivity_pa_per_nm[0] * 0.5e-4, 50.0);
  EXPECT_LE(p.sensitivity_pa_per_nm[0] * 5e-4, 500.0);
}

TEST(WhiskerBarometerModel, HysteresisOffsetDecaysWithTimeConstant) {
  WhiskerBarometerParams p = quiet();
  p.ringing_gain = 0.0;
  WhiskerBarometerModel m(p, 1);
  const auto base = m.step(kDt, 0.0, false).pressure;
  const double peak = 3e-4;
  for (int k = 0; k < 100; ++k) m.step(kDt, peak * std::sin(kPi * (k + 1) / 101.0), false);
  // Release: offset = fraction * sensitivity * peak load, decayed over one step.
  double prev_peak = 0;
  for (int k = 0; k < 100; ++k) prev_peak = std::max(prev_peak, peak * std::sin(kPi * (k + 1) / 101.0));
  const auto rel = m.step(kDt, 0.0, false).pressure;
  const double a = std::exp(-kDt / p.hysteresis_tau_s);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(rel[i] - base[i], p.hysteresis_fraction * p.sensitivity_pa_per_nm[i] * prev_peak * a, 1e-6);
  }
  // Decays to 1/e after hysteresis_tau_s.
  const int n = static_cast<int>(std::lround(p.hysteresis_tau_s / kDt));
  std::array<double, 3> later{};
  for (int k = 0; k < n; ++k) later = m.step(kDt, 0.0, false).pressure;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR((later[i] - base[i]) / (rel[i] - base[i]), std::exp(-1.0), 1e-6);
  }
}

TEST(WhiskerBarometerModel, ValidateNamesTheField) {
  WhiskerBarometerParams p;
  p.cooling_tau_s = 0.0;
  try {
    p.validate();
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("WhiskerBarometerParams.cooling_tau_s"), std::string::npos);
  }
  p = WhiskerBarometerParams{};
  p.sensitivity_pa_per_nm[2] = std::nan("");
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = WhiskerBarometerParams{};
  p.preload_pa[0] = 1e6;
  EXPECT_THROW(WhiskerBarometerModel m(p), std::invalid_argument);
  WhiskerBarometerModel ok{WhiskerBarometerParams{}};
  EXPECT_THROW(ok.step(0.0, 0.0, false), std::invalid_argument);
}

// The touched surface's noise scale multiplies the pressure noise only while
// the whisker is loaded: with one seed the draws are identical, so the
// outputs are linear in the scale under load and equal without load.
TEST(WhiskerBarometerModel, SurfaceNoiseScaleAppliesOnlyUnderLoad) {
  const tactile_sim::WhiskerBarometerParams p;
  tactile_sim::WhiskerBarometerModel m1(p, 5), m2(p, 5), m3(p, 5);
  for (int k = 0; k < 200; ++k) {
    const double load = (k >= 100) ? 2e-4 : 0.0;
    const auto a = m1.step(0.02, load, true, 1.0);
    const auto b = m2.step(0.02, load, true, 2.0);
    const auto c = m3.step(0.02, load, true, 3.0);
    for (int i = 0; i < 3; ++i) {
      if (load == 0.0) {
        EXPECT_EQ(a.pressure[i], c.pressure[i]) << k;
      } else {
        EXPECT_NEAR(c.pressure[i] - b.pressure[i], b.pressure[i] - a.pressure[i], 0.02) << k;  // quantum 0.016 Pa
      }
    }
    if (k == 150) {
      EXPECT_NE(a.pressure[0], c.pressure[0]);
    }
  }
}
