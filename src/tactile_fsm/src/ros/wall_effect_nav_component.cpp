// rclcpp component of the wall-effect behaviours (004 wall following and
// vector field): a mechanical adapter around WallEffectNavLogic. ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tactile_fsm/wall_effect_nav_logic.hpp"

namespace tactile_fsm {

class WallEffectNavComponent : public rclcpp::Node {
 public:
  explicit WallEffectNavComponent(const rclcpp::NodeOptions & options)
  : Node(WallEffectNavLogic::kNodeName, options),
    parameters_(*this, WallEffectNavLogic::default_parameters()),  // every key read-only
    logic_(WallEffectNavLogic::params_from(parameters_.values()))
  {
    WallEffectNavLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WallEffectNavLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::WallEffectNavComponent)
