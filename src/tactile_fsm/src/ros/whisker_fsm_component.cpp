// rclcpp component of the whisker wall-following FSM: a mechanical adapter
// around WhiskerFsmLogic (all behaviour lives there). ROS builds only.
//
// Event driven (tactile_common/event_tick.hpp): the FSM steps when a TactileDepth
// arrives (the depth node publishes it on the pressure pair's arrival), so a pressure
// sample reaches the setpoint without waiting for a timer's phase; a 50 Hz watchdog
// timer steps it when depth stops, so the stale-depth fail-safe (max_input_age_s)
// acts as it did with the timer-driven step.
#include <chrono>
#include <memory>
#include <utility>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/event_tick.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"

namespace tactile_fsm {

class WhiskerFsmComponent : public rclcpp::Node {
 public:
  explicit WhiskerFsmComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerFsmLogic::kNodeName, options),
    parameters_(*this, WhiskerFsmLogic::default_parameters()),  // every key read-only
    logic_(WhiskerFsmLogic::params_from(parameters_.values())),
    tick_(WhiskerFsmLogic::kTimerPeriodNs)
  {
    setpoint_pub_ = tactile_common::data_publisher<tactile_msgs::msg::HoverSetpoint>(*this, WhiskerFsmLogic::kSetpointTopic);
    state_pub_ = tactile_common::data_publisher<tactile_msgs::msg::FsmState>(*this, WhiskerFsmLogic::kStateTopic);
    depth_sub_ = create_subscription<tactile_msgs::msg::TactileDepth>(
      WhiskerFsmLogic::kDepthTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::TactileDepth & msg) {
        logic_.on_depth(msg);
        const int64_t now_ns = now().nanoseconds();
        if (tick_.on_event(now_ns)) {step(now_ns);}
      });
    left_sub_ = create_subscription<tactile_msgs::msg::WhiskerSignal>(
      WhiskerFsmLogic::kLeftSignalTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WhiskerSignal & msg) {logic_.on_left_signal(msg);});
    right_sub_ = create_subscription<tactile_msgs::msg::WhiskerSignal>(
      WhiskerFsmLogic::kRightSignalTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WhiskerSignal & msg) {logic_.on_right_signal(msg);});
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
      WhiskerFsmLogic::kOdomTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    // The watchdog at 50 Hz on the node clock: simulated time under use_sim_time (the
    // SITL launches, any real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(WhiskerFsmLogic::kTimerPeriodNs),
      [this]() {
        if (tick_.on_watchdog()) {step(now().nanoseconds());}
      });
  }

 private:
  void step(int64_t now_ns)
  {
    auto out = logic_.on_timer(now_ns);
    setpoint_pub_->publish(
      std::make_unique<tactile_msgs::msg::HoverSetpoint>(std::move(out.setpoint)));
    if (out.state) {
      state_pub_->publish(
        std::make_unique<tactile_msgs::msg::FsmState>(std::move(*out.state)));
    }
  }

  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WhiskerFsmLogic logic_;
  tactile_common::EventTick tick_;
  rclcpp::Publisher<tactile_msgs::msg::HoverSetpoint>::SharedPtr setpoint_pub_;
  rclcpp::Publisher<tactile_msgs::msg::FsmState>::SharedPtr state_pub_;
  rclcpp::Subscription<tactile_msgs::msg::TactileDepth>::SharedPtr depth_sub_;
  rclcpp::Subscription<tactile_msgs::msg::WhiskerSignal>::SharedPtr left_sub_;
  rclcpp::Subscription<tactile_msgs::msg::WhiskerSignal>::SharedPtr right_sub_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_sub_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::WhiskerFsmComponent)
