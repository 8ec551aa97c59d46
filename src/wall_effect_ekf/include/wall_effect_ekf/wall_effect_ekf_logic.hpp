// Node logic of wall_effect_ekf: IMU, optical flow, ToF and the rotor thrust
// commands in, the wall estimate (distance, direction, height, covariance)
// out at the filter rate (paper 004 eq. 20-25, 100 Hz). No rclcpp: the
// rclcpp component and the standalone host both use this class.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "sensor_msgs/msg/imu.hpp"
#include "sensor_msgs/msg/range.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/optical_flow.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "wall_effect_ekf/wall_ekf.hpp"

namespace wall_effect_ekf {

class WallEffectEkfLogic {
 public:
  static constexpr const char* kNodeName = "wall_effect_ekf";
  static constexpr const char* kImuTopic = "imu";                     // sensor_msgs/msg/Imu
  static constexpr const char* kFlowTopic = "flow";                   // tactile_msgs/msg/OpticalFlow
  static constexpr const char* kRangeTopic = "tof";                   // sensor_msgs/msg/Range (downward)
  static constexpr const char* kThrustTopic = "thrust_command";       // tactile_msgs/msg/ThrustCommand
  static constexpr const char* kOutputTopic = "wall_effect/estimate"; // tactile_msgs/msg/WallEstimate

  struct Params {
    EkfParams ekf;
    double rate_hz = 100.0;          ///< filter rate (004: 100 Hz); ekf.dt = 1 / rate_hz
    /// wall_detected: y_hat below this and sigma_y below detection_sigma.
    /// 004: estimates reliable within 20 cm; the FSM's d_dagger = 20 cm.
    double detection_range = 0.25;   ///< [m] (choice, a little beyond d_dagger)
    double detection_sigma = 0.05;   ///< [m] (choice)
    double max_input_age_s = 0.1;    ///< thrust/IMU older than this: no step (choice)
    uint64_t min_flow_quality = 1;   ///< flow samples below this quality are dropped
    /// The commanded thrusts pass a first-order lag of this time constant
    /// before the prediction (the motors' response; 0 = none; choice: the
    /// simulated motors' 20 ms).
    double motor_time_constant = 0.02;  ///< [s]
    void validate() const;
  };

  struct Stats {
    uint64_t imu = 0, flow = 0, range = 0, thrust = 0, published = 0;
    uint64_t dropped_nonfinite = 0;       ///< NaN/inf in any input
    uint64_t dropped_bad_thrust = 0;      ///< rotor_thrust without 4 entries or negative
    uint64_t dropped_low_quality = 0;     ///< flow below min_flow_quality
    uint64_t dropped_out_of_range = 0;    ///< ToF +-inf (no return / too close)
    uint64_t ticks_without_input = 0;     ///< no thrust or IMU yet, or stale (no step, nothing published)
    uint64_t ticks_without_imu = 0;       ///< predicted only: no IMU sample since the last tick
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit WallEffectEkfLogic(const Params& params);

  void on_imu(const sensor_msgs::msg::Imu& msg);
  void on_flow(const tactile_msgs::msg::OpticalFlow& msg);
  void on_range(const sensor_msgs::msg::Range& msg);
  void on_thrust(const tactile_msgs::msg::ThrustCommand& msg);
  /// Filter step at 1 / rate_hz: predict with the latest thrusts, update with
  /// the mean IMU sample since the last tick and any new flow / ToF sample.
  std::optional<tactile_msgs::msg::WallEstimate> on_timer(int64_t now_ns);

  int64_t period_ns() const;

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: IMU, flow, ToF and thrust in (sensor data), the estimate out at
  /// period_ns() on the node's clock.
  template <class Ports>
  static void wire(Ports& p, WallEffectEkfLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto estimate = p.template publisher<tactile_msgs::msg::WallEstimate>(kOutputTopic, Pub::kData);
    p.template subscribe<sensor_msgs::msg::Imu>(kImuTopic, Sub::kSensorData,
                                                [&l](const sensor_msgs::msg::Imu& m) { l.on_imu(m); });
    p.template subscribe<tactile_msgs::msg::OpticalFlow>(kFlowTopic, Sub::kSensorData,
                                                         [&l](const tactile_msgs::msg::OpticalFlow& m) { l.on_flow(m); });
    p.template subscribe<sensor_msgs::msg::Range>(kRangeTopic, Sub::kSensorData,
                                                  [&l](const sensor_msgs::msg::Range& m) { l.on_range(m); });
    p.template subscribe<tactile_msgs::msg::ThrustCommand>(
        kThrustTopic, Sub::kSensorData, [&l](const tactile_msgs::msg::ThrustCommand& m) { l.on_thrust(m); });
    p.timer(l.period_ns(), [&l, estimate](int64_t now_ns) {
      if (auto out = l.on_timer(now_ns)) estimate(std::move(*out));
    });
  }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const WallEkf& ekf() const { return ekf_; }

 private:
  std::string body_frame_ = "base_link";  ///< of the wall estimate: the thrust command's frame
  Params params_;
  WallEkf ekf_;
  Stats stats_;
  bool started_ = false;
  Vec4 thrust_ = Vec4::Zero();      ///< latest command
  Vec4 thrust_lag_ = Vec4::Zero();  ///< after the motor lag
  bool lag_started_ = false;
  bool have_thrust_ = false;
  int64_t thrust_ns_ = 0, imu_ns_ = 0;
  bool have_imu_ = false;
  Vec3 acc_sum_ = Vec3::Zero(), gyro_sum_ = Vec3::Zero();
  int imu_count_ = 0;
  bool flow_new_ = false;
  Vec2 flow_ = Vec2::Zero();
  bool range_new_ = false;
  double range_ = 0.0;
};

}  // namespace wall_effect_ekf
