#include "tactile_sim/whisker_barometer_model.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tactile_sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void bad(const std::string& field, const std::string& reason, double value) {
  std::ostringstream os;
  os << "WhiskerBarometerParams." << field << ": " << reason << ", got " << value;
  throw std::invalid_argument(os.str());
}

void require_finite(const std::string& field, double v) {
  if (!std::isfinite(v)) bad(field, "must be finite", v);
}
void require_positive(const std::string& field, double v) {
  require_finite(field, v);
  if (!(v > 0.0)) bad(field, "must be > 0", v);
}
void require_non_negative(const std::string& field, double v) {
  require_finite(field, v);
  if (v < 0.0) bad(field, "must be >= 0", v);
}

double quantise(double v, double q) { return q > 0.0 ? std::round(v / q) * q : v; }

}  // namespace

void WhiskerBarometerParams::validate() const {
  require_positive("ambient_pressure_pa", ambient_pressure_pa);
  for (int i = 0; i < 3; ++i) {
    const std::string idx = "[" + std::to_string(i) + "]";
    require_finite("preload_pa" + idx, preload_pa[i]);
    require_finite("sensitivity_pa_per_nm" + idx, sensitivity_pa_per_nm[i]);
    require_non_negative("cooling_delta_c" + idx, cooling_delta_c[i]);
    require_finite("temp_coeff_pa_per_c" + idx, temp_coeff_pa_per_c[i]);
    const double p = ambient_pressure_pa + preload_pa[i];
    // BMP390 operating range 300-1250 hPa.
    if (p < 30000.0 || p > 125000.0) bad("preload_pa" + idx, "ambient + preload outside 300-1250 hPa", p);
  }
  require_finite("board_temperature_c", board_temperature_c);
  if (board_temperature_c < -40.0 || board_temperature_c > 85.0)
    bad("board_temperature_c", "must be within -40..85 degC (BMP390 range)", board_temperature_c);
  require_positive("cooling_tau_s", cooling_tau_s);
  require_positive("rewarming_tau_s", rewarming_tau_s);
  require_positive("package_tau_s", package_tau_s);
  require_finite("heating_delta_c", heating_delta_c);
  require_positive("heating_tau_s", heating_tau_s);
  require_non_negative("airflow_sigma_c", airflow_sigma_c);
  require_positive("airflow_tau_s", airflow_tau_s);
  require_non_negative("random_walk_pa_per_sqrt_s", random_walk_pa_per_sqrt_s);
  require_non_negative("hysteresis_fraction", hysteresis_fraction);
  if (hysteresis_fraction >= 1.0) bad("hysteresis_fraction", "must be < 1", hysteresis_fraction);
  require_positive("hysteresis_tau_s", hysteresis_tau_s);
  require_non_negative("contact_load_threshold_nm", contact_load_threshold_nm);
  require_positive("ringing_freq_hz", ringing_freq_hz);
  require_positive("ringing_damping", ringing_damping);
  if (ringing_damping >= 1.0) bad("ringing_damping", "must be < 1 (underdamped)", ringing_damping);
  require_non_negative("ringing_gain", ringing_gain);
  require_non_negative("vibration_noise_pa", vibration_noise_pa);
  require_non_negative("measurement_noise_pa", measurement_noise_pa);
  require_non_negative("pressure_quantum_pa", pressure_quantum_pa);
  require_non_negative("temperature_noise_c", temperature_noise_c);
  require_non_negative("temperature_quantum_c", temperature_quantum_c);
}

WhiskerBarometerModel::WhiskerBarometerModel(const Params& params)
    : WhiskerBarometerModel(params, params.seed) {}

WhiskerBarometerModel::WhiskerBarometerModel(const Params& params, uint64_t seed)
    : p_(params), rng_(seed) {
  p_.validate();
  p_.seed = seed;
  package_.fill(p_.board_temperature_c);  // at rest, in thermal equilibrium
  temp_.fill(p_.board_temperature_c);
}

