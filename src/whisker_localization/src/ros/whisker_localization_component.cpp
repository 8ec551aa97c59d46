// rclcpp component of whisker_localization: a mechanical adapter around
// WhiskerLocalizationLogic (all behaviour lives there). ROS builds only.
#include <memory>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"

namespace whisker_localization {

class WhiskerLocalizationComponent : public rclcpp::Node {
 public:
  explicit WhiskerLocalizationComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerLocalizationLogic::kNodeName, options),
    parameters_(*this, WhiskerLocalizationLogic::default_parameters()),  // every key read-only
    logic_(WhiskerLocalizationLogic::params_from(parameters_.values()))
  {
    result_pub_ = tactile_common::data_publisher<tactile_msgs::msg::LocalizationResult>(*this, WhiskerLocalizationLogic::kResultTopic);
    pose_set_pub_ = tactile_common::data_publisher<geometry_msgs::msg::PoseArray>(*this, WhiskerLocalizationLogic::kPoseSetTopic);
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
  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  WhiskerLocalizationLogic logic_;
  rclcpp::Publisher<tactile_msgs::msg::LocalizationResult>::SharedPtr result_pub_;
  rclcpp::Publisher<geometry_msgs::msg::PoseArray>::SharedPtr pose_set_pub_;
  rclcpp::Subscription<nav_msgs::msg::Odometry>::SharedPtr odom_sub_;
  rclcpp::Subscription<geometry_msgs::msg::WrenchStamped>::SharedPtr moment_sub_;
};

}  // namespace whisker_localization

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_localization::WhiskerLocalizationComponent)
