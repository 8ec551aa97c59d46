// rclcpp component of whisker_driver: a mechanical adapter around
// WhiskerDriverLogic (all behaviour lives there). ROS builds only.
#include <chrono>
#include <memory>
#include <utility>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"

namespace whisker_driver {

class WhiskerDriverComponent : public rclcpp::Node {
 public:
  explicit WhiskerDriverComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerDriverLogic::kNodeName, options),
    logic_(WhiskerDriverLogic::params_from(
      tactile_common::declare_parameters(*this, WhiskerDriverLogic::default_parameters())))
  {
    publisher_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      WhiskerDriverLogic::kOutputTopic, rclcpp::SensorDataQoS());
    timer_ = create_wall_timer(
      std::chrono::nanoseconds(logic_.period_ns()),
      [this]() {
        for (auto & msg : logic_.on_timer(now().nanoseconds()).pressure) {
          publisher_->publish(
            std::make_unique<tactile_msgs::msg::WhiskerPressure>(std::move(msg)));
        }
      });
  }

 private:
  WhiskerDriverLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerPressure>::SharedPtr publisher_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace whisker_driver

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_driver::WhiskerDriverComponent)
