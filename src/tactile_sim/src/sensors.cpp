// IMU, ToF and optical-flow sensor models; see sensors.hpp.
#include "tactile_sim/sensors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tactile_sim {
namespace {

[[noreturn]] void bad(const char* type, const char* field, const char* why, double v) {
  std::ostringstream s;
  s << type << "." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const char* t, const char* f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(t, f, "must be > 0", v);
}
void non_negative(const char* t, const char* f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(t, f, "must be >= 0", v);
}
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

// --- IMU ---------------------------------------------------------------------

void ImuParams::validate() const {
  const char* t = "ImuParams";
  positive(t, "rate_hz", rate_hz);
  non_negative(t, "gyro_noise_density", gyro_noise_density);
  non_negative(t, "gyro_bias_random_walk", gyro_bias_random_walk);
  non_negative(t, "gyro_bias_initial_sigma", gyro_bias_initial_sigma);
  non_negative(t, "accel_noise_density", accel_noise_density);
  non_negative(t, "accel_bias_random_walk", accel_bias_random_walk);
  non_negative(t, "accel_bias_initial_sigma", accel_bias_initial_sigma);
}

ImuModel::ImuModel(const ImuParams& params, uint64_t run_seed, uint64_t stream)
    : p_(params), rng_(stream_seed(run_seed, stream)) {
  p_.validate();
  // Discrete white noise of a continuous density: sigma = density * sqrt(rate).
  gyro_sigma_ = p_.gyro_noise_density * std::sqrt(p_.rate_hz);
  accel_sigma_ = p_.accel_noise_density * std::sqrt(p_.rate_hz);
  // Bias random walk over one sample period: sigma = rw * sqrt(1 / rate).
  gyro_rw_sigma_ = p_.gyro_bias_random_walk / std::sqrt(p_.rate_hz);
  accel_rw_sigma_ = p_.accel_bias_random_walk / std::sqrt(p_.rate_hz);
  gyro_bias_ = gauss3(p_.gyro_bias_initial_sigma);
  accel_bias_ = gauss3(p_.accel_bias_initial_sigma);
}

Vec3 ImuModel::gauss3(double sigma) {
  if (sigma == 0.0) return Vec3::Zero();
  const double x = n01_(rng_), y = n01_(rng_), z = n01_(rng_);
  return sigma * Vec3(x, y, z);
}

ImuSample ImuModel::sample(const Vec3& specific_force_body, const Vec3& angular_velocity_body) {
  ImuSample s;
  // 004 eq. 23: a_m = R^T(p_dd - g e3) + v_a, w_m = w + v_w (+ biases).
  s.accel = specific_force_body + accel_bias_ + gauss3(accel_sigma_);
  s.gyro = angular_velocity_body + gyro_bias_ + gauss3(gyro_sigma_);
  gyro_bias_ += gauss3(gyro_rw_sigma_);
  accel_bias_ += gauss3(accel_rw_sigma_);
  return s;
}

// --- ToF ---------------------------------------------------------------------

void RangeParams::validate() const {
  const char* t = "RangeParams";
  positive(t, "rate_hz", rate_hz);
  non_negative(t, "min_range", min_range);
  positive(t, "max_range", max_range);
  if (!(max_range > min_range)) bad(t, "max_range", "must be > min_range", max_range);
  non_negative(t, "noise_std", noise_std);
  non_negative(t, "noise_proportional", noise_proportional);
  positive(t, "field_of_view", field_of_view);
  if (!(max_tilt > 0.0 && max_tilt < M_PI / 2)) bad(t, "max_tilt", "must be in (0, pi/2)", max_tilt);
}

RangeModel::RangeModel(const RangeParams& params, uint64_t run_seed, uint64_t stream)
    : p_(params), rng_(stream_seed(run_seed, stream)) {
  p_.validate();
}

double RangeModel::true_range(double h, const Quat& q) const {
  if (!std::isfinite(h) || !q.coeffs().allFinite()) return kNaN;
  const double cos_tilt = (q * Vec3::UnitZ()).z();  // (R e3)_z
  if (cos_tilt < std::cos(p_.max_tilt)) return kInf;  // beam misses the floor
  if (h <= 0.0) return -kInf;                          // at/below the floor
  const double r = h / cos_tilt;
  if (r < p_.min_range) return -kInf;  // sensor_msgs/Range: too close
  if (r > p_.max_range) return kInf;   // sensor_msgs/Range: no return
  return r;
}

double RangeModel::sample(double h, const Quat& q) {
  const double noise = n01_(rng_);  // drawn always: the stream does not depend on validity
  const double r = true_range(h, q);
  if (!std::isfinite(r)) return r;
  const double m = r + (p_.noise_std + p_.noise_proportional * r) * noise;
  if (m < p_.min_range) return -kInf;
  if (m > p_.max_range) return kInf;
  return m;
}

// --- optical flow --------------------------------------------------------------

void FlowParams::validate() const {
  const char* t = "FlowParams";
  positive(t, "rate_hz", rate_hz);
  non_negative(t, "noise_std", noise_std);
  positive(t, "min_height", min_height);
  positive(t, "max_height", max_height);
  if (!(max_height > min_height)) bad(t, "max_height", "must be > min_height", max_height);
  positive(t, "max_rate", max_rate);
}

FlowModel::FlowModel(const FlowParams& params, uint64_t run_seed, uint64_t stream)
    : p_(params), rng_(stream_seed(run_seed, stream)) {
  p_.validate();
}

Vec2 FlowModel::ideal(const Vec3& v_world, const Quat& q, const Vec3& w_body, double z) {
  const Vec3 v_body = q.conjugate() * v_world;  // R^T p_dot
  return Vec2(v_body.x() / z - w_body.y(),    // 004 eq. 9
              v_body.y() / z + w_body.x());   // 004 eq. 10
}

FlowSample FlowModel::sample(const Vec3& v_world, const Quat& q, const Vec3& w_body, double z) {
  FlowSample s;
  s.integration_time = 1.0 / p_.rate_hz;
  const double nx_noise = n01_(rng_), ny_noise = n01_(rng_);  // always drawn (stable stream)
  if (!std::isfinite(z) || !v_world.allFinite() || !w_body.allFinite() ||
      !q.coeffs().allFinite() || z < p_.min_height || z > p_.max_height ||
      (q * Vec3::UnitZ()).z() <= 0.0) {
    return s;
  }
  const Vec2 n = ideal(v_world, q, w_body, z);
  s.n_x = std::clamp(n.x() + p_.noise_std * nx_noise, -p_.max_rate, p_.max_rate);
  s.n_y = std::clamp(n.y() + p_.noise_std * ny_noise, -p_.max_rate, p_.max_rate);
  s.valid = true;
  const bool saturated = std::abs(s.n_x) >= p_.max_rate || std::abs(s.n_y) >= p_.max_rate;
  s.quality = saturated ? 50 : 200;
  return s;
}

}  // namespace tactile_sim
