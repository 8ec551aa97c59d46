// rclcpp component of whisker_localization: a mechanical adapter around
// WhiskerLocalizationLogic (all behaviour lives there). ROS builds only.
#include <memory>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"

namespace whisker_localization {

class WhiskerLocalizationComponent : public rclcpp::Node {
 public:
  explicit WhiskerLocalizationComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerLocalizationLogic::kNodeName, options),
    logic_(WhiskerLocalizationLogic::params_from(
      tactile_common::declare_parameters(*this, WhiskerLocalizationLogic::default_parameters())))
  {
    result_pub_ = create_publisher<tactile_msgs::msg::LocalizationResult>(
      WhiskerLocalizationLogic::kResultTopic, rclcpp::QoS(10));
    pose_set_pub_ = create_publisher<geometry_msgs::msg::PoseArray>(
      WhiskerLocalizationLogic::kPoseSetTopic, rclcpp::QoS(10));
    odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
      WhiskerLocalizationLogic::kOdomTopic, rclcpp::SensorDataQoS(),
      [this](const nav_msgs::msg::Odometry & msg) {logic_.on_odometry(msg);});
    moment_sub_ = create_subscription<geometry_msgs::msg::WrenchStamped>(
      WhiskerLocalizationLogic::kMomentTopic, rclcpp::SensorDataQoS(),
      [this](const geometry_msgs::msg::WrenchStamped & msg) {
        auto out = logic_.on_moment(msg);
        if (out.result) {
          result_pub_->publish(*out.result);
        }
        if (out.pose_set) {
          pose_set_pub_->publish(*out.pose_set);
        }
      });
  }

 private:
  WhiskerLocalizationLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::LocalizationResult>::SharedPtr result_pub_;
  rclcpp::Publisher<geometry_msgs::msg::PoseArray>::SharedPtr pose_set_pub_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_sub_;
  rclcpp::Subscription<geometry_msgs::msg::WrenchStamped>::SharedPtr moment_sub_;
};

}  // namespace whisker_localization

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_localization::WhiskerLocalizationComponent)
