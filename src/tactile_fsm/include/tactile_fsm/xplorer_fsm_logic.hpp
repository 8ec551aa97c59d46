// Node logic of the XPLORER behaviours (paper 001 Sec. III-B, IV): the fused
// external wrench (xplorer_force_est, world frame) and the odometry in; a
// 50 Hz timer publishes the position/yaw setpoint and the FSM state. No
// rclcpp: the rclcpp component and the standalone host use this class.
//
// Stale input goes through the shared SafetyRunner (safety_runner.hpp):
// odometry or wrench older than max_input_age_s -> FAILSAFE_HOVER (the last
// position setpoint held), fresh again -> the FSM resumes, stale for
// failsafe_land_after_s -> FAILSAFE_LAND: x, y and yaw of the last setpoint,
// its height descending at failsafe_land_speed to kLandFloorZ. The landing
// reads no odometry (it may be the stale input): the vehicle's own position
// loop flies the descending setpoint on its own estimate.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_fsm/safety_runner.hpp"
#include "tactile_fsm/xplorer_explorer.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"

namespace tactile_fsm {

class XplorerFsmLogic {
 public:
  static constexpr const char* kNodeName = "xplorer_fsm";
  static constexpr const char* kBehaviour = "xplorer_exploration";
  static constexpr const char* kWrenchTopic = "xplorer/wrench";          // geometry_msgs/msg/WrenchStamped (world)
  static constexpr const char* kOdomTopic = "odom";                      // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "cmd_position";          // geometry_msgs/msg/PoseStamped
  static constexpr const char* kStateTopic = "xplorer/fsm_state";        // tactile_msgs/msg/FsmState
  static constexpr int64_t kTimerPeriodNs = 20000000;   ///< 50 Hz (the arm IMU and force-estimate rate)
  static constexpr int64_t kStatePeriodNs = 200000000;  ///< FsmState at least at 5 Hz and on transitions
  /// FAILSAFE_LAND: the height setpoint stops this far below the ground of the odometry
  /// frame (z = 0, REP 105's start pose, from which hover_height is measured) [m]. Below
  /// it, not at it: a setpoint on the floor would leave the position loop at hover thrust
  /// there; 10 cm under it the loop presses the vehicle onto the floor and its thrust
  /// falls below hover (SITL: XplorerSitl.StaleOdometryLands). Choice.
  static constexpr double kLandFloorZ = -0.1;

  struct Params {
    XplorerParams fsm;
    /// Frame of the position setpoints and of the wrench taken (the world force of
    /// xplorer_force_est): the odometry's frame (REP 105; cf1/odom with a frame prefix).
    std::string frame_id = "odom";
    /// The shared fail-safe: max_input_age_s (older odometry or wrench: FAILSAFE_HOVER)
    /// and failsafe_land_after_s (-> FAILSAFE_LAND); no time limit (time_limit_s infinite).
    SafetyParams safety;
    /// FAILSAFE_LAND: descent speed of the height setpoint [m/s] (choice: the land_speed
    /// of the Crazyflie bridge and of the simulated Crazyflie, 0.25 m/s).
    double failsafe_land_speed = 0.25;
    void validate() const;
  };

  struct Stats {
    uint64_t received_wrench = 0;
    uint64_t received_odom = 0;
    uint64_t dropped_nonfinite = 0;
    uint64_t dropped_wrong_frame = 0;   ///< wrench not in the world frame
    uint64_t dropped_out_of_order = 0;
    uint64_t ticks = 0;
    uint64_t ticks_stale = 0;           ///< no input yet, FAILSAFE_HOVER or FAILSAFE_LAND: the FSM not stepped
    uint64_t failsafe_hovers = 0;       ///< entries of FAILSAFE_HOVER
    uint64_t failsafe_landings = 0;     ///< entries of FAILSAFE_LAND
    uint64_t state_messages = 0;
  };

  struct Outputs {
    std::optional<geometry_msgs::msg::PoseStamped> setpoint;
    std::optional<tactile_msgs::msg::FsmState> state;
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);
  explicit XplorerFsmLogic(const Params& params);

  void on_wrench(const geometry_msgs::msg::WrenchStamped& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  Outputs on_timer(int64_t now_ns);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: wrench and odometry in (sensor data), the position setpoint and the
  /// state out every kTimerPeriodNs on the node's clock (sim time under use_sim_time).
  template <class Ports>
  static void wire(Ports& p, XplorerFsmLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto setpoint = p.template publisher<geometry_msgs::msg::PoseStamped>(kSetpointTopic, Pub::kData);
    auto state = p.template publisher<tactile_msgs::msg::FsmState>(kStateTopic, Pub::kData);
    p.template subscribe<geometry_msgs::msg::WrenchStamped>(
        kWrenchTopic, Sub::kSensorData, [&l](const geometry_msgs::msg::WrenchStamped& m) { l.on_wrench(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdomTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.timer(kTimerPeriodNs, [&l, setpoint, state](int64_t now_ns) {
      auto out = l.on_timer(now_ns);
      if (out.setpoint) setpoint(std::move(*out.setpoint));
      if (out.state) state(std::move(*out.state));
    });
  }

  const XplorerExplorer& fsm() const { return fsm_; }
  /// The FSM's clock at time t [s]: t less the time held in FAILSAFE_HOVER, so
  /// its timers (release_time, settle_time, recovery_time, ...) are paused
  /// while the runner holds the vehicle (as the GPIS sequencer's are): a
  /// resumed state goes on with the time it had left.
  double fsm_clock(double t) const { return t - safety_.held_s(); }
  const SafetyRunner& safety() const { return safety_; }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }

 private:
  Params params_;
  XplorerExplorer fsm_;
  SafetyRunner safety_;
  Stats stats_;
  std::optional<nav_msgs::msg::Odometry> odom_;
  std::optional<geometry_msgs::msg::WrenchStamped> wrench_;
  int64_t last_tick_ns_ = -1, last_state_ns_ = -1;
  XplorerState last_state_ = XplorerState::kTakeoff;
  std::string previous_state_;
  XVec3 hold_ = XVec3::Zero();
  double hold_yaw_ = 0.0;
  bool have_hold_ = false;
  /// The fail-safe's resume (REASON_FAILSAFE_INPUTS_FRESH) stays the published reason until
  /// the FSM's own next transition or reason code.
  bool show_resume_ = false;
  uint32_t resume_transitions_ = 0;
  XplorerReason resume_reason_ = XplorerReason::kNone;
  double resume_t_ = 0.0;
  uint32_t safety_transitions_ = 0;  ///< fail-safe entries and resumes (FsmState.transitions)

  tactile_msgs::msg::FsmState state_message(int64_t now_ns) const;
};

}  // namespace tactile_fsm
