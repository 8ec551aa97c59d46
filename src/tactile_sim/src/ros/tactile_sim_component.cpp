// rclcpp component of the simulator: a mechanical adapter around SimLogic
// (all behaviour lives there). ROS builds only. The world runs on simulated
// time from 0, stepped by a wall timer at the physics rate and published on
// /clock, so the other nodes run with use_sim_time:=true.
#include <chrono>
#include <map>
#include <memory>
#include <string>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/logic/sim_logic.hpp"

namespace tactile_sim {

class TactileSimComponent : public rclcpp::Node {
 public:
  explicit TactileSimComponent(const rclcpp::NodeOptions & options)
  : Node(SimLogic::kNodeName, options),
    logic_(SimLogic::from_parameters(
      tactile_common::declare_parameters(*this, SimLogic::default_parameters())))
  {
    clock_publisher_ = create_publisher<rosgraph_msgs::msg::Clock>("/clock", rclcpp::ClockQoS());
    hover_subscription_ = create_subscription<tactile_msgs::msg::HoverSetpoint>(
      SimLogic::kHoverSetpointTopic, 10,
      [this](const tactile_msgs::msg::HoverSetpoint & msg) {logic_->on_hover_setpoint(msg);});
    position_subscription_ = create_subscription<geometry_msgs::msg::PoseStamped>(
      SimLogic::kPositionSetpointTopic, 10,
      [this](const geometry_msgs::msg::PoseStamped & msg) {logic_->on_position_setpoint(msg);});
    thrust_subscription_ = create_subscription<tactile_msgs::msg::ThrustCommand>(
      SimLogic::kRotorThrustTopic, 10,
      [this](const tactile_msgs::msg::ThrustCommand & msg) {logic_->on_rotor_thrust(msg);});
    timer_ = create_wall_timer(
      std::chrono::nanoseconds(logic_->period_ns()), [this]() {tick();});
  }

 private:
  template<class T>
  void publish(const std::vector<Published<T>> & messages)
  {
    auto & publishers = std::get<Publishers<T>>(publishers_);
    for (const auto & m : messages) {
      auto it = publishers.find(m.topic);
      if (it == publishers.end()) {
        it = publishers.emplace(m.topic, create_publisher<T>(m.topic, rclcpp::SensorDataQoS())).first;
      }
      it->second->publish(m.msg);
    }
  }

  void tick()
  {
    if (logic_->finished(now_ns_)) {
      return;
    }
    outputs_.clear();
    logic_->step(now_ns_, outputs_);
    rosgraph_msgs::msg::Clock clock;
    tactile_common::to_stamp(now_ns_, clock.clock);
    clock_publisher_->publish(clock);
    publish(outputs_.pressure);
    publish(outputs_.whisker_truth);
    publish(outputs_.odometry);
    publish(outputs_.imu);
    publish(outputs_.range);
    publish(outputs_.flow);
    publish(outputs_.arm_imu);
    publish(outputs_.thrust);
    publish(outputs_.wrench);
    publish(outputs_.wall);
    publish(outputs_.collisions);
    now_ns_ += logic_->period_ns();
  }

  template<class T>
  using Publishers = std::map<std::string, typename rclcpp::Publisher<T>::SharedPtr>;

  std::unique_ptr<SimLogic> logic_;
  SimLogic::Outputs outputs_;
  int64_t now_ns_ = 0;
  std::tuple<
    Publishers<tactile_msgs::msg::WhiskerPressure>, Publishers<tactile_msgs::msg::WhiskerGroundTruth>,
    Publishers<nav_msgs::msg::Odometry>, Publishers<sensor_msgs::msg::Imu>,
    Publishers<sensor_msgs::msg::Range>, Publishers<tactile_msgs::msg::OpticalFlow>,
    Publishers<tactile_msgs::msg::ArmImuArray>, Publishers<tactile_msgs::msg::ThrustCommand>,
    Publishers<geometry_msgs::msg::WrenchStamped>, Publishers<tactile_msgs::msg::WallEstimate>,
    Publishers<tactile_msgs::msg::CollisionEvent>> publishers_;
  rclcpp::Publisher<rosgraph_msgs::msg::Clock>::SharedPtr clock_publisher_;
  rclcpp::Subscription<tactile_msgs::msg::HoverSetpoint>::SharedPtr hover_subscription_;
  rclcpp::Subscription<geometry_msgs::msg::PoseStamped>::SharedPtr position_subscription_;
  rclcpp::Subscription<tactile_msgs::msg::ThrustCommand>::SharedPtr thrust_subscription_;
  rclcpp::TimerBase::SharedPtr timer_;
};

}  // namespace tactile_sim

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_sim::TactileSimComponent)
