// Onboard sensor models of the SITL vehicles: IMU, downward ToF range finder
// and downward optical flow (paper 004 eq. 9-10, 23). All models are
// allocation-free per sample and own their random source, seeded with
// stream_seed(run_seed, stream) (stream ids below), so one seed gives one
// output sequence. Parameters, values and sources: docs/physics.md "Sensors".
#pragma once

#include <cstdint>
#include <limits>

#include "tactile_sim/types.hpp"

namespace tactile_sim {

/// Fixed stream ids of the sensor models (see stream_seed). Arm IMUs of
/// XPLORER use kArmImuStreamBase + arm index.
namespace sensor_streams {
constexpr uint64_t kImu = 100;
constexpr uint64_t kRange = 101;
constexpr uint64_t kFlow = 102;
constexpr uint64_t kArmImuStreamBase = 110;  // 110..113
}  // namespace sensor_streams

// ---------------------------------------------------------------------------
// IMU
// ---------------------------------------------------------------------------

/// Gyro + accelerometer: white noise (noise density) and bias random walk.
/// Defaults: Bosch BMI088 datasheet class values (Crazyflie / Bolt IMU),
/// a modelling choice; neither paper gives IMU noise figures.
struct ImuParams {
  double rate_hz = 500.0;                    ///< sampling rate (noise discretisation)
  double gyro_noise_density = 2.4e-4;        ///< [rad/s/sqrt(Hz)] (BMI088: 0.014 deg/s/sqrt(Hz))
  double gyro_bias_random_walk = 2.0e-5;     ///< [rad/s^2/sqrt(Hz)]
  double gyro_bias_initial_sigma = 0.0;      ///< std of the turn-on bias [rad/s]
  double accel_noise_density = 1.7e-3;       ///< [m/s^2/sqrt(Hz)] (BMI088: 175 ug/sqrt(Hz))
  double accel_bias_random_walk = 3.0e-4;    ///< [m/s^3/sqrt(Hz)]
  double accel_bias_initial_sigma = 0.0;     ///< std of the turn-on bias [m/s^2]

  void validate() const;  ///< throws std::invalid_argument naming the field
};

struct ImuSample {
  Vec3 gyro = Vec3::Zero();   ///< angular velocity, sensor (= body) frame [rad/s]
  Vec3 accel = Vec3::Zero();  ///< specific force, sensor frame [m/s^2] (+9.81 z at rest, FLU)
};

class ImuModel {
 public:
  /// Seeds its Rng with stream_seed(run_seed, stream).
  ImuModel(const ImuParams& params, uint64_t run_seed, uint64_t stream = sensor_streams::kImu);

  /// One sample at rate_hz (004 eq. 23: a_m = R^T (p_dd - g e3) + v_a,
  /// w_m = w + v_w, here plus the biases b_a, b_w):
  ///   accel = f_body + b_a + n_a,  gyro = w_body + b_w + n_w,
  ///   n ~ N(0, density^2 * rate_hz), b(k+1) = b(k) + N(0, rw^2 / rate_hz).
  ImuSample sample(const Vec3& specific_force_body, const Vec3& angular_velocity_body);

  const Vec3& gyro_bias() const { return gyro_bias_; }
  const Vec3& accel_bias() const { return accel_bias_; }
  const ImuParams& params() const { return p_; }

 private:
  Vec3 gauss3(double sigma);
  ImuParams p_;
  Rng rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  Vec3 gyro_bias_ = Vec3::Zero();
  Vec3 accel_bias_ = Vec3::Zero();
  double gyro_sigma_, accel_sigma_, gyro_rw_sigma_, accel_rw_sigma_;
};

// ---------------------------------------------------------------------------
// ToF range finder (downward)
// ---------------------------------------------------------------------------

/// Downward time-of-flight ranger (Crazyflie Flow deck v2: VL53L1x). Values
/// are choices from the VL53L1x datasheet class (no paper value).
struct RangeParams {
  double rate_hz = 50.0;
  double min_range = 0.01;         ///< [m]
  double max_range = 4.0;          ///< [m] (VL53L1x long distance mode)
  double noise_std = 0.002;        ///< constant part of the noise std [m]
  double noise_proportional = 0.005;  ///< noise std per metre of range [-]
  double field_of_view = 0.47;     ///< [rad] (27 deg, reported in the message)
  /// Tilt beyond which the beam misses the floor in practice: +inf (no return).
  double max_tilt = 1.2;           ///< [rad]

  void validate() const;
};

class RangeModel {
 public:
  RangeModel(const RangeParams& params, uint64_t run_seed,
             uint64_t stream = sensor_streams::kRange);

  /// Range along the body -z axis to a flat floor: r = h / cos(tilt), with
  /// h = height above the floor and cos(tilt) = (R e3)_z, plus Gaussian noise
  /// (std noise_std + noise_proportional * r). sensor_msgs/Range convention:
  /// below min_range -> -inf, beyond max_range (or no return) -> +inf,
  /// non-finite input -> NaN.
  double sample(double height_above_floor, const Quat& orientation);

  /// Noise-free range (same convention, no noise).
  double true_range(double height_above_floor, const Quat& orientation) const;
  const RangeParams& params() const { return p_; }

 private:
  RangeParams p_;
  Rng rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
};

// ---------------------------------------------------------------------------
// Optical flow (downward), 004 eq. 9-10
// ---------------------------------------------------------------------------

/// Downward optical-flow sensor (PMW3901 class, Crazyflie Flow deck v2).
/// Output in 004's convention (eq. 9-10): n = body-frame velocity / height
/// with the rotation compensation terms, [rad/s].
struct FlowParams {
  double rate_hz = 100.0;
  double noise_std = 0.02;      ///< white noise on n_x, n_y [rad/s] (choice)
  double min_height = 0.08;     ///< below: no focus, invalid (PMW3901: 80 mm)
  double max_height = 4.0;      ///< above: no texture resolved, invalid (choice)
  double max_rate = 7.4;        ///< saturation of |n_x|, |n_y| [rad/s] (PMW3901)

  void validate() const;
};

struct FlowSample {
  bool valid = false;       ///< false: height out of range, tilted past 90 deg or bad input
  double n_x = std::numeric_limits<double>::quiet_NaN();  ///< 004 eq. 9 [rad/s]
  double n_y = std::numeric_limits<double>::quiet_NaN();  ///< 004 eq. 10 [rad/s]
  uint8_t quality = 0;      ///< 0 (invalid) .. 255
  double integration_time = 0.0;  ///< 1 / rate_hz [s]
};

class FlowModel {
 public:
  FlowModel(const FlowParams& params, uint64_t run_seed,
            uint64_t stream = sensor_streams::kFlow);

  /// 004 eq. 9-10 with z = height above the floor:
  ///   n_x = (e1^T R^T p_dot) / z - w_y,   n_y = (e2^T R^T p_dot) / z + w_x,
  /// plus noise, saturated at +-max_rate.
  FlowSample sample(const Vec3& velocity_world, const Quat& orientation,
                    const Vec3& angular_velocity_body, double height_above_floor);

  /// Noise-free eq. 9-10 (no validity checks, no saturation).
  static Vec2 ideal(const Vec3& velocity_world, const Quat& orientation,
                    const Vec3& angular_velocity_body, double height_above_floor);
  const FlowParams& params() const { return p_; }

 private:
  FlowParams p_;
  Rng rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
};

}  // namespace tactile_sim
