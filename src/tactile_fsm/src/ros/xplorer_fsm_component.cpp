// rclcpp component of the XPLORER behaviours: a mechanical adapter around
// XplorerFsmLogic (all behaviour lives there). ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"

namespace tactile_fsm {

class XplorerFsmComponent : public rclcpp::Node {
 public:
  explicit XplorerFsmComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerFsmLogic::kNodeName, options),
    parameters_(*this, XplorerFsmLogic::default_parameters()),  // every key read-only
    logic_(XplorerFsmLogic::params_from(parameters_.values()))
  {
    setpoint_pub_ = tactile_common::data_publisher<geometry_msgs::msg::PoseStamped>(*this, XplorerFsmLogic::kSetpointTopic);
    state_pub_ = tactile_common::data_publisher<tactile_msgs::msg::FsmState>(*this, XplorerFsmLogic::kStateTopic);
    wrench_sub_ = create_subscription<geometry_msgs::msg::WrenchStamped>(
      XplorerFsmLogic::kWrenchTopic, rclcpp::SensorDataQoS(),
      [this](const geometry_msgs::msg::WrenchStamped & msg) {logic_.on_wrench(msg);});
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
      XplorerFsmLogic::kOdomTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(), std::chrono::nanoseconds(XplorerFsmLogic::kTimerPeriodNs), [this]() {
        auto out = logic_.on_timer(now().nanoseconds());
        if (out.setpoint) {setpoint_pub_->publish(*out.setpoint);}
        if (out.state) {state_pub_->publish(*out.state);}
      });
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerFsmLogic logic_;
  rclcpp::Publisher<geometry_msgs::msg::PoseStamped>::SharedPtr setpoint_pub_;
  rclcpp::Publisher<tactile_msgs::msg::FsmState>::SharedPtr state_pub_;
  rclcpp::Subscription<geometry_msgs::msg::WrenchStamped>::SharedPtr wrench_sub_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_sub_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace tactile_fsm

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_fsm::XplorerFsmComponent)