WhiskerBarometerModel::Sample WhiskerBarometerModel::step(double dt, double load, bool motors_on,
                                                          double contact_noise_scale) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument("WhiskerBarometerModel::step: dt must be > 0 and finite");
  }
  if (!std::isfinite(load)) load = prev_load_;  // keep the last valid load

  // --- N_td: temperature (000 eq. 1, temperature drift term) --------------
  // The propeller airflow cools the package surface (lag package_tau_s) and the
  // die follows the package (cooling_tau_s); at rest both relax back to the
  // board temperature (re-warming time constant for the die).
  const double tau_t = motors_on ? p_.cooling_tau_s : p_.rewarming_tau_s;
  const double k_t = 1.0 - std::exp(-dt / tau_t);
  const double k_p = 1.0 - std::exp(-dt / p_.package_tau_s);
  // Slow deck heating while flying, decays back at rest with the same tau.
  const double k_h = 1.0 - std::exp(-dt / p_.heating_tau_s);
  heating_ += ((motors_on ? p_.heating_delta_c : 0.0) - heating_) * k_h;
  // Ornstein-Uhlenbeck airflow fluctuation, exact discretisation.
  const double a_ou = std::exp(-dt / p_.airflow_tau_s);
  const double s_ou = (motors_on ? p_.airflow_sigma_c : 0.0) * std::sqrt(1.0 - a_ou * a_ou);
  const double s_rw = p_.random_walk_pa_per_sqrt_s * std::sqrt(dt);

  // --- N_h: hysteresis --------------------------------------------------------
  const double a_h = std::exp(-dt / p_.hysteresis_tau_s);
  const bool contact = load > p_.contact_load_threshold_nm;
  bool released = false;
  if (contact) {
    if (!in_contact_) peak_load_ = 0.0;
    peak_load_ = std::max(peak_load_, load);
  } else if (in_contact_) {
    released = true;
  }
  in_contact_ = contact;

  // --- N_r: ringing of the whisker's first bending mode -----------------------
  // Every change of load kicks the mode (onset and release excite it most);
  // the damped oscillation is propagated exactly over dt.
  ring_x_ += p_.ringing_gain * (load - prev_load_);
  prev_load_ = load;
  {
    const double w = 2.0 * kPi * p_.ringing_freq_hz;
    const double z = p_.ringing_damping;
    const double wd = w * std::sqrt(1.0 - z * z);
    const double e = std::exp(-z * w * dt);
    const double c = std::cos(wd * dt), s = std::sin(wd * dt);
    const double x0 = ring_x_, v0 = ring_v_;
    ring_x_ = e * (x0 * c + (v0 + z * w * x0) / wd * s);
    ring_v_ = e * (v0 * c - (w * w * x0 + z * w * v0) / wd * s);
  }

  Sample out;
  const double loaded_scale = load > p_.contact_load_threshold_nm ? std::max(contact_noise_scale, 0.0) : 1.0;
  const double noise_sigma = loaded_scale *
                             std::sqrt(p_.measurement_noise_pa * p_.measurement_noise_pa +
                                       (motors_on ? p_.vibration_noise_pa * p_.vibration_noise_pa : 0.0));
  for (int i = 0; i < 3; ++i) {
    package_[i] += ((motors_on ? p_.board_temperature_c - p_.cooling_delta_c[i] : p_.board_temperature_c) -
                    package_[i]) * k_p;
    temp_[i] += (package_[i] - temp_[i]) * k_t;
    airflow_[i] = a_ou * airflow_[i] + s_ou * gauss();
    walk_[i] += s_rw * gauss();
    const double temperature = temp_[i] + heating_ + airflow_[i];

    const double k = p_.sensitivity_pa_per_nm[i];
    if (released) hyst_[i] += p_.hysteresis_fraction * k * peak_load_;
    hyst_[i] *= a_h;

    c_.contact[i] = k * std::max(load, 0.0);                                         // S_t
    c_.temp_drift[i] = p_.temp_coeff_pa_per_c[i] * (temperature - p_.board_temperature_c) + walk_[i];  // N_td
    c_.hysteresis[i] = hyst_[i];                                                     // N_h
    c_.ringing[i] = k * ring_x_;                                                     // N_r (ringing)
    c_.temperature[i] = temperature;

    // 000 eq. 1: S_r = S_t + N_td + N_h + N_r (N_r also holds the noise).
    const double s_r = c_.contact[i] + c_.temp_drift[i] + c_.hysteresis[i] + c_.ringing[i] +
                       noise_sigma * gauss();
    out.pressure[i] = quantise(p_.ambient_pressure_pa + p_.preload_pa[i] + s_r, p_.pressure_quantum_pa);
    out.temperature[i] =
        quantise(temperature + p_.temperature_noise_c * gauss(), p_.temperature_quantum_c);
  }
  return out;
}

}  // namespace tactile_sim
