// rclcpp component of gpis_explorer: a mechanical adapter around
// GpisExplorerLogic (all behaviour lives there). ROS builds only.
#include <chrono>
#include <memory>

#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"

namespace gpis_explorer {

class GpisExplorerComponent : public rclcpp::Node {
 public:
  explicit GpisExplorerComponent(const rclcpp::NodeOptions & options)
  : Node(GpisExplorerLogic::kNodeName, options),
    parameters_(*this, GpisExplorerLogic::default_parameters()),  // every key read-only
    logic_(GpisExplorerLogic::params_from(parameters_.values()))
  {
    setpoint_ = tactile_common::data_publisher<tactile_msgs::msg::HoverSetpoint>(*this, GpisExplorerLogic::kSetpointTopic);
    state_ = tactile_common::data_publisher<tactile_msgs::msg::FsmState>(*this, GpisExplorerLogic::kStateTopic);
    // Latched: a late subscriber (rviz, a recorder) gets the last map and target; never
    // intra-process (tactile_common/ros_qos.hpp: Humble refuses the combination).
    map_ = tactile_common::latched_publisher<tactile_msgs::msg::GpisMap>(*this, GpisExplorerLogic::kMapTopic);
    target_ = tactile_common::latched_publisher<tactile_msgs::msg::ExplorationTarget>(
      *this, GpisExplorerLogic::kTargetTopic);
    depth_ = create_subscription<tactile_msgs::msg::TactileDepth>(
      GpisExplorerLogic::kDepthTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::TactileDepth & msg) {logic_.on_depth(msg);});
    odometry_ = create_subscription<nav_msgs::msg::Odometry>(
      GpisExplorerLogic::kOdomTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(GpisExplorerLogic::kTimerPeriodNs), [this]() {
        auto out = logic_.on_timer(now().nanoseconds());
        setpoint_->publish(out.setpoint);
        if (out.state) {state_->publish(*out.state);}
        if (out.map) {map_->publish(*out.map);}
        if (out.target) {target_->publish(*out.target);}
      });
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  GpisExplorerLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::HoverSetpoint>::SharedPtr setpoint_;
  rclcpp::Publisher<tactile_msgs::msg::FsmState>::SharedPtr state_;
  rclcpp::Publisher<tactile_msgs::msg::GpisMap>::SharedPtr map_;
  rclcpp::Publisher<tactile_msgs::msg::ExplorationTarget>::SharedPtr target_;
  rclcpp::Subscription<tactile_msgs::msg::TactileDepth>::SharedPtr depth_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odometry_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace gpis_explorer

RCLCPP_COMPONENTS_REGISTER_NODE(gpis_explorer::GpisExplorerComponent)
