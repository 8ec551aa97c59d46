// rclcpp component of the Crazyflie bridge: a mechanical adapter around
// BridgeRunner / CrazyflieBridgeLogic (all flight behaviour lives there) and
// BridgeHealth (status and diagnostics thresholds). ROS builds only.
//
// - One wall timer at setpoint_rate_hz receives the pending log data (at most 5 ms),
//   publishes it and sends the setpoint: link I/O stays on one thread.
// - Operator services (relative names; tactile_msgs/srv, Crazyswarm2's crazyflie_interfaces
//   field for field): takeoff, land, go_to, emergency, arm, notify_setpoints_stop and
//   start_behaviour (hand-over). The crazyflie_interfaces responses are empty, so a refused
//   command is logged (WARN) with the logic's reason; start_behaviour answers it too.
// - `status` (tactile_msgs/msg/BridgeStatus) at status_rate_hz and, where the ROS 2
//   installation has diagnostic_updater, /diagnostics (battery, link, log stream, flight).
// - Shutdown lands first: on Ctrl-C / SIGTERM (rclcpp's pre-shutdown callback, while the
//   CRTP link is still open) or when the component is destroyed, BridgeRunner::land_and_stop
//   lands an airborne Crazyflie within shutdown_land_timeout_s, then stops the motors
//   (emergency stop if the landing did not finish in time).
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>

#include "crazyflie_bridge/bridge_health.hpp"
#include "crazyflie_bridge/bridge_runner.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_msgs/msg/bridge_status.hpp"
#include "tactile_msgs/srv/arm.hpp"
#include "tactile_msgs/srv/go_to.hpp"
#include "tactile_msgs/srv/land.hpp"
#include "tactile_msgs/srv/notify_setpoints_stop.hpp"
#include "tactile_msgs/srv/start_behaviour.hpp"
#include "tactile_msgs/srv/stop.hpp"
#include "tactile_msgs/srv/takeoff.hpp"
#ifdef CRAZYFLIE_BRIDGE_HAVE_DIAGNOSTIC_UPDATER
#include "diagnostic_updater/diagnostic_updater.hpp"
#endif

namespace crazyflie_bridge {

namespace {

double seconds(const builtin_interfaces::msg::Duration & d)
{
  return static_cast<double>(d.sec) + 1e-9 * static_cast<double>(d.nanosec);
}

}  // namespace

class CrazyflieBridgeComponent : public rclcpp::Node {
public:
  explicit CrazyflieBridgeComponent(const rclcpp::NodeOptions & options)
  : Node(CrazyflieBridgeLogic::kNodeName, options),
    params_(CrazyflieBridgeLogic::params_from(
      tactile_common::declare_parameters(*this, CrazyflieBridgeLogic::default_parameters()))),
    health_(BridgeHealth::params_from(
      tactile_common::declare_parameters(*this, BridgeHealth::default_parameters()))),
    runner_(params_)
  {
    left_pub_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      CrazyflieBridgeLogic::kLeftPressureTopic, rclcpp::SensorDataQoS());
    right_pub_ = create_publisher<tactile_msgs::msg::WhiskerPressure>(
      CrazyflieBridgeLogic::kRightPressureTopic, rclcpp::SensorDataQoS());
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>(
      CrazyflieBridgeLogic::kOdomTopic, rclcpp::SensorDataQoS());
    status_pub_ = create_publisher<tactile_msgs::msg::BridgeStatus>(BridgeHealth::kStatusTopic, 10);
    setpoint_sub_ = create_subscription<tactile_msgs::msg::HoverSetpoint>(
      CrazyflieBridgeLogic::kSetpointTopic, rclcpp::QoS(10),
      [this](const tactile_msgs::msg::HoverSetpoint & msg) {
        runner_.on_hover_setpoint(msg, now_ns());
      });
    sinks_.left = [this](const tactile_msgs::msg::WhiskerPressure & m) {left_pub_->publish(m);};
    sinks_.right = [this](const tactile_msgs::msg::WhiskerPressure & m) {right_pub_->publish(m);};
    sinks_.odom = [this](const nav_msgs::msg::Odometry & m) {odom_pub_->publish(m);};

    create_operator_services();

