// rclcpp component of the XPLORER contact mapper: a mechanical adapter around
// XplorerMapLogic (all behaviour lives there). ROS builds only.
#include "mapping_pcl/xplorer_map_logic.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"

namespace mapping_pcl {

class XplorerMapComponent : public rclcpp::Node {
 public:
  explicit XplorerMapComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerMapLogic::kNodeName, options),
    parameters_(*this, XplorerMapLogic::default_parameters()),  // every key read-only
    logic_(XplorerMapLogic::params_from(parameters_.values()))
  {
    XplorerMapLogic::wire(ports_, logic_);
  }

  ~XplorerMapComponent() override
  {
    if (!logic_.params().ply_file.empty()) {
      logic_.finalize();
      logic_.save_ply();
    }
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerMapLogic logic_;
  /// Declared after logic_: its subscriptions and timer go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace mapping_pcl

RCLCPP_COMPONENTS_REGISTER_NODE(mapping_pcl::XplorerMapComponent)
