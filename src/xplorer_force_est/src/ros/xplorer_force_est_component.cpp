// rclcpp component of xplorer_force_est: a mechanical adapter around
// XplorerForceEstLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

namespace xplorer_force_est {

class XplorerForceEstComponent : public rclcpp::Node {
 public:
  explicit XplorerForceEstComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerForceEstLogic::kNodeName, options),
    parameters_(*this, XplorerForceEstLogic::default_parameters()),  // every key read-only
    logic_(XplorerForceEstLogic::params_from(parameters_.values()))
  {
    XplorerForceEstLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerForceEstLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace xplorer_force_est

RCLCPP_COMPONENTS_REGISTER_NODE(xplorer_force_est::XplorerForceEstComponent)
