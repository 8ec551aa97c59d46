// rclcpp component of whisker_localization: a mechanical adapter around
// WhiskerLocalizationLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"

namespace whisker_localization {

class WhiskerLocalizationComponent : public rclcpp::Node {
 public:
  explicit WhiskerLocalizationComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerLocalizationLogic::kNodeName, options),
    parameters_(*this, WhiskerLocalizationLogic::default_parameters()),  // every key read-only
    logic_(WhiskerLocalizationLogic::params_from(parameters_.values()))
  {
    WhiskerLocalizationLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WhiskerLocalizationLogic logic_;
  /// Declared after logic_: its subscriptions and timers go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace whisker_localization

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_localization::WhiskerLocalizationComponent)
