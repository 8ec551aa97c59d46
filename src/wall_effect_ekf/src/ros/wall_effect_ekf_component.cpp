// rclcpp component of wall_effect_ekf: a mechanical adapter around
// WallEffectEkfLogic (all behaviour lives there). ROS builds only.
#include <chrono>
#include <memory>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"

namespace wall_effect_ekf {

class WallEffectEkfComponent : public rclcpp::Node {
 public:
  explicit WallEffectEkfComponent(const rclcpp::NodeOptions & options)
  : Node(WallEffectEkfLogic::kNodeName, options),
    parameters_(*this, WallEffectEkfLogic::default_parameters()),  // every key read-only
    logic_(WallEffectEkfLogic::params_from(parameters_.values()))
  {
    publisher_ = tactile_common::data_publisher<tactile_msgs::msg::WallEstimate>(*this, WallEffectEkfLogic::kOutputTopic);
    imu_ = create_subscription<sensor_msgs::msg::Imu>(
      WallEffectEkfLogic::kImuTopic, rclcpp::SensorDataQoS(),
      [this](const sensor_msgs::msg::Imu & msg) {logic_.on_imu(msg);});
    flow_ = create_subscription<tactile_msgs::msg::OpticalFlow>(
      WallEffectEkfLogic::kFlowTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::OpticalFlow & msg) {logic_.on_flow(msg);});
    range_ = create_subscription<sensor_msgs::msg::Range>(
      WallEffectEkfLogic::kRangeTopic, rclcpp::SensorDataQoS(),
      [this](const sensor_msgs::msg::Range & msg) {logic_.on_range(msg);});
    thrust_ = create_subscription<tactile_msgs::msg::ThrustCommand>(
      WallEffectEkfLogic::kThrustTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::ThrustCommand & msg) {logic_.on_thrust(msg);});
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
  WallEffectEkfLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::WallEstimate>::SharedPtr publisher_;
  rclcpp::Subscription<sensor_msgs::msg::Imu>::SharedPtr imu_;
  rclcpp::Subscription<tactile_msgs::msg::OpticalFlow>::SharedPtr flow_;
  rclcpp::Subscription<sensor_msgs::msg::Range>::SharedPtr range_;
  rclcpp::Subscription<tactile_msgs::msg::ThrustCommand>::SharedPtr thrust_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace wall_effect_ekf

RCLCPP_COMPONENTS_REGISTER_NODE(wall_effect_ekf::WallEffectEkfComponent)
