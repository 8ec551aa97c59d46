// Node logic of the INDI controller of the ducted quadrotor (paper 004
// eq. 26-36): position setpoint, odometry (motion capture or GPS), IMU and
// the wall estimate in, the four rotor thrust commands out. Outer loop
// (eq. 26, 30-34) at outer_rate_hz, inner loop (eq. 35-36) at rate_hz.
//
// Setpoint (nav_msgs/Odometry on kSetpointTopic, world frame): pose.position
// is p_d, the yaw of pose.orientation is psi_d, twist.linear is p_dot_d
// (world frame). A NaN position component makes that axis velocity-only
// (004: a pilot's direction with K_p = K_i = 0).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "wall_effect_ekf/indi_controller.hpp"

namespace wall_effect_ekf {

/// Body -> wall-frame rotation (wall_effect_model.hpp) from the body -> world
/// attitude and the wall direction psi-hat in the body frame.
Mat3 wall_frame_attitude(const Mat3& R_world_body, double wall_direction_body);

class IndiControlLogic {
 public:
  static constexpr const char* kNodeName = "indi_controller";
  static constexpr const char* kSetpointTopic = "wall_effect/setpoint";  // nav_msgs/msg/Odometry (world)
  static constexpr const char* kOdometryTopic = "odom";                  // nav_msgs/msg/Odometry
  static constexpr const char* kImuTopic = "imu";                        // sensor_msgs/msg/Imu (with orientation)
  static constexpr const char* kWallTopic = "wall_effect/estimate";      // tactile_msgs/msg/WallEstimate
  static constexpr const char* kOutputTopic = "cmd_rotor_thrust";        // tactile_msgs/msg/ThrustCommand

  struct Params {
    IndiParams indi;
    double rate_hz = 500.0;        ///< inner loop (IMU rate of the simulated vehicle; choice)
    double outer_rate_hz = 100.0;  ///< outer loop (004: 100 Hz ground station)
    bool use_wall_in_allocation = true;  ///< eq. 36: B with the wall estimate when detected
    double max_input_age_s = 0.1;  ///< odometry / IMU older than this: hold the last thrusts... see README
    void validate() const;
  };

  struct Stats {
    uint64_t setpoints = 0, odometry = 0, imu = 0, walls = 0, published = 0;
    uint64_t dropped_nonfinite = 0;   ///< NaN/inf where a number is required
    uint64_t ticks_without_input = 0; ///< no odometry/IMU yet or stale: motors idle (on the ground) or hover thrust
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  explicit IndiControlLogic(const Params& params);

  void on_setpoint(const nav_msgs::msg::Odometry& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  void on_imu(const sensor_msgs::msg::Imu& msg);
  void on_wall(const tactile_msgs::msg::WallEstimate& msg);
  std::optional<tactile_msgs::msg::ThrustCommand> on_timer(int64_t now_ns);

  int64_t period_ns() const;

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: the setpoint in reliable (a command, never dropped), odometry, IMU and
  /// wall estimate in as sensor data; the rotor thrusts out at period_ns() on the node's clock.
  template <class Ports>
  static void wire(Ports& p, IndiControlLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto thrust = p.template publisher<tactile_msgs::msg::ThrustCommand>(kOutputTopic, Pub::kData);
    p.template subscribe<nav_msgs::msg::Odometry>(kSetpointTopic, Sub::kReliable,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_setpoint(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdometryTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.template subscribe<sensor_msgs::msg::Imu>(kImuTopic, Sub::kSensorData,
                                                [&l](const sensor_msgs::msg::Imu& m) { l.on_imu(m); });
    p.template subscribe<tactile_msgs::msg::WallEstimate>(kWallTopic, Sub::kSensorData,
                                                          [&l](const tactile_msgs::msg::WallEstimate& m) { l.on_wall(m); });
    p.timer(l.period_ns(), [&l, thrust](int64_t now_ns) {
      if (auto out = l.on_timer(now_ns)) thrust(std::move(*out));
    });
  }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const IndiController& controller() const { return ctl_; }

 private:
  std::string body_frame_ = "base_link";  ///< of the rotor thrusts: the odometry's child frame
  Params params_;
  IndiController ctl_;
  Stats stats_;
  IndiSetpoint sp_;
  bool have_sp_ = false, have_odom_ = false, have_imu_ = false, have_wall_ = false;
  int64_t odom_ns_ = 0, imu_ns_ = 0, wall_ns_ = 0;
  Vec3 pos_ = Vec3::Zero(), vel_ = Vec3::Zero();
  Mat3 R_ = Mat3::Identity();
  Vec3 acc_ = Vec3(0, 0, kGravity), gyro_ = Vec3::Zero();
  bool wall_detected_ = false;
  double wall_distance_ = 0.0, wall_direction_ = 0.0;
  int64_t ticks_ = 0;
  int outer_every_ = 5;
};

}  // namespace wall_effect_ekf
