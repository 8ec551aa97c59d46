// Node logic of the wall-effect behaviours (004 wall following and vector
// field, wall_effect_navigation.hpp): the wall estimate and odometry in, the
// INDI controller's setpoint and the behaviour state out at 100 Hz.
//
// Stale input goes through the shared SafetyRunner (safety_runner.hpp), once
// both inputs have come: odometry or wall estimate older than max_input_age_s
// -> FAILSAFE_HOVER at the position the drone was last known at, fresh again
// -> the navigator resumes, stale for failsafe_land_after_s -> FAILSAFE_LAND:
// that x, y held, z velocity-only at -failsafe_land_speed. The landing reads no
// odometry (it may be the stale input) and needs no height: the INDI
// controller flies the descent on its own odometry, and on the floor its
// incremental thrust (004 eq. 34) winds down to zero.
#pragma once

#include <cstdint>
#include <array>
#include <optional>
#include <string>
#include <utility>

#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_fsm/safety_runner.hpp"
#include "tactile_fsm/wall_effect_navigation.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"

namespace tactile_fsm {

class WallEffectNavLogic {
 public:
  static constexpr const char* kNodeName = "wall_effect_nav";
  static constexpr const char* kWallTopic = "wall_effect/estimate";     // tactile_msgs/msg/WallEstimate
  static constexpr const char* kOdomTopic = "odom";                     // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "wall_effect/setpoint"; // nav_msgs/msg/Odometry (world; NaN x, y = velocity only)
  static constexpr const char* kStateTopic = "fsm_state";               // tactile_msgs/msg/FsmState
  static constexpr int64_t kTimerPeriodNs = 10'000'000;                  // 100 Hz

  struct Params {
    WallEffectNavParams nav;
    /// "position" (goal_x, goal_y in the world), "gps" (gps_goal as ENU of
    /// gps_origin through GeographicLib) or "direction" (pilot heading direction_deg).
    std::string goal_mode = "position";
    double goal_x = 0.0, goal_y = 0.0;
    std::array<double, 3> gps_origin{{0.0, 0.0, 0.0}};  ///< lat, lon [deg], alt [m]
    std::array<double, 3> gps_goal{{0.0, 0.0, 0.0}};
    double direction_deg = 0.0;
    /// The shared fail-safe: max_input_age_s (older odometry or wall estimate:
    /// FAILSAFE_HOVER instead of steering by the last distance) and
    /// failsafe_land_after_s (-> FAILSAFE_LAND); no time limit (time_limit_s infinite).
    SafetyParams safety;
    /// FAILSAFE_LAND: descent speed, a velocity-only z setpoint [m/s] (choice: the
    /// land_speed of the Crazyflie bridge and of the simulated Crazyflie, 0.25 m/s).
    double failsafe_land_speed = 0.25;
    NavGoal goal() const;          ///< resolved goal (GPS -> ENU)
    void validate() const;
  };

  struct Stats {
    uint64_t ticks = 0, walls = 0, odometry = 0;
    uint64_t dropped_nonfinite = 0;
    uint64_t ticks_without_odometry = 0;  ///< odometry missing or stale (before both inputs came: nothing published)
    uint64_t ticks_wall_stale = 0;        ///< wall estimate stale (FAILSAFE_HOVER / FAILSAFE_LAND)
    uint64_t failsafe_hovers = 0;         ///< entries of FAILSAFE_HOVER
    uint64_t failsafe_landings = 0;       ///< entries of FAILSAFE_LAND
  };

  struct Outputs {
    std::optional<nav_msgs::msg::Odometry> setpoint;
    std::optional<tactile_msgs::msg::FsmState> state;  ///< on transitions and at 2 Hz
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  explicit WallEffectNavLogic(const Params& params);

  void on_wall(const tactile_msgs::msg::WallEstimate& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  Outputs on_timer(int64_t now_ns);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: wall estimate and odometry in (sensor data), the setpoint and the
  /// state out every kTimerPeriodNs on the node's clock.
  template <class Ports>
  static void wire(Ports& p, WallEffectNavLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto setpoint = p.template publisher<nav_msgs::msg::Odometry>(kSetpointTopic, Pub::kData);
    auto state = p.template publisher<tactile_msgs::msg::FsmState>(kStateTopic, Pub::kData);
    p.template subscribe<tactile_msgs::msg::WallEstimate>(kWallTopic, Sub::kSensorData,
                                                          [&l](const tactile_msgs::msg::WallEstimate& m) { l.on_wall(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdomTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.timer(kTimerPeriodNs, [&l, setpoint, state](int64_t now_ns) {
      auto out = l.on_timer(now_ns);
      if (out.setpoint) setpoint(std::move(*out.setpoint));
      if (out.state) state(std::move(*out.state));
    });
  }

  const WallEffectNavigator& navigator() const { return nav_; }
  const SafetyRunner& safety() const { return safety_; }
  const Params& params() const { return params_; }
  const Stats& stats() const { return stats_; }

 private:
  Params params_;
  WallEffectNavigator nav_;
  SafetyRunner safety_;
  Stats stats_;
  bool have_wall_ = false, have_odom_ = false;
  /// Frame of the setpoints: the odometry's header frame (odom, or cf1/odom with a
  /// frame_prefix), whose positions they are computed from.
  std::string odom_frame_ = "odom";
  double wall_distance_ = 0.0, wall_direction_ = 0.0;
  Vec2 position_ = Vec2::Zero();
  double yaw_ = 0.0;
  int64_t odom_ns_ = 0, wall_ns_ = 0, state_since_ns_ = 0, last_state_pub_ns_ = -1;
  Vec2 hover_ = Vec2::Zero();  ///< FAILSAFE_HOVER / FAILSAFE_LAND: x, y held (last known on entry)
  NavState last_state_;
  std::string previous_state_, reason_ = "start";
  uint8_t reason_code_ = 0;          ///< FsmState.reason_code: the fail-safe's codes; the navigator has none
  uint32_t safety_transitions_ = 0;  ///< fail-safe entries and resumes (FsmState.transitions)

  std::string behaviour_name() const;
  nav_msgs::msg::Odometry failsafe_setpoint(int64_t now_ns, bool landing) const;
};

}  // namespace tactile_fsm
