// rclcpp component of tactile_depth: a mechanical adapter around
// TactileDepthLogic (all behaviour lives there). ROS builds only.
#include <memory>
#include <utility>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"

namespace tactile_depth {

class TactileDepthComponent : public rclcpp::Node {
 public:
  explicit TactileDepthComponent(const rclcpp::NodeOptions & options)
  : Node(TactileDepthLogic::kNodeName, options),
    parameters_(*this, TactileDepthLogic::default_parameters(),
                [this](const tactile_common::ParamMap & values) {
                  logic_.set_params(TactileDepthLogic::params_from(values));
                }),
    logic_(TactileDepthLogic::params_from(parameters_.values()))
  {
    publisher_ = tactile_common::data_publisher<tactile_msgs::msg::TactileDepth>(*this, TactileDepthLogic::kOutputTopic);
    left_ = create_subscription<tactile_msgs::msg::WhiskerSignal>(
      TactileDepthLogic::kLeftSignalTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WhiskerSignal & msg) {
        if (auto out = logic_.on_left_signal(msg)) {
          publisher_->publish(
            std::make_unique<tactile_msgs::msg::TactileDepth>(std::move(*out)));
        }
      });
    right_ = create_subscription<tactile_msgs::msg::WhiskerSignal>(
      TactileDepthLogic::kRightSignalTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WhiskerSignal & msg) {
        if (auto out = logic_.on_right_signal(msg)) {
          publisher_->publish(
            std::make_unique<tactile_msgs::msg::TactileDepth>(std::move(*out)));
        }
      });
    odometry_ = create_subscription<nav_msgs::msg::Odometry>(
      TactileDepthLogic::kOdometryTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  TactileDepthLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::TactileDepth>::SharedPtr publisher_;
  rclcpp::Subscription<tactile_msgs::msg::WhiskerSignal>::SharedPtr left_;
  rclcpp::Subscription<tactile_msgs::msg::WhiskerSignal>::SharedPtr right_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odometry_;
};

}  // namespace tactile_depth

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_depth::TactileDepthComponent)
