// Setpoint scripts of 004's estimation experiments, as a node publishing the
// INDI controller's setpoint (IndiControlLogic::kSetpointTopic), for a wall
// along x at y = 0 (004 Fig. 3a; world frame = wall frame):
//
// - "estimation_flight" (004 "In-flight distance estimation", Fig. 4a): take
//   off at the start point; from t_start (5 s) hold y_d = 0.18 m at 1.0 m and
//   psi_d = 0; from 25 s y_d = 0.18 - 0.03 sin(t - 25) until 41 s; then psi_d
//   ramps by -90 deg (from 41 s), the sinusoid repeats, and psi_d ramps by a
//   further -90 deg (from 66 s). 004 says "varied by 90 deg in 30 s twice,
//   starting at t = 41 s and t = 66 s"; the ramp length is a parameter
//   (yaw_ramp_s, default 10 s so the two ramps do not overlap).
// - "hold": from t_start hold y_d = wall_distance, psi_d = yaw_deg.
// - "sweep" (004 Fig. 5): from t_start hold each of sweep_distances for
//   sweep_hold_s (004: 11 hovers of 60 s, 13 to 23 cm), psi_d = yaw_deg.
//
// Core + node logic in one header (no ROS).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "wall_effect_ekf/wall_effect_model.hpp"

namespace wall_effect_ekf {

struct TrajectoryParams {
  std::string mode = "estimation_flight";  ///< "estimation_flight", "hold" or "sweep"
  double x = 0.0;                ///< position along the wall [m]
  double start_y = 0.4;          ///< take-off distance (004: ~40 cm) [m]
  double height = 1.0;           ///< [m] (004: 1.0 m)
  double wall_distance = 0.18;   ///< y_d [m] (004: 18 cm)
  double amplitude = 0.03;       ///< sinusoid amplitude [m] (004: 0.03 m)
  double angular_frequency = 1.0;  ///< of sin(w (t - t0)) [rad/s] (004: sin(t - 25))
  double t_start = 5.0;          ///< [s] (004: t = 5 s)
  double t_sine = 25.0;          ///< [s] (004: 25 s)
  double t_sine_end = 41.0;      ///< [s] (004: 41 s)
  double t_yaw1 = 41.0;          ///< [s] (004: 41 s)
  double t_yaw2 = 66.0;          ///< [s] (004: 66 s)
  double yaw_ramp_s = 10.0;      ///< duration of each 90 deg ramp [s] (choice, see above)
  double yaw_deg = 0.0;          ///< psi_d of "hold"/"sweep" and before the ramps [deg] (004: 0)
  /// y_d of the "sweep" segments [m] (004 Fig. 5: 13 to 23 cm, 11 flights).
  std::vector<double> sweep_distances = {0.13, 0.14, 0.15, 0.16, 0.17, 0.18, 0.19, 0.20, 0.21, 0.22, 0.23};
  double sweep_hold_s = 60.0;    ///< [s] (004: 60 s each)
  /// The setpoints are in odom (the frame of the odometry the controller tracks
  /// with, REP 105) behind this prefix ("" or ending in '/': cf1/odom).
  std::string frame_prefix;
  void validate() const;
};

struct TrajectorySetpoint {
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  double yaw = 0.0;
};

/// Index of the sweep segment at time t (-1 before t_start or after the last).
int sweep_segment(const TrajectoryParams& p, double t);
/// The setpoint at time t [s] (004 protocol above).
TrajectorySetpoint trajectory_setpoint(const TrajectoryParams& p, double t);

class WallTrajectoryLogic {
 public:
  static constexpr const char* kNodeName = "wall_trajectory";
  static constexpr const char* kOutputTopic = "wall_effect/setpoint";  // nav_msgs/msg/Odometry
  static constexpr int64_t kPeriodNs = 10'000'000;                      // 100 Hz

  static tactile_common::ParamMap default_parameters();
  static TrajectoryParams params_from(const tactile_common::ParamMap& map);
  explicit WallTrajectoryLogic(const TrajectoryParams& p);
  nav_msgs::msg::Odometry on_timer(int64_t now_ns) const;

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: the setpoint out every kPeriodNs on the node's clock.
  template <class Ports>
  static void wire(Ports& p, WallTrajectoryLogic& l) {
    auto setpoint = p.template publisher<nav_msgs::msg::Odometry>(kOutputTopic, tactile_common::ports::Pub::kData);
    p.timer(kPeriodNs, [&l, setpoint](int64_t now_ns) { setpoint(l.on_timer(now_ns)); });
  }
  const TrajectoryParams& params() const { return p_; }

 private:
  TrajectoryParams p_;
};

}  // namespace wall_effect_ekf
