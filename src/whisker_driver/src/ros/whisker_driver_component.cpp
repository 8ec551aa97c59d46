// rclcpp component of the whisker driver: a mechanical adapter around
// WhiskerDriverLogic (parameters, wall timer at rate_hz, SensorDataQoS publisher).
#include <chrono>
#include <memory>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"

namespace whisker_driver {

class WhiskerDriverComponent : public rclcpp::Node {
 public:
  explicit WhiskerDriverComponent(const rclcpp::NodeOptions& options)
      : Node(WhiskerDriverLogic::kNodeName, options) {
    const auto params = WhiskerDriverLogic::params_from(
        tactile_common::declare_parameters(*this, WhiskerDriverLogic::default_parameters()));
    logic_ = std::make_unique<WhiskerDriverLogic>(params);
    pub_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(WhiskerDriverLogic::kOutputTopic,
                                                                rclcpp::SensorDataQoS());
    timer_ = create_wall_timer(std::chrono::nanoseconds(logic_->period_ns()), [this]() {
      for (auto& msg : logic_->on_timer(now().nanoseconds()).pressure) pub_->publish(msg);
    });
  }

 private:
  std::unique_ptr<WhiskerDriverLogic> logic_;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerPressure>::SharedPtr pub_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace whisker_driver

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_driver::WhiskerDriverComponent)
