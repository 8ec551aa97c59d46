// rclcpp component of tdorc_filter: a mechanical adapter around
// TdorcFilterLogic (all behaviour lives there). ROS builds only.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"

namespace tdorc_filter {

class TdorcFilterComponent : public rclcpp::Node {
 public:
  explicit TdorcFilterComponent(const rclcpp::NodeOptions & options)
  : Node(TdorcFilterLogic::kNodeName, options),
    parameters_(*this, TdorcFilterLogic::default_parameters(),
                [this](const tactile_common::ParamMap & values) {
                  logic_.set_params(TdorcFilterLogic::params_from(values));
                }),
    logic_(TdorcFilterLogic::params_from(parameters_.values()))
  {
    TdorcFilterLogic::wire(ports_, logic_);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  TdorcFilterLogic logic_;
  /// Declared after logic_: its subscriptions go first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tdorc_filter

RCLCPP_COMPONENTS_REGISTER_NODE(tdorc_filter::TdorcFilterComponent)