    timer_ = create_wall_timer(
      std::chrono::nanoseconds(static_cast<int64_t>(1e9 / params_.setpoint_rate_hz)),
      [this]() {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (shut_down_) {return;}  // the shutdown landing owns the link now
        runner_.pump(std::chrono::milliseconds(5), [this]() {return now_ns();}, sinks_);
        runner_.on_timer(now_ns());
      });
    status_timer_ = create_wall_timer(
      std::chrono::nanoseconds(static_cast<int64_t>(1e9 / health_.status_rate_hz)),
      [this]() {
        const int64_t t = now_ns();
        status_pub_->publish(BridgeHealth::to_msg(runner_.status(t), t));
      });
#ifdef CRAZYFLIE_BRIDGE_HAVE_DIAGNOSTIC_UPDATER
    updater_ = std::make_unique<diagnostic_updater::Updater>(this, health_.diagnostics_period_s);
    updater_->setHardwareID("crazyflie " + params_.uri);
    // One task per check; each evaluates the current status (a few comparisons).
    for (const auto & check : BridgeHealth::evaluate(health_, runner_.status(now_ns()))) {
      const std::string name = check.name;
      updater_->add(name, [this, name](diagnostic_updater::DiagnosticStatusWrapper & stat) {
        for (const auto & c : BridgeHealth::evaluate(health_, runner_.status(now_ns()))) {
          if (c.name != name) {continue;}
          stat.summary(static_cast<unsigned char>(c.level), c.message);
          for (const auto & [key, value] : c.values) {stat.add(key, value);}
        }
      });
    }
#endif

    // Ctrl-C / SIGTERM: rclcpp shuts the context down from its signal handler thread; the
    // pre-shutdown callbacks run before rcl is shut down, with the link and clock usable.
    shutdown_callback_ = get_node_base_interface()->get_context()->add_pre_shutdown_callback(
      [this]() {land_on_shutdown("shutdown (Ctrl-C / SIGTERM)");});

    RCLCPP_INFO(
      get_logger(), "connected to %s; mode %s%s", params_.uri.c_str(), to_string(runner_.mode()),
      params_.autostart ? " (autostart: the behaviour is forwarded once setpoints and log data are fresh)" :
      " (nothing flies until takeoff; then start_behaviour hands over to the behaviour)");
  }

  ~CrazyflieBridgeComponent() override
  {
    get_node_base_interface()->get_context()->remove_pre_shutdown_callback(shutdown_callback_);
    land_on_shutdown("the bridge component is destroyed");
  }

private:
  int64_t now_ns() const {return get_clock()->now().nanoseconds();}

  /// Logs a command's outcome with the logic's reason (it names the command and its
  /// values); the crazyflie_interfaces responses cannot carry it.
  void report(const CrazyflieBridgeLogic::CommandResult & r)
  {
    if (r.accepted) {
      RCLCPP_INFO(get_logger(), "%s; mode %s", r.reason.c_str(), to_string(runner_.mode()));
    } else {
      RCLCPP_WARN(get_logger(), "%s", r.reason.c_str());
    }
  }

