// rclcpp component of the Crazyflie bridge: a mechanical adapter around
// BridgeRunner / CrazyflieBridgeLogic (all behaviour lives there). One wall
// timer at setpoint_rate_hz receives the pending log data (at most 5 ms),
// publishes it and sends the setpoint: link I/O stays on one thread. ROS
// builds only.
#include <chrono>
#include <memory>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"

namespace crazyflie_bridge {

class CrazyflieBridgeComponent : public rclcpp::Node {
 public:
  explicit CrazyflieBridgeComponent(const rclcpp::NodeOptions & options)
  : Node(CrazyflieBridgeLogic::kNodeName, options),
    runner_(CrazyflieBridgeLogic::params_from(
      tactile_common::declare_parameters(*this, CrazyflieBridgeLogic::default_parameters())))
  {
    left_pub_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      CrazyflieBridgeLogic::kLeftPressureTopic, rclcpp::SensorDataQoS());
    right_pub_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      CrazyflieBridgeLogic::kRightPressureTopic, rclcpp::SensorDataQoS());
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>(
      CrazyflieBridgeLogic::kOdomTopic, rclcpp::SensorDataQoS());
    setpoint_sub_ = create_subscription<tactile_msgs::msg::HoverSetpoint>(
      CrazyflieBridgeLogic::kSetpointTopic, rclcpp::QoS(10),
      [this](const tactile_msgs::msg::HoverSetpoint & msg) {
        runner_.on_hover_setpoint(msg, now().nanoseconds());
      });
    sinks_.left = [this](const tactile_msgs::msg::WhiskerPressure & m) {left_pub_->publish(m);};
    sinks_.right = [this](const tactile_msgs::msg::WhiskerPressure & m) {right_pub_->publish(m);};
    sinks_.odom = [this](const nav_msgs::msg::Odometry & m) {odom_pub_->publish(m);};
    const double rate = get_parameter("setpoint_rate_hz").as_double();
    timer_ = create_wall_timer(
      std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate)),
      [this]() {
        runner_.pump(std::chrono::milliseconds(5), [this]() {return now().nanoseconds();}, sinks_);
        runner_.on_timer(now().nanoseconds());
      });
  }

 private:
  BridgeRunner runner_;
  BridgeRunner::Sinks sinks_;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerPressure>::SharedPtr left_pub_, right_pub_;
  rclcpp::Publisher<nav_msgs::msg::Odometry>::SharedPtr odom_pub_;
  rclcpp::Subscription<tactile_msgs::msg::HoverSetpoint>::SharedPtr setpoint_sub_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace crazyflie_bridge

RCLCPP_COMPONENTS_REGISTER_NODE(crazyflie_bridge::CrazyflieBridgeComponent)
