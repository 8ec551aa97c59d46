// rclcpp component of tactile_depth: a mechanical adapter around
// TactileDepthLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
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
    TactileDepthLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  TactileDepthLogic logic_;
  /// Declared after logic_: its subscriptions go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tactile_depth

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_depth::TactileDepthComponent)
