// Node logic of the whisker wall-following FSM (paper 000, Methods "Whisker-based
// aerial tactile navigation strategy", Fig. S4e): TactileDepth, the two
// WhiskerSignals and Odometry in; each step publishes HoverSetpoint and FsmState, on
// a 50 Hz timer or on a depth's arrival (wire()). No rclcpp: the rclcpp component and
// the standalone host use this class, both through wire().
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/event_tick.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_fsm/whisker_wall_follower.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/tactile_depth.hpp"
#include "tactile_msgs/msg/whisker_signal.hpp"

namespace tactile_fsm {

class WhiskerFsmLogic {
 public:
  static constexpr const char* kNodeName = "whisker_fsm";
  static constexpr const char* kBehaviour = "whisker_wall_following";
  static constexpr const char* kDepthTopic = "whisker/depth";               // tactile_msgs/msg/TactileDepth
  static constexpr const char* kLeftSignalTopic = "whisker/left/signal";    // tactile_msgs/msg/WhiskerSignal
  static constexpr const char* kRightSignalTopic = "whisker/right/signal";  // tactile_msgs/msg/WhiskerSignal
  static constexpr const char* kOdomTopic = "odom";                         // nav_msgs/msg/Odometry
  static constexpr const char* kSetpointTopic = "cmd_hover";                // tactile_msgs/msg/HoverSetpoint
  static constexpr const char* kStateTopic = "fsm_state";                   // tactile_msgs/msg/FsmState
  /// Frame of the setpoint (body-frame velocities) before the first odometry; then the
  /// odometry's child frame (it carries the vehicle's frame_prefix: cf1/base_link).
  static constexpr const char* kBodyFrame = "base_link";
  /// Control tick, 50 Hz as 000 ("at 50 Hz" onboard).
  static constexpr int64_t kTimerPeriodNs = 20000000;
  /// FsmState is published on every transition, on the tick an override rule of the
  /// FSM begins to fire (the reason names it) and at least at 5 Hz.
  static constexpr int64_t kStatePeriodNs = 200000000;

  struct Params {
    WallFollowerParams fsm;
    /// Target position in the odometry frame [m]. Not in the paper (it lands
    /// "once the fuselage passed over the final baffle"); the default is the
    /// three-baffle scenario's target, 0.6 m past the last baffle.
    double target_x = 3.6;
    double target_y = 0.0;
    /// Window of the RMS of the sample-to-sample changes of each whisker's
    /// S_c sum (phantom_quiet_rms of the core), in signal samples (25 = 0.5 s
    /// at 50 Hz, as tdorc_filter's hold_quiet_samples).
    int phantom_quiet_samples = 25;
    void validate() const;
  };

  struct Stats {
    uint64_t received_depth = 0;
    uint64_t received_signal_left = 0;
    uint64_t received_signal_right = 0;
    uint64_t received_odom = 0;
    uint64_t dropped_nonfinite = 0;     ///< NaN/inf in a used field (depth in contact, S_p, pose, quaternion of zero norm)
    uint64_t dropped_out_of_order = 0;  ///< stamp older than the last accepted one of that input
    uint64_t dropped_wrong_whisker = 0; ///< WhiskerSignal.whisker_id not the side of its topic
    uint64_t ticks = 0;
    uint64_t state_messages = 0;
    /// Ticks on which each override rule of the FSM fired (WhiskerWallFollower::override_count()).
    uint64_t rule_heading_limit = 0;
    uint64_t rule_turn_anchor = 0;
    uint64_t rule_step_and_scan = 0;
    uint64_t rule_yaw_offset = 0;
  };

  struct Outputs {
    tactile_msgs::msg::HoverSetpoint setpoint;          ///< every tick
    std::optional<tactile_msgs::msg::FsmState> state;   ///< on transitions and at 5 Hz
  };

  /// Every parameter the node reads, with the shipped defaults (WallFollowerParams').
  static tactile_common::ParamMap default_parameters();
  /// Reads and validates; throws tactile_common::ParamError naming the source,
  /// the parameter and the reason.
  static Params params_from(const tactile_common::ParamMap& map);

  explicit WhiskerFsmLogic(const Params& params);

