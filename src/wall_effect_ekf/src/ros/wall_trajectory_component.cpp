// rclcpp component of 004's setpoint scripts (estimation flight, hold,
// sweep): a mechanical adapter around WallTrajectoryLogic. ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"

namespace wall_effect_ekf {

class WallTrajectoryComponent : public rclcpp::Node {
 public:
  explicit WallTrajectoryComponent(const rclcpp::NodeOptions & options)
  : Node(WallTrajectoryLogic::kNodeName, options),
    parameters_(*this, WallTrajectoryLogic::default_parameters()),  // every key read-only
    logic_(WallTrajectoryLogic::params_from(parameters_.values()))
  {
    WallTrajectoryLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WallTrajectoryLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::WallTrajectoryComponent)
