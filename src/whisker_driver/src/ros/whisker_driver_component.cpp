// rclcpp component of whisker_driver: a mechanical adapter around
// WhiskerDriverLogic (all behaviour lives there) and, where the ROS 2 installation has
// diagnostic_updater, the bench rig's /diagnostics from DriverHealth (stall, frame
// errors, device gone). ROS builds only.
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "whisker_driver/driver_health.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
#include "diagnostic_updater/diagnostic_updater.hpp"
#endif

namespace whisker_driver {

class WhiskerDriverComponent : public rclcpp::Node {
 public:
  explicit WhiskerDriverComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerDriverLogic::kNodeName, options),
    logic_(WhiskerDriverLogic::params_from(
      tactile_common::declare_parameters(*this, WhiskerDriverLogic::default_parameters()))),
    health_(DriverHealth::params_from(
      tactile_common::declare_parameters(*this, DriverHealth::default_parameters())))
  {
    publisher_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      WhiskerDriverLogic::kOutputTopic, rclcpp::SensorDataQoS());
    last_sample_ns_ = now().nanoseconds();  // a device that never sends stalls from the start
    timer_ = create_wall_timer(
      std::chrono::nanoseconds(logic_.period_ns()),
      [this]() {
        const int64_t t = now().nanoseconds();
        auto out = logic_.on_timer(t);
        if (!out.pressure.empty()) {last_sample_ns_ = t;}
        for (auto & msg : out.pressure) {
          publisher_->publish(
            std::make_unique<tactile_msgs::msg::WhiskerPressure>(std::move(msg)));
        }
      });
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
    const auto & p = logic_.params();
    updater_ = std::make_unique<diagnostic_updater::Updater>(this, health_.params().diagnostics_period_s);
    updater_->setHardwareID(p.source == "serial" ? p.device : p.source);
    // Both whiskers' drivers are named whisker_driver: the task names the namespace.
    updater_->add(
      std::string("whisker deck ") + get_namespace(),
      [this](diagnostic_updater::DiagnosticStatusWrapper & stat) {
        const double age = 1e-9 * static_cast<double>(now().nanoseconds() - last_sample_ns_);
        const auto c = health_.update(logic_.stats(), age);
        stat.summary(static_cast<unsigned char>(c.level), c.message);
        for (const auto & [key, value] : c.values) {stat.add(key, value);}
      });
#endif
  }

 private:
  WhiskerDriverLogic logic_;
  DriverHealth health_;
  int64_t last_sample_ns_ = 0;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerPressure>::SharedPtr publisher_;
  rclcpp::TimerBase::SharedPtr timer_;
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
  std::unique_ptr<diagnostic_updater::Updater> updater_;
#endif
};

}  // namespace whisker_driver

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_driver::WhiskerDriverComponent)