  void on_depth(const tactile_msgs::msg::TactileDepth& msg);
  void on_left_signal(const tactile_msgs::msg::WhiskerSignal& msg);
  void on_right_signal(const tactile_msgs::msg::WhiskerSignal& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  /// 50 Hz control tick at now_ns (same clock as the message stamps).
  Outputs on_timer(int64_t now_ns);

  /// How the node steps: the one thing its hosts choose (tactile_common/event_tick.hpp).
  struct Stepping {
    /// Event driven: each TactileDepth steps the FSM at its receive time (unless `tick`
    /// rate-limits it) and the 50 Hz timer is tick's watchdog, stepping it once depth
    /// stops. Null: the 50 Hz timer steps it every 20 ms and a depth is only stored (the
    /// simulated hosts: the simulator's timer fires first at each tick, so the step sees
    /// the depth of that tick's pressure and the order of a run is fixed). Not owned.
    tactile_common::EventTick* tick = nullptr;
    /// A step never goes back in time: one due before the previous step runs at the
    /// previous step's time. For a host whose timer clock lags its receive clock
    /// (`tactile fly`: the executor fires an overdue watchdog with its due time, after a
    /// depth stepped the FSM at the wall clock). Off in rclcpp, where both are the node's
    /// clock and a clock that goes back (a bag played again) starts the FSM's time over.
    bool monotonic = false;
  };

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: depth, the two signals and odometry in (in that order), HoverSetpoint
  /// and FsmState out on each step, the 50 Hz timer.
  template <class Ports>
  static void wire(Ports& p, WhiskerFsmLogic& l, Stepping stepping = {}) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto setpoint = p.template publisher<tactile_msgs::msg::HoverSetpoint>(kSetpointTopic, Pub::kData);
    auto state = p.template publisher<tactile_msgs::msg::FsmState>(kStateTopic, Pub::kData);
    auto last_ns = stepping.monotonic ? std::make_shared<int64_t>(std::numeric_limits<int64_t>::min()) : nullptr;
    auto step = [&l, setpoint, state, last_ns](int64_t now_ns) {
      if (last_ns) now_ns = *last_ns = std::max(now_ns, *last_ns);
      auto out = l.on_timer(now_ns);
      setpoint(std::move(out.setpoint));
      if (out.state) state(std::move(*out.state));
    };
    tactile_common::EventTick* tick = stepping.tick;
    p.template subscribe<tactile_msgs::msg::TactileDepth>(
        kDepthTopic, Sub::kSensorData,
        [&l, tick, step](const tactile_msgs::msg::TactileDepth& m, int64_t receive_ns) {
          l.on_depth(m);
          if (tick && tick->on_event(receive_ns)) step(receive_ns);
        });
    p.template subscribe<tactile_msgs::msg::WhiskerSignal>(
        kLeftSignalTopic, Sub::kSensorData, [&l](const tactile_msgs::msg::WhiskerSignal& m) { l.on_left_signal(m); });
    p.template subscribe<tactile_msgs::msg::WhiskerSignal>(
        kRightSignalTopic, Sub::kSensorData, [&l](const tactile_msgs::msg::WhiskerSignal& m) { l.on_right_signal(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdomTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.timer(kTimerPeriodNs, [tick, step](int64_t now_ns) {
      if (!tick || tick->on_watchdog()) step(now_ns);
    });
  }

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const WhiskerWallFollower& fsm() const { return fsm_; }

 private:
  std::string body_frame_ = kBodyFrame;
  /// Last phantom_quiet_samples S_c sums of one whisker (ring, allocated once).
  struct SumWindow {
    std::vector<double> v;
    std::size_t next = 0, count = 0;
    void push(double sum);
    /// RMS of the sample-to-sample changes over the full window; NaN until full.
    double change_rms() const;
  };
  bool on_signal(const tactile_msgs::msg::WhiskerSignal& msg, uint8_t expected_id, int64_t& stamp, bool& contact,
                 double& input_sum, SumWindow& window);

  Params params_;
  WhiskerWallFollower fsm_;
  Stats stats_;
  WallFollowerInput in_;
  int64_t depth_ns_ = INT64_MIN, odom_ns_ = INT64_MIN, left_ns_ = INT64_MIN, right_ns_ = INT64_MIN;
  bool left_contact_ = false, right_contact_ = false;
  double left_sum_ = NAN, right_sum_ = NAN;  ///< sum of the three S_c of the last signal [Pa]
  SumWindow left_window_, right_window_;
  int64_t last_state_pub_ns_ = INT64_MIN;
  std::string previous_state_name_;  ///< state before the last transition ("" at start)
  std::string current_state_name_;   ///< "STATE" or "WALL_FOLLOWING/SUB_STATE"
};

}  // namespace tactile_fsm
