// State estimate of the Crazyflie from its Flow deck v2 (PMW3901 optical flow
// + VL53L1x ToF) and gyro, as the onboard estimator would give it: body
// velocity from flow x height, integrated into position (drifts), height from
// the ToF, yaw from gyro integration with a small bias (drifts).
//
// Uses the sensor models of sensors.hpp (FlowModel: 004 eq. 9-10; RangeModel)
// and adds what makes a flow-deck estimate drift: a flow scale error (lens /
// pixel-to-angle calibration, texture), a gyro bias and noise. Values and
// choices: docs/physics.md, "Whiskered Crazyflie".
//
// Core layer: allocation-free per step, deterministic for a seed.
#pragma once

#include <cstdint>

#include "tactile_sim/sensors.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_sim {

struct FlowDeckParams {
  FlowParams flow;    ///< PMW3901 model (100 Hz, 0.02 rad/s noise, 80 mm min height)
  RangeParams range;  ///< VL53L1x model (50 Hz)
  /// Multiplicative scale error of the measured flow [-] (choice: +3 %, the
  /// order of the flow deck's texture/height dependent scale error).
  double flow_scale_error = 0.03;
  double gyro_bias = 0.0035;        ///< yaw gyro bias [rad/s] (choice: 0.2 deg/s, BMI088 class)
  double gyro_noise_density = 2.4e-4;  ///< yaw gyro white noise [rad/s/sqrt(Hz)] (BMI088 datasheet class)
  double accel_noise_density = 1.6e-3; ///< accelerometer white noise [m/s^2/sqrt(Hz)] (BMI088 class)
  /// Gain of each flow velocity correction of the velocity estimate [-] (per flow sample).
  double flow_gain = 0.25;
  /// Bandwidth of the height/vertical-velocity complementary filter (ToF + accel) [rad/s].
  double height_filter_bandwidth = 10.0;
  /// false: IMU + ToF only, no flow corrections — the horizontal velocity is
  /// the integrated accelerometer (000 Fig. 6: flight in darkness "using only
  /// the onboard IMU and a downward-facing ToF sensor").
  bool use_flow = true;
  /// Residual horizontal accelerometer bias after the take-off calibration
  /// [m/s^2], fixed in the body frame in a direction drawn from the seed; it
  /// integrates into the velocity estimate (the controller then flies the
  /// drone at -bias x t). 0 by default: with flow the flow corrections bound
  /// it. Choice for IMU + ToF flight: docs/physics.md.
  double accel_bias = 0.0;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Stream ids of the flow deck's random sources (offsets from the vehicle's seed).
namespace flow_deck_streams {
constexpr uint64_t kFlow = 120;
constexpr uint64_t kRange = 121;
constexpr uint64_t kGyro = 122;
constexpr uint64_t kAccelBias = 123;
}  // namespace flow_deck_streams

class FlowDeckEstimator {
 public:
  /// `seed` is the vehicle's seed; sub-streams via stream_seed (flow_deck_streams).
  FlowDeckEstimator(const FlowDeckParams& params, uint64_t seed);

  /// Starts the estimate at the truth (the onboard estimator is reset at take-off).
  void reset(const RigidBodyState& truth);

  /// Advances by dt: `truth` after the physics step, `accel_world` its true
  /// acceleration (world, without gravity), `floor_z` the floor height below.
  void step(double dt, const RigidBodyState& truth, const Vec3& accel_world, double floor_z);

  const RigidBodyState& estimate() const { return est_; }
  /// Latest flow sample (for /flow) and whether it was produced in the last step.
  const FlowSample& last_flow() const { return flow_; }
  bool flow_updated() const { return flow_updated_; }
  /// Latest ToF range [m] (sensor_msgs/Range convention) and whether new in the last step.
  double last_range() const { return range_; }
  bool range_updated() const { return range_updated_; }
  /// Current estimated height above the floor [m].
  double height() const { return height_; }
  const FlowDeckParams& params() const { return p_; }

 private:
  FlowDeckParams p_;
  FlowModel flow_model_;
  RangeModel range_model_;
  Rng rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  Vec2 accel_bias_body_ = Vec2::Zero();

  RigidBodyState est_;
  double yaw_ = 0.0;
  double height_ = 0.0;
  double vz_ = 0.0;
  Vec2 v_world_ = Vec2::Zero();
  double flow_timer_ = 0.0, range_timer_ = 0.0;
  FlowSample flow_;
  double range_ = 0.0;
  bool flow_updated_ = false, range_updated_ = false;
};

}  // namespace tactile_sim
