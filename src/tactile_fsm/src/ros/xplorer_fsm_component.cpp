// rclcpp component of the XPLORER behaviours: a mechanical adapter around
// XplorerFsmLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"

namespace tactile_fsm {

class XplorerFsmComponent : public rclcpp::Node {
 public:
  explicit XplorerFsmComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerFsmLogic::kNodeName, options),
    parameters_(*this, XplorerFsmLogic::default_parameters()),  // every key read-only
    logic_(XplorerFsmLogic::params_from(parameters_.values()))
  {
    XplorerFsmLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerFsmLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::XplorerFsmComponent)
