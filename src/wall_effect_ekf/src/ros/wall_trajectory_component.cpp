// rclcpp component of 004's setpoint scripts (estimation flight, hold,
// sweep): a mechanical adapter around WallTrajectoryLogic. ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"

namespace wall_effect_ekf {

class WallTrajectoryComponent : public rclcpp::Node {
 public:
  explicit WallTrajectoryComponent(const rclcpp::NodeOptions & options)
  : Node(WallTrajectoryLogic::kNodeName, options),
    parameters_(*this, WallTrajectoryLogic::default_parameters()),  // every key read-only
    logic_(WallTrajectoryLogic::params_from(parameters_.values()))
  {
    publisher_ = tactile_common::data_publisher<nav_msgs::msg::Odometry>(*this, WallTrajectoryLogic::kOutputTopic);
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(WallTrajectoryLogic::kPeriodNs),
      [this]() {publisher_->publish(logic_.on_timer(now().nanoseconds()));});
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WallTrajectoryLogic logic_;
  rclcpp::Publisher<nav_msgs::msg::Odometry>::SharedPtr publisher_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::WallTrajectoryComponent)
