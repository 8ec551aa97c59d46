// Whisker barometer signal model: three BMP390 channels of one whisker.
//
// Paper 000 eq. 1 models the raw barometer signal as
//     S_r(t) = S_t(t) + N_td(t) + N_h(t) + N_r(t)
// (true contact signal, temperature drift, hysteresis, ringing/noise). This
// class synthesises S_r per channel from a whisker load (the bending moment
// at the whisker base, N m) and whether the motors run, so that the TDORC
// pipeline (000 eq. 4-11) can be exercised in simulation. Every parameter,
// its value and its origin (paper or modelling choice) is documented in
// docs/whisker_signal_model.md.
//
// ROS-free core: no allocation in step(), deterministic for a given seed.
#pragma once

#include <array>
#include <cstdint>
#include <random>

namespace tactile_sim {

/// Parameters of the whisker barometer model. Defaults are the tuned values
/// (see docs/whisker_signal_model.md): "paper" marks values from paper 000,
/// everything else is a modelling choice.
struct WhiskerBarometerParams {
  using Vec3 = std::array<double, 3>;

  uint64_t seed = 1;  ///< seed of the model's mt19937_64

  // --- static pressure ----------------------------------------------------
  double ambient_pressure_pa = 101325.0;     ///< atmosphere at the arena [Pa]
  Vec3 preload_pa = {2400.0, 1900.0, 2900.0};  ///< gel preload on each sealed barometer [Pa]

  // --- S_t: contact response (load = base bending moment [N m]) -------------
  /// Pressure per base bending moment in the sweep plane [Pa / (N m)]. The
  /// three barometers sit around the follicle, so bending in the sweep plane
  /// compresses the gel above each one differently. A typical contact (PRBM,
  /// 000 eq. S1-S8: 0.4 mm Nitinol, 200 mm, 2-5 cm deflection) gives
  /// 1e-4 .. 5e-4 N m, i.e. ~50-500 Pa on the most sensitive channel.
  Vec3 sensitivity_pa_per_nm = {1.0e6, 0.6e6, 0.35e6};

  // --- N_td: temperature drift -------------------------------------------
  double board_temperature_c = 30.0;   ///< barometer temperature at rest (self-heated PCB) [degC]
  Vec3 cooling_delta_c = {5.6, 5.1, 6.1};  ///< steady-state cooling by propeller airflow [K]
  double cooling_tau_s = 60.0;         ///< die following its package after take-off [s] (tuned, see docs)
  /// Thermal lag of the package surface (resin/gel shell) behind the air
  /// temperature change at take-off [s]: the die temperature is a cascade of two
  /// first-order lags, so its drift starts with zero slope.
  double package_tau_s = 4.0;
  double rewarming_tau_s = 45.0;       ///< time constant of re-warming after landing [s]
  /// Slow heating of the deck while flying (battery/motor currents): a
  /// first-order rise by heating_delta_c with time constant heating_tau_s,
  /// nearly linear over a 1-2 min flight.
  double heating_delta_c = 1.0;        ///< [K]
  double heating_tau_s = 300.0;        ///< [s]
  /// Airflow fluctuations: Ornstein-Uhlenbeck temperature fluctuation per
  /// channel, stationary std airflow_sigma_c while the motors run.
  double airflow_sigma_c = 0.03;       ///< [K]
  double airflow_tau_s = 20.0;         ///< correlation time [s]
  /// Residual temperature coefficient of each channel after the BMP390's own
  /// compensation (dominated by the sealed gel) [Pa/K]. Negative: cooling
  /// raises the reading, like a contact (the paper's band-pass FPR on the
  /// one-sided S_p^up > T implies an upward drift). Tuned with the cooling
  /// values above to 000 Ext. Data Fig. 2: FPR band-pass 37.9 %, TDOC 11.6 %,
  /// TDORC 0 % (paper 38.24 / 12.23 / 0 %), see docs/whisker_signal_model.md.
  Vec3 temp_coeff_pa_per_c = {-125.0, -110.0, -135.0};
  /// Slow random-walk drift of each channel [Pa / sqrt(s)].
  double random_walk_pa_per_sqrt_s = 0.3;

