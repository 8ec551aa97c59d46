// The scenario pilot: flies the pilot script of a scenario (e.g. the paper 000
// data-collection protocol: hover to initialise, forward at 0.2 m/s, on
// contact sweep right at 0.2 m/s for 2 s) by publishing setpoints. It stands
// in for the behaviour nodes (tactile_fsm) that later issues attach.
// Node-logic layer: messages in, messages out, no ROS.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_msgs/msg/collision_event.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/whisker_signal.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_sim {

class ScriptedPilotLogic {
 public:
  static constexpr const char* kNodeName = "scenario_pilot";
  static constexpr const char* kHoverTopic = "cmd_hover";         // whisker_crazyflie
  static constexpr const char* kPositionTopic = "cmd_position";   // xplorer, ducted_quadrotor
  static constexpr const char* kOdometryTopic = "odom";
  static constexpr const char* kCollisionTopic = "collisions";
  static constexpr double kRateHz = 50.0;

  struct Outputs {
    std::optional<tactile_msgs::msg::HoverSetpoint> hover;
    std::optional<geometry_msgs::msg::PoseStamped> position;
  };

  struct Stats {
    uint64_t steps_completed = 0;
    uint64_t steps_timed_out = 0;   ///< 'until' steps that ended by their timeout
    bool finished = false;          ///< the whole script has run
    double contact_time_s = std::numeric_limits<double>::quiet_NaN();  ///< first 'until: contact' trigger
  };

  /// Throws ScenarioError if a step cannot be flown by this vehicle (e.g. a
  /// position step on the velocity-controlled Crazyflie).
  ScriptedPilotLogic(std::vector<PilotStep> script, VehicleType vehicle, const Vec3& initial_position,
                     double initial_yaw);

  /// Whisker contact (either whisker's compensated signal over threshold).
  void on_whisker_signal(const tactile_msgs::msg::WhiskerSignal& msg);
  void on_collision(const tactile_msgs::msg::CollisionEvent& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  /// At kRateHz: advances the script and returns the setpoint to publish.
  Outputs on_timer(int64_t now_ns);

  const Stats& stats() const { return stats_; }
  size_t current_step() const { return step_; }

 private:
  void start_step(int64_t now_ns);

  std::vector<PilotStep> script_;
  VehicleType vehicle_;
  size_t step_ = 0;
  bool started_ = false;
  int64_t step_start_ns_ = 0;
  int64_t last_ns_ = 0;
  bool contact_ = false;     // contact seen since the current step started
  double height_ = 0.0;      // held height setpoint
  Vec3 position_sp_;         // position vehicles: moving setpoint
  double yaw_sp_ = 0.0;
  bool have_odom_ = false;
  Vec3 odom_position_ = Vec3::Zero();
  double odom_yaw_ = 0.0;
  Stats stats_;
};

}  // namespace tactile_sim
