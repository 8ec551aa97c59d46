// Node logic of gpis_explorer: tactile depth (contact points) and odometry in;
// velocity setpoints, the GPIS map, the next exploration target and the
// exploration state out (paper 000 eq. 31-46, Extended Data Fig. 1d). No
// rclcpp: the rclcpp component and the standalone host both use this class.
#pragma once

#include <climits>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "gpis_explorer/sequencer.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/exploration_target.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/gpis_map.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/tactile_depth.hpp"

namespace gpis_explorer {

class GpisExplorerLogic {
 public:
  static constexpr const char* kNodeName = "gpis_explorer";
  static constexpr const char* kDepthTopic = "whisker/depth";     // tactile_msgs/msg/TactileDepth
  static constexpr const char* kOdomTopic = "odom";               // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "cmd_hover";      // tactile_msgs/msg/HoverSetpoint
  static constexpr const char* kStateTopic = "fsm_state";         // tactile_msgs/msg/FsmState
  static constexpr const char* kMapTopic = "gpis/map";            // tactile_msgs/msg/GpisMap
  static constexpr const char* kTargetTopic = "gpis/target";      // tactile_msgs/msg/ExplorationTarget
  /// Frames of the outputs before the first odometry; after it, the map and the target
  /// are in the odometry's header frame and the setpoint in its child (body) frame, so
  /// they follow the odometry's frame_prefix (e.g. cf1/odom, cf1/base_link).
  static constexpr const char* kFrame = "odom";
  static constexpr const char* kBodyFrame = "base_link";
  static constexpr const char* kBehaviour = "gpis_exploration";
  /// Control tick, 50 Hz as 000 ("at 50 Hz" onboard).
  static constexpr int64_t kTimerPeriodNs = 20000000;
  /// FsmState on every transition and at least at 5 Hz.
  static constexpr int64_t kStatePeriodNs = 200000000;

  struct Params {
    /// Input staleness: sequencer.wall.max_input_age_s and
    /// sequencer.wall.failsafe_land_after_s (keys max_input_age_s,
    /// failsafe_land_after_s), the wall follower's parameters and rule
    /// (tactile_fsm::input_is_fresh): stale depth or odometry -> FAILSAFE_HOVER.
    SequencerParams sequencer;
    void validate() const;
  };

  struct Stats {
    uint64_t received_depth = 0;
    uint64_t received_odom = 0;
    uint64_t dropped_nonfinite = 0;     ///< NaN/inf in a used field (depth in contact, pose, zero quaternion)
    uint64_t dropped_out_of_order = 0;  ///< stamp older than the last accepted one of that input
    uint64_t ticks = 0;
    uint64_t stale_ticks = 0;           ///< ticks with stale depth or odometry (hovered: FAILSAFE_HOVER once flying)
    uint64_t maps_published = 0;
  };

  struct Outputs {
    tactile_msgs::msg::HoverSetpoint setpoint;                 ///< every tick
    std::optional<tactile_msgs::msg::FsmState> state;          ///< transitions and 5 Hz
    std::optional<tactile_msgs::msg::GpisMap> map;             ///< after each GPIS update
    std::optional<tactile_msgs::msg::ExplorationTarget> target;  ///< after each GPIS update
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit GpisExplorerLogic(const Params& params);

  void on_depth(const tactile_msgs::msg::TactileDepth& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  Outputs on_timer(int64_t now_ns);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: depth and odometry in (sensor data); every kTimerPeriodNs on the
  /// node's clock the setpoint and the state out, the map and the target latched (a late
  /// subscriber, RViz or a recorder, still gets the last ones).
  template <class Ports>
  static void wire(Ports& p, GpisExplorerLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto setpoint = p.template publisher<tactile_msgs::msg::HoverSetpoint>(kSetpointTopic, Pub::kData);
    auto state = p.template publisher<tactile_msgs::msg::FsmState>(kStateTopic, Pub::kData);
    auto gpis_map = p.template publisher<tactile_msgs::msg::GpisMap>(kMapTopic, Pub::kLatched);
    auto target = p.template publisher<tactile_msgs::msg::ExplorationTarget>(kTargetTopic, Pub::kLatched);
    p.template subscribe<tactile_msgs::msg::TactileDepth>(kDepthTopic, Sub::kSensorData,
                                                          [&l](const tactile_msgs::msg::TactileDepth& m) { l.on_depth(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdomTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.timer(kTimerPeriodNs, [&l, setpoint, state, gpis_map, target](int64_t now_ns) {
      auto out = l.on_timer(now_ns);
      setpoint(std::move(out.setpoint));
      if (out.state) state(std::move(*out.state));
      if (out.map) gpis_map(std::move(*out.map));
      if (out.target) target(std::move(*out.target));
    });
  }

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const ExplorationSequencer& sequencer() const { return seq_; }

  /// The GPIS map message of the explorer's current state.
  static tactile_msgs::msg::GpisMap make_map(const GpisExplorer& ex, int64_t stamp_ns, const std::string& frame);

 private:
  Params params_;
  ExplorationSequencer seq_;
  Stats stats_;
  SequencerInput in_;
  double depth_t_ = NAN;  ///< stamp of the last accepted depth [s]; NaN = none yet
  double odom_t_ = NAN;   ///< ... odometry
  int64_t depth_ns_ = INT64_MIN;
  int64_t odom_ns_ = INT64_MIN;
  std::string odom_frame_ = kFrame, body_frame_ = kBodyFrame;  ///< of the last odometry
  int64_t last_state_ns_ = INT64_MIN;
};

}  // namespace gpis_explorer
