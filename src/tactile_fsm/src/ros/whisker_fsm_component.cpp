// rclcpp component of the whisker wall-following FSM: a mechanical adapter
// around WhiskerFsmLogic (all behaviour lives there). ROS builds only.
//
// Event driven (tactile_common/event_tick.hpp, WhiskerFsmLogic::Stepping): the FSM steps
// when a TactileDepth arrives (the depth node publishes it on the pressure pair's
// arrival), so a pressure sample reaches the setpoint without waiting for a timer's
// phase; the 50 Hz watchdog timer, on the node clock (simulated time under use_sim_time),
// steps it when depth stops, so the stale-depth fail-safe (max_input_age_s) acts as it
// did with the timer-driven step.
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/event_tick.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"

namespace tactile_fsm {

class WhiskerFsmComponent : public rclcpp::Node {
 public:
  explicit WhiskerFsmComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerFsmLogic::kNodeName, options),
    parameters_(*this, WhiskerFsmLogic::default_parameters()),  // every key read-only
    logic_(WhiskerFsmLogic::params_from(parameters_.values())),
    tick_(WhiskerFsmLogic::kTimerPeriodNs)
  {
    WhiskerFsmLogic::Stepping stepping;
    stepping.tick = &tick_;  // always event driven
    WhiskerFsmLogic::wire(ports_, logic_, stepping);
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WhiskerFsmLogic logic_;
  tactile_common::EventTick tick_;
  /// Declared after logic_ and tick_: its subscriptions and timers go first, no callback outlives them.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::WhiskerFsmComponent)
