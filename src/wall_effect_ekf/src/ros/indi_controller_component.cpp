// rclcpp component of the INDI controller (004 eq. 26-36): a mechanical
// adapter around IndiControlLogic. ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "wall_effect_ekf/indi_control_logic.hpp"

namespace wall_effect_ekf {

class IndiControlComponent : public rclcpp::Node {
 public:
  explicit IndiControlComponent(const rclcpp::NodeOptions & options)
  : Node(IndiControlLogic::kNodeName, options),
    parameters_(*this, IndiControlLogic::default_parameters()),  // every key read-only
    logic_(IndiControlLogic::params_from(parameters_.values()))
  {
    IndiControlLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  IndiControlLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::IndiControlComponent)
