// rclcpp component of the INDI controller (004 eq. 26-36): a mechanical
// adapter around IndiControlLogic. ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "wall_effect_ekf/indi_control_logic.hpp"

namespace wall_effect_ekf {

class IndiControlComponent : public rclcpp::Node {
 public:
  explicit IndiControlComponent(const rclcpp::NodeOptions & options)
  : Node(IndiControlLogic::kNodeName, options),
    parameters_(*this, IndiControlLogic::default_parameters()),  // every key read-only
    logic_(IndiControlLogic::params_from(parameters_.values()))
  {
    publisher_ = tactile_common::data_publisher<tactile_msgs::msg::ThrustCommand>(*this, IndiControlLogic::kOutputTopic);
    setpoint_ = create_subscription<nav_msgs::msg::Odometry>(
      IndiControlLogic::kSetpointTopic, 10,
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_setpoint(msg);});
    odometry_ = create_subscription<nav_msgs::msg::Odometry>(
      IndiControlLogic::kOdometryTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    imu_ = create_subscription<sensor_msgs::msg::Imu>(
      IndiControlLogic::kImuTopic, rclcpp::SensorDataQoS(),
      [this](const sensor_msgs::msg::Imu & msg) {logic_.on_imu(msg);});
    wall_ = create_subscription<tactile_msgs::msg::WallEstimate>(
      IndiControlLogic::kWallTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::WallEstimate & msg) {logic_.on_wall(msg);});
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(),
      std::chrono::nanoseconds(logic_.period_ns()),
      [this]() {
        if (auto out = logic_.on_timer(now().nanoseconds())) {
          publisher_->publish(*out);
        }
      });
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  IndiControlLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::ThrustCommand>::SharedPtr publisher_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr setpoint_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odometry_;
  rclcpp::Subscription<sensor_msgs::msg::Imu>::SharedPtr imu_;
  rclcpp::Subscription<tactile_msgs::msg::WallEstimate>::SharedPtr wall_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::IndiControlComponent)
