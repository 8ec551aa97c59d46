// rclcpp component of the XPLORER contact mapper: a mechanical adapter around
// XplorerMapLogic (all behaviour lives there). ROS builds only.
#include <chrono>
#include <memory>

#include "mapping_pcl/xplorer_map_logic.hpp"
#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"

namespace mapping_pcl {

class XplorerMapComponent : public rclcpp::Node {
 public:
  explicit XplorerMapComponent(const rclcpp::NodeOptions & options)
  : Node(XplorerMapLogic::kNodeName, options),
    parameters_(*this, XplorerMapLogic::default_parameters()),  // every key read-only
    logic_(XplorerMapLogic::params_from(parameters_.values()))
  {
    cloud_pub_ = tactile_common::latched_publisher<sensor_msgs::msg::PointCloud2>(*this, XplorerMapLogic::kCloudTopic);
    wrench_sub_ = create_subscription<geometry_msgs::msg::WrenchStamped>(
      XplorerMapLogic::kWrenchBodyTopic, rclcpp::SensorDataQoS(),
      [this](const geometry_msgs::msg::WrenchStamped & msg) {logic_.on_wrench_body(msg);});
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
      XplorerMapLogic::kOdometryTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    state_sub_ = create_subscription<tactile_msgs::msg::FsmState>(
      XplorerMapLogic::kFsmStateTopic, 10,
      [this](const tactile_msgs::msg::FsmState & msg) {logic_.on_fsm_state(msg);});
    arm_sub_ = create_subscription<tactile_msgs::msg::ArmImuArray>(
      XplorerMapLogic::kArmImuTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::ArmImuArray & msg) {logic_.on_arm_imu(msg);});
    // On the node clock: simulated time under use_sim_time (the SITL launches, any
    // real_time_factor), system time otherwise.
    timer_ = rclcpp::create_timer(this, get_clock(), std::chrono::nanoseconds(logic_.period_ns()), [this]() {
        if (auto cloud = logic_.on_timer(now().nanoseconds())) {cloud_pub_->publish(*cloud);}
      });
  }

  ~XplorerMapComponent() override
  {
    if (!logic_.params().ply_file.empty()) {
      logic_.finalize();
      logic_.save_ply();
    }
  }

 private:
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  XplorerMapLogic logic_;
  rclcpp::Publisher<sensor_msgs::msg::PointCloud2>::SharedPtr cloud_pub_;
  rclcpp::Subscription<geometry_msgs::msg::WrenchStamped>::SharedPtr wrench_sub_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_sub_;
  rclcpp::Subscription<tactile_msgs::msg::FsmState>::SharedPtr state_sub_;
  rclcpp::Subscription<tactile_msgs::msg::ArmImuArray>::SharedPtr arm_sub_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace mapping_pcl

RCLCPP_COMPONENTS_REGISTER_NODE(mapping_pcl::XplorerMapComponent)
