// rclcpp component of xplorer_force_est: a mechanical adapter around
// XplorerForceEstLogic (all behaviour lives there). ROS builds only.
#include <memory>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

namespace xplorer_force_est {

class XplorerForceEstComponent : public rclcpp::Node {
 public:
  explicit XplorerForceEstComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerForceEstLogic::kNodeName, options),
    parameters_(*this, XplorerForceEstLogic::default_parameters()),  // every key read-only
    logic_(XplorerForceEstLogic::params_from(parameters_.values()))
  {
    world_pub_ = tactile_common::data_publisher<geometry_msgs::msg::WrenchStamped>(*this, XplorerForceEstLogic::kWrenchWorldTopic);
    body_pub_ = tactile_common::data_publisher<geometry_msgs::msg::WrenchStamped>(*this, XplorerForceEstLogic::kWrenchBodyTopic);
    arm_sub_ = create_subscription<tactile_msgs::msg::ArmImuArray>(
      XplorerForceEstLogic::kArmImuTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::ArmImuArray & msg) {
        auto out = logic_.on_arm_imu(msg);
        if (out.world) {world_pub_->publish(*out.world);}
        if (out.body) {body_pub_->publish(*out.body);}
      });
    imu_sub_ = create_subscription<sensor_msgs::msg::Imu>(
      XplorerForceEstLogic::kImuTopic, rclcpp::SensorDataQoS(),
      [this](const sensor_msgs::msg::Imu & msg) {logic_.on_imu(msg);});
    thrust_sub_ = create_subscription<tactile_msgs::msg::ThrustCommand>(
      XplorerForceEstLogic::kThrustTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::ThrustCommand & msg) {logic_.on_thrust(msg);});
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerForceEstLogic logic_;
  rclcpp::Publisher<geometry_msgs::msg::WrenchStamped>::SharedPtr world_pub_;
  rclcpp::Publisher<geometry_msgs::msg::WrenchStamped>::SharedPtr body_pub_;
  rclcpp::Subscription<tactile_msgs::msg::ArmImuArray>::SharedPtr arm_sub_;
  rclcpp::Subscription<sensor_msgs::msg::Imu>::SharedPtr imu_sub_;
  rclcpp::Subscription<tactile_msgs::msg::ThrustCommand>::SharedPtr thrust_sub_;
};

}  // namespace xplorer_force_est

RCLCPP_COMPONENTS_REGISTER_NODE(xplorer_force_est::XplorerForceEstComponent)
