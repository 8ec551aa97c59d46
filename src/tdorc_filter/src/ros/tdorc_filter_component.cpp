// rclcpp component of tdorc_filter: a mechanical adapter around
// TdorcFilterLogic (all behaviour lives there). ROS builds only.
#include <memory>
#include <utility>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"

// Publishers take unique_ptr: with use_intra_process_comms the message then moves
// to the subscriptions in the same container (publish(const T&) copies it first).
namespace tdorc_filter {

class TdorcFilterComponent : public rclcpp::Node {
 public:
  explicit TdorcFilterComponent(const rclcpp::NodeOptions & options)
  : Node(TdorcFilterLogic::kNodeName, options),
    parameters_(*this, TdorcFilterLogic::default_parameters(),
                [this](const tactile_common::ParamMap & values) {
                  logic_.set_params(TdorcFilterLogic::params_from(values));
                }),
    logic_(TdorcFilterLogic::params_from(parameters_.values()))
  {
    publisher_ = tactile_common::data_publisher<tactile_msgs::msg::WhiskerSignal>(*this, TdorcFilterLogic::kOutputTopic);
    subscription_ = create_subscription<tactile_msgs::msg::WhiskerPressure>(
      TdorcFilterLogic::kInputTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WhiskerPressure & msg) {
        // Receive time: this node's clock (sim time under ros2 bag play --clock).
        if (auto out = logic_.on_pressure(msg, now().nanoseconds())) {
          publisher_->publish(
            std::make_unique<tactile_msgs::msg::WhiskerSignal>(std::move(*out)));
        }
      });
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  TdorcFilterLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerSignal>::SharedPtr publisher_;
  rclcpp::Subscription<tactile_msgs::msg::WhiskerPressure>::SharedPtr subscription_;
};

}  // namespace tdorc_filter

RCLCPP_COMPONENTS_REGISTER_NODE(tdorc_filter::TdorcFilterComponent)
