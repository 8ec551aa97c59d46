// rclcpp component of the wall-effect behaviours (004 wall following and
// vector field): a mechanical adapter around WallEffectNavLogic. ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_fsm/wall_effect_nav_logic.hpp"

namespace tactile_fsm {

class WallEffectNavComponent : public rclcpp::Node {
 public:
  explicit WallEffectNavComponent(const rclcpp::NodeOptions & options)
  : Node(WallEffectNavLogic::kNodeName, options),
    parameters_(*this, WallEffectNavLogic::default_parameters()),  // every key read-only
    logic_(WallEffectNavLogic::params_from(parameters_.values()))
  {
    setpoint_ = tactile_common::data_publisher<nav_msgs::msg::Odometry>(*this, WallEffectNavLogic::kSetpointTopic);
    state_ = tactile_common::data_publisher<tactile_msgs::msg::FsmState>(*this, WallEffectNavLogic::kStateTopic);
    wall_ = create_subscription<tactile_msgs::msg::WallEstimate>(
      WallEffectNavLogic::kWallTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WallEstimate & msg) {logic_.on_wall(msg);});
    odom_ = create_subscription<nav_msgs::msg::Odometry>(
      WallEffectNavLogic::kOdomTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(WallEffectNavLogic::kTimerPeriodNs),
      [this]() {
        auto out = logic_.on_timer(now().nanoseconds());
        if (out.setpoint) {setpoint_->publish(*out.setpoint);}
        if (out.state) {state_->publish(*out.state);}
      });
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WallEffectNavLogic logic_;
  rclcpp::Publisher<nav_msgs::msg::Odometry>::SharedPtr setpoint_;
  rclcpp::Publisher<tactile_msgs::msg::FsmState>::SharedPtr state_;
  rclcpp::Subscription<tactile_msgs::msg::WallEstimate>::SharedPtr wall_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::WallEffectNavComponent)
