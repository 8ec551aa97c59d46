// rclcpp component of whisker_driver: a mechanical adapter around
// WhiskerDriverLogic (all behaviour lives there) and, where the ROS 2 installation has
// diagnostic_updater, the bench rig's /diagnostics from DriverHealth (stall, frame
// errors, device gone). ROS builds only.
//
// Two hosts of one ROS face (DriverRosFace, templated on the node type):
// - where the ROS 2 installation has rclcpp_lifecycle (WHISKER_DRIVER_LIFECYCLE), a managed
//   node: configure opens the source (the serial device, the bag), activate starts reading
//   frames and publishing (timer, lifecycle publisher), deactivate stops, cleanup closes
//   the device;
// - elsewhere a plain rclcpp::Node that opens and streams from its constructor (a device
//   that cannot be opened throws: the container's load fails).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "whisker_driver/driver_health.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
#include "diagnostic_updater/diagnostic_updater.hpp"
#endif
#ifdef WHISKER_DRIVER_LIFECYCLE
#include "lifecycle_msgs/msg/state.hpp"
#include "rclcpp_lifecycle/lifecycle_node.hpp"
#endif

namespace whisker_driver {

/// The driver's ROS face. NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode (whose
/// publisher is activated by the node's own on_activate / on_deactivate).
template <class NodeT>
class DriverRosFace {
public:
  /// Parameters (a bad value throws: the container's load fails, naming file and key)
  /// and diagnostics. No device yet: open().
  explicit DriverRosFace(NodeT & node)
  : node_(node),
    parameters_(node, {WhiskerDriverLogic::default_parameters(), DriverHealth::default_parameters()}),
    params_(WhiskerDriverLogic::params_from(parameters_.values())),  // every key read-only
    health_(DriverHealth::params_from(parameters_.values()))
  {
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
    updater_ = std::make_unique<diagnostic_updater::Updater>(&node_, health_.params().diagnostics_period_s);
    updater_->setHardwareID(device_name());
    // Both whiskers' drivers are named whisker_driver: the task names the namespace.
    updater_->add(
      std::string("whisker deck ") + node_.get_namespace(),
      [this](diagnostic_updater::DiagnosticStatusWrapper & stat) {
        if (!active_) {
          stat.summary(diagnostic_msgs::msg::DiagnosticStatus::STALE,
                       std::string("not streaming: the driver is ") + (logic_ ? "inactive" : "unconfigured"));
          return;
        }
        // Since the last sample, or since start() (a device that never sends stalls from the start).
        const int64_t last = std::max(started_ns_, logic_->last_output_ns().value_or(started_ns_));
        const double age = 1e-9 * static_cast<double>(node_.now().nanoseconds() - last);
        const auto c = health_.update(logic_->stats(), age);
        stat.summary(static_cast<unsigned char>(c.level), c.message);
        for (const auto & [key, value] : c.values) {stat.add(key, value);}
      });
#endif
  }

  DriverRosFace(const DriverRosFace &) = delete;
  DriverRosFace & operator=(const DriverRosFace &) = delete;

  /// The serial device, else the source's name.
  std::string device_name() const {return params_.source == "serial" ? params_.device : params_.source;}

  /// Opens the source (serial device, bag) and creates the node's ports
  /// (WhiskerDriverLogic::wire(): the publisher, a lifecycle one activated with the node,
  /// and the timer, stopped until start()). Throws SerialError / std::runtime_error naming
  /// the device or path and the reason.
  void open()
  {
    logic_ = std::make_unique<WhiskerDriverLogic>(params_);
    ports_ = std::make_unique<tactile_common::RosPorts<NodeT>>(node_);
    WhiskerDriverLogic::wire(*ports_, *logic_);
    ports_->cancel_timers();
    RCLCPP_INFO(node_.get_logger(), "opened %s (source %s)", device_name().c_str(), params_.source.c_str());
  }

  /// Reads frames and publishes at rate_hz.
  void start()
  {
    if (!logic_) {throw std::runtime_error("no device open: configure first");}
    started_ns_ = node_.now().nanoseconds();
    ports_->start_timers();
    active_ = true;
  }

  /// Stops reading (bytes the device sends meanwhile wait in the tty's buffer, up to its size).
  void stop()
  {
    active_ = false;
    if (ports_) {ports_->cancel_timers();}
  }

  /// Closes the device.
  void close()
  {
    stop();
    if (logic_) {
      ports_.reset();  // its timer calls the logic: gone first
      logic_.reset();
      RCLCPP_INFO(node_.get_logger(), "closed %s", device_name().c_str());
    }
  }

private:
  NodeT & node_;
  /// Declared first: its values configure the driver; `ros2 param set` is refused (read-only).
  tactile_common::NodeParameters parameters_;
  WhiskerDriverLogic::Params params_;
  DriverHealth health_;
  std::unique_ptr<WhiskerDriverLogic> logic_;  ///< the open source (configured)
  std::atomic<bool> active_{false};
  int64_t started_ns_ = 0;
  /// The logic's publisher and timer (open() to close()); declared after logic_.
  std::unique_ptr<tactile_common::RosPorts<NodeT>> ports_;
#ifdef WHISKER_DRIVER_HAVE_DIAGNOSTIC_UPDATER
  std::unique_ptr<diagnostic_updater::Updater> updater_;
#endif
};

#ifdef WHISKER_DRIVER_LIFECYCLE

/// The managed driver (whisker_driver README "Lifecycle").
class WhiskerDriverComponent : public rclcpp_lifecycle::LifecycleNode {
public:
  using CallbackReturn = rclcpp_lifecycle::node_interfaces::LifecycleNodeInterface::CallbackReturn;
  using State = rclcpp_lifecycle::State;

  explicit WhiskerDriverComponent(const rclcpp::NodeOptions & options)
  : LifecycleNode(WhiskerDriverLogic::kNodeName, options), face_(*this) {}

  ~WhiskerDriverComponent() override
  {
    if (rclcpp::ok(get_node_base_interface()->get_context()) &&
      get_current_state().id() != lifecycle_msgs::msg::State::PRIMARY_STATE_FINALIZED)
    {
      shutdown();
    }
    face_.close();
  }

  CallbackReturn on_configure(const State &) override
  {
    try {
      face_.open();
    } catch (const std::exception & e) {
      RCLCPP_ERROR(get_logger(), "configure failed: cannot open %s: %s; the driver stays unconfigured",
                   face_.device_name().c_str(), e.what());
      return CallbackReturn::FAILURE;
    }
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_activate(const State & state) override
  {
    LifecycleNode::on_activate(state);  // the lifecycle publisher
    face_.start();
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_deactivate(const State & state) override
  {
    face_.stop();
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_cleanup(const State &) override
  {
    face_.close();
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_shutdown(const State & state) override
  {
    face_.close();
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_error(const State & state) override
  {
    RCLCPP_ERROR(get_logger(), "error in a transition from state %s: closing %s", state.label().c_str(),
                 face_.device_name().c_str());
    face_.close();
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

private:
  DriverRosFace<rclcpp_lifecycle::LifecycleNode> face_;
};

#else

/// The plain driver: opens the device and streams from its constructor.
class WhiskerDriverComponent : public rclcpp::Node {
public:
  explicit WhiskerDriverComponent(const rclcpp::NodeOptions & options)
  : Node(WhiskerDriverLogic::kNodeName, options), face_(*this)
  {
    face_.open();
    face_.start();
  }

private:
  DriverRosFace<rclcpp::Node> face_;
};

#endif

}  // namespace whisker_driver

RCLCPP_COMPONENTS_REGISTER_NODE(whisker_driver::WhiskerDriverComponent)
