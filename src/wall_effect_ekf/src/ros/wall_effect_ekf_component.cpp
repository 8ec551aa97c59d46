// rclcpp component of wall_effect_ekf: a mechanical adapter around
// WallEffectEkfLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"

namespace wall_effect_ekf {

class WallEffectEkfComponent : public rclcpp::Node {
 public:
  explicit WallEffectEkfComponent(const rclcpp::NodeOptions & options)
  : Node(WallEffectEkfLogic::kNodeName, options),
    parameters_(*this, WallEffectEkfLogic::default_parameters()),  // every key read-only
    logic_(WallEffectEkfLogic::params_from(parameters_.values()))
  {
    WallEffectEkfLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WallEffectEkfLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::WallEffectEkfComponent)