  // --- N_h: hysteresis (partial inelastic recovery of the gel) ---------------
  /// Fraction of a contact's peak response left as an offset at release.
  double hysteresis_fraction = 0.08;
  double hysteresis_tau_s = 15.0;      ///< decay time constant of the offset [s]
  /// Load above which the whisker counts as in contact (for peak tracking) [N m].
  double contact_load_threshold_nm = 1e-6;

  // --- N_r: ringing and noise -----------------------------------------------
  /// Whisker first bending mode (clamped-free Nitinol wire, 0.4 mm x 200 mm).
  double ringing_freq_hz = 4.8;
  double ringing_damping = 0.06;       ///< damping ratio zeta
  /// Ringing amplitude per change of load, relative to the static response.
  double ringing_gain = 0.3;
  double vibration_noise_pa = 2.0;     ///< rotor vibration noise (white at 50 Hz) while flying [Pa]
  double measurement_noise_pa = 1.2;   ///< BMP390 RMS noise [Pa]
  double pressure_quantum_pa = 0.016;  ///< BMP390 pressure resolution [Pa]
  double temperature_noise_c = 0.005;  ///< temperature RMS noise [K]
  double temperature_quantum_c = 0.005;  ///< temperature resolution [K]

  /// Throws std::invalid_argument naming the bad field and the reason.
  void validate() const;
};

/// Three-channel whisker barometer (000 eq. 1).
class WhiskerBarometerModel {
 public:
  using Params = WhiskerBarometerParams;

  struct Sample {
    std::array<double, 3> pressure{};     ///< raw pressure [Pa]
    std::array<double, 3> temperature{};  ///< barometer temperature [degC]
  };

  /// Components of the last step (for tests and plots), pressure terms [Pa].
  struct Components {
    std::array<double, 3> contact{};      ///< S_t
    std::array<double, 3> temp_drift{};   ///< N_td (temperature part + random walk)
    std::array<double, 3> hysteresis{};   ///< N_h
    std::array<double, 3> ringing{};      ///< N_r ringing part (noise excluded)
    std::array<double, 3> temperature{};  ///< noiseless temperature [degC]
  };

  /// Seeds from params.seed. Throws std::invalid_argument on bad params.
  explicit WhiskerBarometerModel(const Params& params);
  /// Seeds from `seed` (overrides params.seed).
  WhiskerBarometerModel(const Params& params, uint64_t seed);

  /// Advances the model by dt [s] (> 0) and returns the measured sample.
  /// @param load      whisker base bending moment in the sweep plane [N m] (>= 0 pushes)
  /// @param motors_on propellers spinning (convective cooling, vibration)
  /// @param contact_noise_scale multiplies the pressure noise while the whisker
  ///        is loaded (surface texture: the arena material's signal_noise_scale;
  ///        glass is smoother than a rigid board, textile rougher). 1 = nominal.
  Sample step(double dt, double load, bool motors_on, double contact_noise_scale = 1.0);

  const Params& params() const { return p_; }
  const Components& components() const { return c_; }
  /// Steady temperature of channel i the model approaches with the motors
  /// on, before slow heating and fluctuations [degC].
  double cooled_temperature(int i) const { return p_.board_temperature_c - p_.cooling_delta_c[i]; }

 private:
  double gauss() { return normal_(rng_); }

  Params p_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};

  std::array<double, 3> package_{};   // package surface temperature [degC]
  std::array<double, 3> temp_{};      // barometer die temperature without OU [degC]
  std::array<double, 3> airflow_{};   // OU fluctuation [K]
  std::array<double, 3> walk_{};      // random walk [Pa]
  std::array<double, 3> hyst_{};      // hysteresis offset [Pa]
  double heating_ = 0.0;              // slow heating [K]
  double ring_x_ = 0.0;               // ringing state: moment-equivalent displacement [N m]
  double ring_v_ = 0.0;               // and its rate [N m / s]
  double prev_load_ = 0.0;
  double peak_load_ = 0.0;
  bool in_contact_ = false;
  Components c_{};
};

}  // namespace tactile_sim
