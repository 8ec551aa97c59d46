#include "tactile_sim/flow_deck.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tactile_sim {
namespace {

void require(bool ok, const char* field, const char* reason, double value) {
  if (ok) return;
  std::ostringstream os;
  os << "FlowDeckParams." << field << ": " << reason << ", got " << value;
  throw std::invalid_argument(os.str());
}

}  // namespace

void FlowDeckParams::validate() const {
  flow.validate();
  range.validate();
  require(std::isfinite(flow_scale_error) && flow_scale_error > -0.5 && flow_scale_error < 0.5,
          "flow_scale_error", "must be in (-0.5, 0.5)", flow_scale_error);
  require(std::isfinite(gyro_bias) && std::abs(gyro_bias) < 1.0, "gyro_bias",
          "must be finite and |.| < 1 rad/s", gyro_bias);
  require(std::isfinite(gyro_noise_density) && gyro_noise_density >= 0.0, "gyro_noise_density",
          "must be >= 0", gyro_noise_density);
  require(std::isfinite(accel_noise_density) && accel_noise_density >= 0.0,
          "accel_noise_density", "must be >= 0", accel_noise_density);
  require(flow_gain > 0.0 && flow_gain <= 1.0, "flow_gain", "must be in (0, 1]", flow_gain);
  require(std::isfinite(height_filter_bandwidth) && height_filter_bandwidth > 0.0,
          "height_filter_bandwidth", "must be > 0", height_filter_bandwidth);
  require(std::isfinite(accel_bias) && accel_bias >= 0.0 && accel_bias < 1.0, "accel_bias",
          "must be in [0, 1) m/s^2", accel_bias);
}

FlowDeckEstimator::FlowDeckEstimator(const FlowDeckParams& params, uint64_t seed)
    : p_(params),
      flow_model_(params.flow, seed, flow_deck_streams::kFlow),
      range_model_(params.range, seed, flow_deck_streams::kRange),
      rng_(stream_seed(seed, flow_deck_streams::kGyro)) {
  p_.validate();
  // Direction of the accelerometer bias in the body frame, from its own stream.
  Rng bias_rng(stream_seed(seed, flow_deck_streams::kAccelBias));
  const double dir = std::uniform_real_distribution<double>(-M_PI, M_PI)(bias_rng);
  accel_bias_body_ = p_.accel_bias * Vec2(std::cos(dir), std::sin(dir));
}

void FlowDeckEstimator::reset(const RigidBodyState& truth) {
  est_ = truth;
  yaw_ = truth.yaw();
  v_world_ = truth.velocity.head<2>();
  vz_ = truth.velocity.z();
  height_ = 0.0;
  flow_timer_ = range_timer_ = 0.0;
  flow_updated_ = range_updated_ = false;
  est_.position = truth.position;
}

void FlowDeckEstimator::step(double dt, const RigidBodyState& truth, const Vec3& accel_world,
                             double floor_z) {
  flow_updated_ = range_updated_ = false;
  const double sqrt_rate = std::sqrt(1.0 / dt);
  // Gyro: truth + constant bias + white noise; yaw integrates it (drifts).
  const Vec3 w_true = truth.angular_velocity;
  const Vec3 z_body = truth.orientation * Vec3::UnitZ();
  const double yaw_rate_true = (truth.orientation * w_true).z();  // world-z rate
  const double gyro_z = yaw_rate_true + p_.gyro_bias + p_.gyro_noise_density * sqrt_rate * n01_(rng_);
  yaw_ += gyro_z * dt;
  // Accelerometer (truth + white noise) drives the prediction.
  Vec3 acc = accel_world;
  for (int i = 0; i < 3; ++i) acc[i] += p_.accel_noise_density * sqrt_rate * n01_(rng_);
  // Horizontal bias, fixed in the body frame (rotated with the true yaw here;
  // the estimated yaw's error is applied below with the rest of the reading).
  const double yaw_true = truth.yaw();
  if (p_.accel_bias > 0.0) {
    acc.x() += std::cos(yaw_true) * accel_bias_body_.x() - std::sin(yaw_true) * accel_bias_body_.y();
    acc.y() += std::sin(yaw_true) * accel_bias_body_.x() + std::cos(yaw_true) * accel_bias_body_.y();
  }
  // The accelerometer measures in the body frame; rotating it with the
  // estimated yaw instead of the true one is part of the drift.
  const double dyaw = yaw_ - yaw_true;
  const Vec2 a_h(std::cos(dyaw) * acc.x() - std::sin(dyaw) * acc.y(),
                 std::sin(dyaw) * acc.x() + std::cos(dyaw) * acc.y());
  v_world_ += a_h * dt;

  const double h_true = truth.position.z() - floor_z;
  // ToF at its rate: complementary filter of height with the vertical accel.
  range_timer_ += dt;
  double h_meas = NAN;
  if (range_timer_ + 1e-12 >= 1.0 / p_.range.rate_hz) {
    range_timer_ -= 1.0 / p_.range.rate_hz;
    range_ = range_model_.sample(h_true, truth.orientation);
    range_updated_ = true;
    if (std::isfinite(range_)) h_meas = range_ * z_body.z();  // tilt from the attitude estimate
    else if (range_ < 0.0) h_meas = 0.0;                         // too close: on the floor
  }
  const double wc = p_.height_filter_bandwidth;
  vz_ += acc.z() * dt;
  height_ += vz_ * dt;
  if (std::isfinite(h_meas)) {
    const double rate_dt = 1.0 / p_.range.rate_hz;
    const double e = h_meas - height_;
    height_ += 2.0 * wc * rate_dt * e;
    vz_ += wc * wc * rate_dt * e;
  }

  // Flow at its rate: body velocity = (flow + rotation) * height (004 eq. 9-10 inverted).
  flow_timer_ += dt;
  if (p_.use_flow && flow_timer_ + 1e-12 >= 1.0 / p_.flow.rate_hz) {
    flow_timer_ -= 1.0 / p_.flow.rate_hz;
    flow_ = flow_model_.sample(truth.velocity, truth.orientation, w_true, h_true);
    flow_updated_ = true;
    if (flow_.valid && height_ > p_.flow.min_height * 0.5) {
      const double s = 1.0 + p_.flow_scale_error;
      const double gx = w_true.x(), gy = w_true.y();  // roll/pitch gyro: noise negligible here
      const Vec2 v_body((s * flow_.n_x + gy) * height_, (s * flow_.n_y - gx) * height_);
      const Vec2 v_meas(std::cos(yaw_) * v_body.x() - std::sin(yaw_) * v_body.y(),
                        std::sin(yaw_) * v_body.x() + std::cos(yaw_) * v_body.y());
      v_world_ += p_.flow_gain * (v_meas - v_world_);
    }
  }
  if (h_true <= 1e-4 && std::abs(truth.velocity.z()) < 1e-6) {
    // On the floor (motors off): the estimator knows it is not moving.
    v_world_.setZero();
    vz_ = 0.0;
  }

  est_.position.x() += v_world_.x() * dt;
  est_.position.y() += v_world_.y() * dt;
  est_.position.z() = floor_z + height_;
  est_.velocity = Vec3(v_world_.x(), v_world_.y(), vz_);
  // Roll/pitch from the attitude estimate (accurate: gravity-referenced), yaw drifts.
  const Quat yaw_err(Eigen::AngleAxisd(dyaw, Vec3::UnitZ()));
  est_.orientation = (yaw_err * truth.orientation).normalized();
  est_.angular_velocity = w_true;
  est_.angular_velocity.z() += p_.gyro_bias;
}

}  // namespace tactile_sim
