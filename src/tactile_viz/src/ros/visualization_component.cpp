// rclcpp component of the visualization node: a mechanical adapter around
// VisualizationLogic (all behaviour lives there). ROS builds with visualization_msgs only.
#include <memory>
#include <string>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_viz/visualization_logic.hpp"

namespace tactile_viz {

class VisualizationComponent : public rclcpp::Node {
 public:
  explicit VisualizationComponent(const rclcpp::NodeOptions & options)
  : Node(VisualizationLogic::kNodeName, options),
    parameters_(*this, VisualizationLogic::default_parameters()),  // every key read-only
    logic_(VisualizationLogic::params_from(parameters_.values()))
  {
    using L = VisualizationLogic;
    // Reliable, volatile, depth 10 (REP 2003 data publisher): a DELETE must not be lost.
    markers_ = tactile_common::data_publisher<visualization_msgs::msg::MarkerArray>(*this, L::kMarkersTopic);
    mean_grid_ = tactile_common::latched_publisher<nav_msgs::msg::OccupancyGrid>(*this, L::kMeanGridTopic);
    variance_grid_ = tactile_common::latched_publisher<nav_msgs::msg::OccupancyGrid>(*this, L::kVarianceGridTopic);
    // Inputs: the estimate streams best effort (matches reliable and best-effort publishers,
    // never slows one down), the collision events reliable as the simulator publishes them,
    // the GPIS map and target latched (a late start still draws the current map).
    depth_ = create_subscription<tactile_msgs::msg::TactileDepth>(
      L::kDepthTopic, rclcpp::SensorDataQoS(), [this](const tactile_msgs::msg::TactileDepth & m) {publish(logic_.on_tactile_depth(m));});
    wall_ = create_subscription<tactile_msgs::msg::WallEstimate>(
      L::kWallTopic, rclcpp::SensorDataQoS(), [this](const tactile_msgs::msg::WallEstimate & m) {publish(logic_.on_wall_estimate(m));});
    collisions_ = create_subscription<tactile_msgs::msg::CollisionEvent>(
      L::kCollisionTopic, 10, [this](const tactile_msgs::msg::CollisionEvent & m) {publish(logic_.on_collision(m));});
    localization_ = create_subscription<tactile_msgs::msg::LocalizationResult>(
      L::kLocalizationTopic, rclcpp::SensorDataQoS(),
      [this](const tactile_msgs::msg::LocalizationResult & m) {publish(logic_.on_localization(m));});
    // latched_subscription: transient local, never intra-process (Humble refuses the
    // combination in an intra-process container; tactile_common/ros_qos.hpp).
    gpis_map_ = tactile_common::latched_subscription<tactile_msgs::msg::GpisMap>(
      *this, L::kGpisMapTopic, [this](const tactile_msgs::msg::GpisMap & m) {on_gpis_map(m);});
    gpis_target_ = tactile_common::latched_subscription<tactile_msgs::msg::ExplorationTarget>(
      *this, L::kGpisTargetTopic,
      [this](const tactile_msgs::msg::ExplorationTarget & m) {publish(logic_.on_exploration_target(m));});
  }

 private:
  void publish(const visualization_msgs::msg::MarkerArray & markers)
  {
    if (!markers.markers.empty()) {markers_->publish(markers);}
  }

  void on_gpis_map(const tactile_msgs::msg::GpisMap & msg)
  {
    try {
      publish(logic_.on_gpis_map(msg));
      mean_grid_->publish(logic_.mean_grid(msg));
      variance_grid_->publish(logic_.variance_grid(msg));
    } catch (const InputError & e) {
      // A malformed map from another node: said, not drawn; the node goes on.
      RCLCPP_ERROR_THROTTLE(get_logger(), *get_clock(), 5000, "%s (map not drawn)", e.what());
    }
  }

  /// Declared before logic_: its values configure it; its on-set callback refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  VisualizationLogic logic_;
  rclcpp::Publisher<visualization_msgs::msg::MarkerArray>::SharedPtr markers_;
  rclcpp::Publisher<nav_msgs::msg::OccupancyGrid>::SharedPtr mean_grid_;
  rclcpp::Publisher<nav_msgs::msg::OccupancyGrid>::SharedPtr variance_grid_;
  rclcpp::Subscription<tactile_msgs::msg::TactileDepth>::SharedPtr depth_;
  rclcpp::Subscription<tactile_msgs::msg::WallEstimate>::SharedPtr wall_;
  rclcpp::Subscription<tactile_msgs::msg::CollisionEvent>::SharedPtr collisions_;
  rclcpp::Subscription<tactile_msgs::msg::LocalizationResult>::SharedPtr localization_;
  rclcpp::Subscription<tactile_msgs::msg::GpisMap>::SharedPtr gpis_map_;
  rclcpp::Subscription<tactile_msgs::msg::ExplorationTarget>::SharedPtr gpis_target_;
};

}  // namespace tactile_viz

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_viz::VisualizationComponent)