  void create_operator_services()
  {
    using namespace tactile_msgs::srv;  // NOLINT
    takeoff_srv_ = create_service<Takeoff>(
      "takeoff", [this](const Takeoff::Request::SharedPtr req, Takeoff::Response::SharedPtr) {
        // 0 selects the configured default (a Crazyswarm2 client always sends both fields).
        const double h = req->height == 0.0f ? params_.takeoff_height : static_cast<double>(req->height);
        const double d = seconds(req->duration) == 0.0 ? params_.takeoff_duration_s : seconds(req->duration);
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown("takeoff")) {return;}
        report(runner_.takeoff(h, d, now_ns()));
      });
    land_srv_ = create_service<Land>(
      "land", [this](const Land::Request::SharedPtr req, Land::Response::SharedPtr) {
        const double d = seconds(req->duration) == 0.0 ? params_.land_duration_s : seconds(req->duration);
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown("land")) {return;}
        report(runner_.land(static_cast<double>(req->height), d, now_ns()));
      });
    go_to_srv_ = create_service<GoTo>(
      "go_to", [this](const GoTo::Request::SharedPtr req, GoTo::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown("go_to")) {return;}
        report(runner_.go_to(req->goal.x, req->goal.y, req->goal.z, static_cast<double>(req->yaw),
                             seconds(req->duration), req->relative, now_ns()));
      });
    emergency_srv_ = create_service<Stop>(
      "emergency", [this](const Stop::Request::SharedPtr, Stop::Response::SharedPtr) {
        // No shutdown check: an emergency stop is always taken.
        std::lock_guard<std::mutex> lock(io_mutex_);
        // BridgeRunner sends the first stop packet before it returns.
        const auto r = runner_.emergency_stop(now_ns());
        if (r.accepted) {
          RCLCPP_ERROR(get_logger(), "EMERGENCY STOP (service): %s", r.reason.c_str());
        } else {
          RCLCPP_ERROR(get_logger(), "%s", r.reason.c_str());
        }
      });
    arm_srv_ = create_service<Arm>(
      "arm", [this](const Arm::Request::SharedPtr req, Arm::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown(req->arm ? "arm" : "disarm")) {return;}
        report(runner_.arm(req->arm, now_ns()));
      });
    notify_srv_ = create_service<NotifySetpointsStop>(
      "notify_setpoints_stop",
      [this](const NotifySetpointsStop::Request::SharedPtr req, NotifySetpointsStop::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown("notify_setpoints_stop")) {return;}
        report(runner_.notify_setpoints_stop(req->remain_valid_millisecs, now_ns()));
      });
    start_srv_ = create_service<StartBehaviour>(
      "start_behaviour",
      [this](const StartBehaviour::Request::SharedPtr, StartBehaviour::Response::SharedPtr res) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse_after_shutdown("start_behaviour")) {
          res->success = false;
          res->message = "start_behaviour refused: the bridge is shutting down";
          return;
        }
        const auto r = runner_.start_behaviour(now_ns());
        report(r);
        res->success = r.accepted;
        res->message = r.accepted ? std::string("mode ") + to_string(runner_.mode()) : r.reason;
      });
  }

  bool refuse_after_shutdown(const char * what)
  {
    if (!shut_down_) {return false;}
    RCLCPP_WARN(get_logger(), "%s refused: the bridge is shutting down", what);
    return true;
  }

  /// Once: land (bounded), then motors off; the timer no longer touches the link.
  void land_on_shutdown(const char * why)
  {
    std::lock_guard<std::mutex> lock(io_mutex_);  // waits for a timer tick in progress
    if (shut_down_) {return;}
    shut_down_ = true;
    const auto mode = runner_.mode();
    const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(1e3 * params_.shutdown_land_timeout_s));
    RCLCPP_INFO(get_logger(), "%s: landing from mode %s (at most %.1f s), then motors off", why, to_string(mode),
                params_.shutdown_land_timeout_s);
    const auto t0 = std::chrono::steady_clock::now();
    bool landed = false;
    try {
      landed = runner_.land_and_stop(timeout, [this]() {return now_ns();}, sinks_);
    } catch (const std::exception & e) {
      RCLCPP_ERROR(get_logger(), "shutdown landing failed: %s", e.what());
    }
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (landed) {
      RCLCPP_INFO(get_logger(), "shutdown: landed and stopped in %.2f s (mode %s)", took, to_string(runner_.mode()));
    } else {
      RCLCPP_ERROR(get_logger(), "shutdown: not landed within %.1f s: emergency stop sent (mode %s)",
                   params_.shutdown_land_timeout_s, to_string(runner_.mode()));
    }
  }

  CrazyflieBridgeLogic::Params params_;
  BridgeHealth::Params health_;
  BridgeRunner runner_;
  BridgeRunner::Sinks sinks_;
  std::mutex io_mutex_;  ///< the link's receive side and the shutdown landing
  bool shut_down_ = false;
  rclcpp::Publisher<tactile_msgs::msg::WhiskerPressure>::SharedPtr left_pub_, right_pub_;
  rclcpp::Publisher<nav_msgs::msg::Odometry>::SharedPtr odom_pub_;
  rclcpp::Publisher<tactile_msgs::msg::BridgeStatus>::SharedPtr status_pub_;
  rclcpp::Subscription<tactile_msgs::msg::HoverSetpoint>::SharedPtr setpoint_sub_;
  rclcpp::Service<tactile_msgs::srv::Takeoff>::SharedPtr takeoff_srv_;
  rclcpp::Service<tactile_msgs::srv::Land>::SharedPtr land_srv_;
  rclcpp::Service<tactile_msgs::srv::GoTo>::SharedPtr go_to_srv_;
  rclcpp::Service<tactile_msgs::srv::Stop>::SharedPtr emergency_srv_;
  rclcpp::Service<tactile_msgs::srv::Arm>::SharedPtr arm_srv_;
  rclcpp::Service<tactile_msgs::srv::NotifySetpointsStop>::SharedPtr notify_srv_;
  rclcpp::Service<tactile_msgs::srv::StartBehaviour>::SharedPtr start_srv_;
  rclcpp::TimerBase::SharedPtr timer_, status_timer_;
  rclcpp::PreShutdownCallbackHandle shutdown_callback_;
#ifdef CRAZYFLIE_BRIDGE_HAVE_DIAGNOSTIC_UPDATER
  std::unique_ptr<diagnostic_updater::Updater> updater_;
#endif
};

}  // namespace crazyflie_bridge

RCLCPP_COMPONENTS_REGISTER_NODE(crazyflie_bridge::CrazyflieBridgeComponent)
