// rclcpp component of 004's setpoint scripts (estimation flight, hold,
// sweep): a mechanical adapter around WallTrajectoryLogic. ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"

namespace wall_effect_ekf {

class WallTrajectoryComponent : public rclcpp::Node {
 public:
  explicit WallTrajectoryComponent(const rclcpp::NodeOptions & options)
  : Node(WallTrajectoryLogic::kNodeName, options),
    logic_(WallTrajectoryLogic::params_from(
      tactile_common::declare_parameters(*this, WallTrajectoryLogic::default_parameters())))
  {
    publisher_ = create_publisher<nav_msgs::msg::Odometry>(WallTrajectoryLogic::kOutputTopic, 10);
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(WallTrajectoryLogic::kPeriodNs),
      [this]() {publisher_->publish(logic_.on_timer(now().nanoseconds()));});
  }

 private:
  WallTrajectoryLogic logic_;
  rclcpp::Publisher<nav_msgs::msg::Odometry>::SharedPtr publisher_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::WallTrajectoryComponent)
