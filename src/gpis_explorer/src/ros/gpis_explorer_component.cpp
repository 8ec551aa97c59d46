// rclcpp component of gpis_explorer: a mechanical adapter around
// GpisExplorerLogic (all behaviour lives there). ROS builds only.
#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"

namespace gpis_explorer {

class GpisExplorerComponent : public rclcpp::Node {
 public:
  explicit GpisExplorerComponent(const rclcpp::NodeOptions & options)
  : Node(GpisExplorerLogic::kNodeName, options),
    parameters_(*this, GpisExplorerLogic::default_parameters()),  // every key read-only
    logic_(GpisExplorerLogic::params_from(parameters_.values()))
  {
    GpisExplorerLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  GpisExplorerLogic logic_;
  /// Declared after logic_: its subscriptions and timer go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace gpis_explorer

RCLCPP_COMPONENTS_REGISTER_NODE(gpis_explorer::GpisExplorerComponent)
