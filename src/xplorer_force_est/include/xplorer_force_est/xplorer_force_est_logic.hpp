// Node logic of xplorer_force_est: arm IMUs, flight-controller IMU and thrust
// command in, the external wrench (paper 001 eq. 2-7 + yaw-torque observer)
// out as geometry_msgs/WrenchStamped in the world and body frames. No rclcpp:
// the rclcpp component and the standalone host both use this class.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/arm_imu_array.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "xplorer_force_est/force_estimator.hpp"

namespace xplorer_force_est {

class XplorerForceEstLogic {
 public:
  static constexpr const char* kNodeName = "xplorer_force_est";
  static constexpr const char* kArmImuTopic = "arm_imu";               // tactile_msgs/msg/ArmImuArray
  static constexpr const char* kImuTopic = "imu";                      // sensor_msgs/msg/Imu
  static constexpr const char* kThrustTopic = "thrust_command";        // tactile_msgs/msg/ThrustCommand
  static constexpr const char* kWrenchWorldTopic = "xplorer/wrench";     // geometry_msgs/msg/WrenchStamped (world)
  static constexpr const char* kWrenchBodyTopic = "xplorer/wrench_body"; // geometry_msgs/msg/WrenchStamped (body)

  struct Params {
    xplorer_force_est::Params estimator;
    std::string world_frame = "odom";  ///< of the IMU attitude that rotates the force (REP 105; was map)
    std::string body_frame = "base_link";
    /// A stamp gap larger than this on the arm or IMU stream resets the
    /// filters (choice: 0.5 s = 25 arm samples). An arm set more than this
    /// after the last flight-controller IMU sample (the IMU stopped after it
    /// had started) publishes no wrench: its world frame and CoM part would
    /// come from a stale attitude and acceleration while its stamp is fresh,
    /// and the XPLORER FSM would move on it.
    double max_sample_gap_s = 0.5;
    /// |arm_angle| above this is not a deflection (the arms stop at 30 deg,
    /// 001 Sec. II): treated as missing (choice: 0.8 rad).
    double max_arm_angle = 0.8;
    void validate() const;
  };

  struct Stats {
    uint64_t received_arm = 0;
    uint64_t received_imu = 0;
    uint64_t received_thrust = 0;
    uint64_t published = 0;
    uint64_t published_degraded = 0;     ///< estimate with a missing arm or without the CoM part
    uint64_t dropped_nonfinite_imu = 0;  ///< NaN/inf accelerometer, gyro or attitude
    uint64_t dropped_nonfinite_thrust = 0;
    uint64_t dropped_out_of_order = 0;   ///< arm or IMU stamp not after the previous one
    uint64_t arm_bad_id = 0;             ///< arm_id > 3 or repeated within one message (entry ignored)
    uint64_t arm_from_orientation = 0;   ///< arm_angle NaN, angle derived from the arm IMU attitude
    uint64_t arm_out_of_range = 0;       ///< |arm_angle| > max_arm_angle (treated as missing)
    std::array<uint64_t, 4> arm_missing{};  ///< per arm: absent or unusable in an ArmImuArray
    uint64_t resets_on_gap = 0;
    uint64_t dropped_imu_stale = 0;      ///< arm set with the flight-controller IMU older than max_sample_gap_s: no wrench
  };

  struct Outputs {
    std::optional<geometry_msgs::msg::WrenchStamped> world;
    std::optional<geometry_msgs::msg::WrenchStamped> body;
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit XplorerForceEstLogic(const Params& params);

  /// Arm IMU set (50 Hz): runs eq. 2-4, 6, 7 and publishes the wrench.
  Outputs on_arm_imu(const tactile_msgs::msg::ArmImuArray& msg);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: arm IMU set, flight-controller IMU and thrust in (sensor data); the
  /// world and body wrenches out after each arm IMU set.
  template <class Ports>
  static void wire(Ports& p, XplorerForceEstLogic& l);
  /// Flight-controller IMU: eq. 5 and the yaw-torque observer.
  void on_imu(const sensor_msgs::msg::Imu& msg);
  /// Thrust command: f = normalised x thrust_scale (001 Sec. V-A3), or the
  /// total thrust when the normalised command is NaN; per-rotor thrusts feed
  /// the yaw observer.
  void on_thrust(const tactile_msgs::msg::ThrustCommand& msg);

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const Estimate& estimate() const { return estimator_.estimate(); }

 private:
  Params params_;
  XplorerForceEstimator estimator_;
  Stats stats_;
  Quat q_wb_ = Quat::Identity();
  bool have_attitude_ = false;
  bool have_arm_stamp_ = false, have_imu_stamp_ = false;
  int64_t last_arm_ns_ = 0, last_imu_ns_ = 0;
};

template <class Ports>
void XplorerForceEstLogic::wire(Ports& p, XplorerForceEstLogic& l) {
  using geometry_msgs::msg::WrenchStamped;
  using tactile_common::ports::Pub;
  using tactile_common::ports::Sub;
  auto world = p.template publisher<WrenchStamped>(kWrenchWorldTopic, Pub::kData);
  auto body = p.template publisher<WrenchStamped>(kWrenchBodyTopic, Pub::kData);
  p.template subscribe<tactile_msgs::msg::ArmImuArray>(
      kArmImuTopic, Sub::kSensorData, [&l, world, body](const tactile_msgs::msg::ArmImuArray& m) {
        auto out = l.on_arm_imu(m);
        if (out.world) world(std::move(*out.world));
        if (out.body) body(std::move(*out.body));
      });
  p.template subscribe<sensor_msgs::msg::Imu>(kImuTopic, Sub::kSensorData,
                                              [&l](const sensor_msgs::msg::Imu& m) { l.on_imu(m); });
  p.template subscribe<tactile_msgs::msg::ThrustCommand>(
      kThrustTopic, Sub::kSensorData, [&l](const tactile_msgs::msg::ThrustCommand& m) { l.on_thrust(m); });
}

}  // namespace xplorer_force_est
