// rclcpp component of the Crazyflie bridge: a mechanical adapter around
// BridgeRunner / CrazyflieBridgeLogic (all flight behaviour lives there) and
// BridgeHealth (status and diagnostics thresholds). ROS builds only.
//
// Two hosts of one ROS face (BridgeRosFace below, templated on the node type):
// - where the ROS 2 installation has rclcpp_lifecycle (CRAZYFLIE_BRIDGE_LIFECYCLE), a
//   managed node: configure opens the link (cflib's connection sequence, TOCs, log
//   blocks created), activate starts streaming (log blocks started, timers, publishers,
//   operator services), deactivate lands first if airborne and stops streaming, cleanup
//   closes the link; shutdown and error land, stop the motors and close it;
// - elsewhere a plain rclcpp::Node that does configure + activate in its constructor
//   (a link that cannot be opened throws: the container's load fails).
//
// - One wall timer at setpoint_rate_hz receives the pending log data (at most 5 ms),
//   publishes it and sends the setpoint: link I/O stays on one thread.
// - Operator services (relative names; tactile_msgs/srv, Crazyswarm2's crazyflie_interfaces
//   field for field): takeoff, land, go_to, emergency, arm, notify_setpoints_stop and
//   start_behaviour (hand-over). The crazyflie_interfaces responses are empty, so a refused
//   command is logged (WARN) with the logic's reason; start_behaviour answers it too.
//   Refused unless streaming (active); emergency is taken whenever the link is open.
// - `status` (tactile_msgs/msg/BridgeStatus) at status_rate_hz and, where the ROS 2
//   installation has diagnostic_updater, /diagnostics (battery, link, log stream, flight;
//   STALE "not streaming" while not active).
// - Shutdown lands first: on Ctrl-C / SIGTERM (rclcpp's pre-shutdown callback, while the
//   CRTP link is still open), on the lifecycle's deactivate / shutdown / error, or when the
//   component is destroyed, BridgeRunner::land_and_stop lands an airborne Crazyflie within
//   shutdown_land_timeout_s, then stops the motors (emergency stop if the landing did not
//   finish in time). Nothing takes off because the node became active: the operator's
//   takeoff (or autostart) does.
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>

#include "crazyflie_bridge/bridge_health.hpp"
#include "crazyflie_bridge/bridge_runner.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "std_msgs/msg/string.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tactile_common/ros_qos.hpp"
#ifdef TACTILE_HAVE_TF2
#include "tactile_common/ros_tf.hpp"
#endif
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
#ifdef CRAZYFLIE_BRIDGE_LIFECYCLE
#include "lifecycle_msgs/msg/state.hpp"
#include "rclcpp_lifecycle/lifecycle_node.hpp"
#endif

namespace crazyflie_bridge {

namespace {

double seconds(const builtin_interfaces::msg::Duration & d)
{
  return static_cast<double>(d.sec) + 1e-9 * static_cast<double>(d.nanosec);
}

}  // namespace

/// Everything of the bridge's ROS face that does not depend on the node's base class.
/// NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode (whose publishers are activated
/// by the node's own on_activate / on_deactivate).
template <class NodeT>
class BridgeRosFace {
public:
  /// Parameters (a bad value throws: the container's load fails, naming file and key),
  /// publishers, the setpoint subscription, the operator services and diagnostics.
  /// No link yet: open().
  explicit BridgeRosFace(NodeT & node)
  : node_(node),
    // The flight parameters are read-only; the health thresholds are live (BridgeHealth::
    // default_parameters()): a new threshold applies from the next status / diagnostics.
    parameters_(node, {CrazyflieBridgeLogic::default_parameters(), BridgeHealth::default_parameters()},
                [this](const tactile_common::ParamMap & values) {
                  health_ = BridgeHealth::live_update(health_, BridgeHealth::params_from(values));
                }),
    params_(CrazyflieBridgeLogic::params_from(parameters_.values())),
    health_(BridgeHealth::params_from(parameters_.values()))
  {
    // The log data's publishers and the setpoint subscription, as in `tactile fly`
    // (BridgeRunner::wire).
    sinks_ = BridgeRunner::wire(ports_, [this](const tactile_msgs::msg::HoverSetpoint & msg) {
        // In forward mode this sends at once: link I/O under io_mutex_, as the timer's.
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (shut_down_ || !active_) {return;}  // the shutdown landing owns the link now
        runner_->on_hover_setpoint(msg, now_ns());
      });
#ifdef TACTILE_HAVE_TF2
    sinks_.odom = [this, publish_odom = std::move(sinks_.odom)](const nav_msgs::msg::Odometry & m) {
        publish_odom(m);
        broadcaster_->sendTransform(tactile_common::odometry_transform(m));  // odom -> base_link
      };
#endif
    status_pub_ = node_.template create_publisher<tactile_msgs::msg::BridgeStatus>(BridgeHealth::kStatusTopic, 10);
    // Frames (README "Frames"): the whiskered Crazyflie's URDF on robot_description
    // (latched; a plain publisher even in the lifecycle node, so it is there before
    // activation), /tf_static map -> odom and base_link -> its links, /tf odom -> base_link
    // with every odometry message.
    const CrazyflieBridgeLogic frames(params_);
    description_pub_ = tactile_common::latched_publisher<std_msgs::msg::String>(
      node_.get_node_topics_interface(), kRobotDescriptionTopic);
    std_msgs::msg::String description;
    description.data = frames.robot_description();
    description_pub_->publish(description);
#ifdef TACTILE_HAVE_TF2
    static_broadcaster_ = tactile_common::static_broadcaster(node_);
    static_broadcaster_->sendTransform(
      tactile_common::static_transforms(frames.static_frames(), builtin_interfaces::msg::Time()));
    broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>(node_);
#else
    RCLCPP_WARN(node_.get_logger(), "crazyflie_bridge: built without tf2_ros: no /tf, /tf_static");
#endif

    create_operator_services();
#ifdef CRAZYFLIE_BRIDGE_HAVE_DIAGNOSTIC_UPDATER
    updater_ = std::make_unique<diagnostic_updater::Updater>(&node_, health_.diagnostics_period_s);
    updater_->setHardwareID("crazyflie " + params_.uri);
    // One task per check; each evaluates the current status (a few comparisons).
    for (const auto & check : BridgeHealth::evaluate(health_, CrazyflieBridgeLogic::Status{})) {
      const std::string name = check.name;
      updater_->add(name, [this, name](diagnostic_updater::DiagnosticStatusWrapper & stat) {
        if (!active_) {
          stat.summary(diagnostic_msgs::msg::DiagnosticStatus::STALE,
                       std::string("not streaming: the bridge is ") + (runner_ ? "inactive" : "unconfigured"));
          return;
        }
        for (const auto & c : BridgeHealth::evaluate(health_, runner_->status(now_ns()))) {
          if (c.name != name) {continue;}
          stat.summary(static_cast<unsigned char>(c.level), c.message);
          for (const auto & [key, value] : c.values) {stat.add(key, value);}
        }
      });
    }
#endif
    // Ctrl-C / SIGTERM: rclcpp shuts the context down from its signal handler thread; the
    // pre-shutdown callbacks run before rcl is shut down, with the link and clock usable.
    shutdown_callback_ = node_.get_node_base_interface()->get_context()->add_pre_shutdown_callback(
      [this]() {land_on_shutdown("shutdown (Ctrl-C / SIGTERM)");});
  }

  ~BridgeRosFace()
  {
    node_.get_node_base_interface()->get_context()->remove_pre_shutdown_callback(shutdown_callback_);
    land_on_shutdown("the bridge component is destroyed");
  }

  BridgeRosFace(const BridgeRosFace &) = delete;
  BridgeRosFace & operator=(const BridgeRosFace &) = delete;

  const CrazyflieBridgeLogic::Params & params() const {return params_;}

  /// Opens params.uri: link, cflib's connection sequence (protocol and firmware version,
  /// TOCs), log blocks created, not started. Throws UriError / LinkError / ClientError /
  /// std::runtime_error (shutting down) with the reason.
  void open()
  {
    std::lock_guard<std::mutex> lock(io_mutex_);
    if (shut_down_) {throw std::runtime_error("the bridge is shutting down");}
    runner_ = std::make_unique<BridgeRunner>(params_, ClientOptions{}, nullptr, /*stream=*/false);
    const auto & c = runner_->client();
    RCLCPP_INFO(
      node_.get_logger(), "connected to %s: CRTP protocol %u, firmware '%s', %zu log / %zu param TOC entries",
      params_.uri.c_str(), static_cast<unsigned>(c.protocol_version()), c.firmware_version().c_str(),
      c.log_toc().size(), c.param_toc().size());
    for (const auto & w : runner_->warnings()) {RCLCPP_WARN(node_.get_logger(), "%s", w.c_str());}
  }

  /// Starts the log blocks and the timers; the services answer from now on. Nothing is
  /// sent to the motors until takeoff (or autostart with fresh setpoints and log data).
  void start()
  {
    std::lock_guard<std::mutex> lock(io_mutex_);
    if (!runner_) {throw std::runtime_error("no link: configure first");}
    if (shut_down_) {throw std::runtime_error("the bridge is shutting down");}
    runner_->start_streaming();
    start_timers_locked();
    RCLCPP_INFO(
      node_.get_logger(), "streaming from %s; mode %s%s", params_.uri.c_str(), to_string(runner_->mode()),
      params_.autostart ? " (autostart: the behaviour is forwarded once setpoints and log data are fresh)" :
      " (nothing flies until takeoff; then start_behaviour hands over to the behaviour)");
  }

  /// Lands first when airborne (bounded by shutdown_land_timeout_s, then motors off),
  /// then stops the timers and the log blocks. Returns false (still streaming, reason
  /// logged) when the log blocks could not be stopped.
  bool stop(const char * why)
  {
    if (!runner_) {return true;}
    land_and_stop_motors(why, /*final=*/false);
    std::lock_guard<std::mutex> lock(io_mutex_);
    active_ = false;
    timer_.reset();
    status_timer_.reset();
    try {
      if (!runner_->stop_streaming()) {
        RCLCPP_ERROR(node_.get_logger(), "%s: still airborne (mode %s): streaming not stopped", why,
                     to_string(runner_->mode()));
        start_timers_locked();
        return false;
      }
    } catch (const std::exception & e) {
      // The motors are off (landed or emergency-stopped above): streaming is not needed
      // for safety any more; the link is released by cleanup.
      RCLCPP_ERROR(node_.get_logger(), "%s: stopping the log blocks failed: %s", why, e.what());
    }
    RCLCPP_INFO(node_.get_logger(), "%s: streaming stopped; mode %s, link to %s open", why,
                to_string(runner_->mode()), params_.uri.c_str());
    return true;
  }

  /// Closes the link (after stop()).
  void close(const char * why)
  {
    std::lock_guard<std::mutex> lock(io_mutex_);
    if (!runner_) {return;}
    active_ = false;
    timer_.reset();
    status_timer_.reset();
    runner_.reset();
    RCLCPP_INFO(node_.get_logger(), "%s: link to %s closed", why, params_.uri.c_str());
  }

  /// Once and for good: land (bounded), then motors off; the timer no longer touches the link.
  void land_on_shutdown(const char * why) {land_and_stop_motors(why, /*final=*/true);}

private:
  int64_t now_ns() const {return node_.get_clock()->now().nanoseconds();}

  /// The link timer (receive, publish, send the setpoint) and the status timer; active.
  void start_timers_locked()
  {
    timer_ = node_.create_wall_timer(
      std::chrono::nanoseconds(static_cast<int64_t>(1e9 / params_.setpoint_rate_hz)),
      [this]() {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (shut_down_ || !active_) {return;}  // the shutdown landing owns the link now
        runner_->pump(std::chrono::milliseconds(5), [this]() {return now_ns();}, sinks_);
        runner_->on_timer(now_ns());
      });
    status_timer_ = node_.create_wall_timer(
      std::chrono::nanoseconds(static_cast<int64_t>(1e9 / health_.status_rate_hz)),
      [this]() {
        if (!active_) {return;}
        const int64_t t = now_ns();
        status_pub_->publish(BridgeHealth::to_msg(runner_->status(t), t));
      });
    active_ = true;
  }

  static bool airborne(CrazyflieBridgeLogic::Mode m)
  {
    using M = CrazyflieBridgeLogic::Mode;
    return m == M::kTakingOff || m == M::kHovering || m == M::kGoTo || m == M::kForward ||
           m == M::kHoverHold || m == M::kLanding;
  }

  /// Logs a command's outcome with the logic's reason (it names the command and its
  /// values); the crazyflie_interfaces responses cannot carry it.
  void report(const CrazyflieBridgeLogic::CommandResult & r)
  {
    if (r.accepted) {
      RCLCPP_INFO(node_.get_logger(), "%s; mode %s", r.reason.c_str(), to_string(runner_->mode()));
    } else {
      RCLCPP_WARN(node_.get_logger(), "%s", r.reason.c_str());
    }
  }

  /// The reason a command is not taken now (shutting down, not streaming), or empty.
  std::string refusal(const char * what) const
  {
    if (shut_down_) {return std::string(what) + " refused: the bridge is shutting down";}
    if (!active_) {
      return std::string(what) + " refused: the bridge is not active (" +
             (runner_ ? "inactive: activate it" : "unconfigured: configure and activate it") + ")";
    }
    return {};
  }

  bool refuse(const char * what)
  {
    const std::string r = refusal(what);
    if (r.empty()) {return false;}
    RCLCPP_WARN(node_.get_logger(), "%s", r.c_str());
    return true;
  }

  void create_operator_services()
  {
    using namespace tactile_msgs::srv;  // NOLINT
    takeoff_srv_ = node_.template create_service<Takeoff>(
      "takeoff", [this](const Takeoff::Request::SharedPtr req, Takeoff::Response::SharedPtr) {
        // 0 selects the configured default (a Crazyswarm2 client always sends both fields).
        const double h = req->height == 0.0f ? params_.takeoff_height : static_cast<double>(req->height);
        const double d = seconds(req->duration) == 0.0 ? params_.takeoff_duration_s : seconds(req->duration);
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse("takeoff")) {return;}
        report(runner_->takeoff(h, d, now_ns()));
      });
    land_srv_ = node_.template create_service<Land>(
      "land", [this](const Land::Request::SharedPtr req, Land::Response::SharedPtr) {
        const double d = seconds(req->duration) == 0.0 ? params_.land_duration_s : seconds(req->duration);
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse("land")) {return;}
        report(runner_->land(static_cast<double>(req->height), d, now_ns()));
      });
    go_to_srv_ = node_.template create_service<GoTo>(
      "go_to", [this](const GoTo::Request::SharedPtr req, GoTo::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse("go_to")) {return;}
        report(runner_->go_to(req->goal.x, req->goal.y, req->goal.z, static_cast<double>(req->yaw),
                              seconds(req->duration), req->relative, now_ns()));
      });
    emergency_srv_ = node_.template create_service<Stop>(
      "emergency", [this](const Stop::Request::SharedPtr, Stop::Response::SharedPtr) {
        // No shutdown or lifecycle check: an emergency stop is taken whenever the link is open.
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (!runner_) {
          RCLCPP_ERROR(node_.get_logger(), "emergency: no link to %s (unconfigured): nothing to stop",
                       params_.uri.c_str());
          return;
        }
        // BridgeRunner sends the first stop packet before it returns.
        const auto r = runner_->emergency_stop(now_ns());
        if (r.accepted) {
          RCLCPP_ERROR(node_.get_logger(), "EMERGENCY STOP (service): %s", r.reason.c_str());
        } else {
          RCLCPP_ERROR(node_.get_logger(), "%s", r.reason.c_str());
        }
      });
    arm_srv_ = node_.template create_service<Arm>(
      "arm", [this](const Arm::Request::SharedPtr req, Arm::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse(req->arm ? "arm" : "disarm")) {return;}
        report(runner_->arm(req->arm, now_ns()));
      });
    notify_srv_ = node_.template create_service<NotifySetpointsStop>(
      "notify_setpoints_stop",
      [this](const NotifySetpointsStop::Request::SharedPtr req, NotifySetpointsStop::Response::SharedPtr) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        if (refuse("notify_setpoints_stop")) {return;}
        report(runner_->notify_setpoints_stop(req->remain_valid_millisecs, now_ns()));
      });
    start_srv_ = node_.template create_service<StartBehaviour>(
      "start_behaviour",
      [this](const StartBehaviour::Request::SharedPtr, StartBehaviour::Response::SharedPtr res) {
        std::lock_guard<std::mutex> lock(io_mutex_);
        const std::string no = refusal("start_behaviour");
        if (!no.empty()) {
          RCLCPP_WARN(node_.get_logger(), "%s", no.c_str());
          res->success = false;
          res->message = no;
          return;
        }
        const auto r = runner_->start_behaviour(now_ns());
        report(r);
        res->success = r.accepted;
        res->message = r.accepted ? std::string("mode ") + to_string(runner_->mode()) : r.reason;
      });
  }

  /// Lands an airborne vehicle (bounded), then the motors are off. `final`: once, and no
  /// command or timer touches the link afterwards (shutdown, destruction).
  void land_and_stop_motors(const char * why, bool final)
  {
    std::lock_guard<std::mutex> lock(io_mutex_);  // waits for a timer tick in progress
    if (shut_down_) {return;}
    if (final) {shut_down_ = true;}
    if (!runner_) {return;}
    const auto mode = runner_->mode();
    if (!final && !airborne(mode)) {return;}  // on the ground: the motors are not commanded
    const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(1e3 * params_.shutdown_land_timeout_s));
    RCLCPP_INFO(node_.get_logger(), "%s: landing from mode %s (at most %.1f s), then motors off", why,
                to_string(mode), params_.shutdown_land_timeout_s);
    const auto t0 = std::chrono::steady_clock::now();
    bool landed = false;
    try {
      landed = runner_->land_and_stop(timeout, [this]() {return now_ns();}, sinks_);
    } catch (const std::exception & e) {
      RCLCPP_ERROR(node_.get_logger(), "%s: landing failed: %s", why, e.what());
    }
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const char * tag = final ? "shutdown" : why;  // "shutdown: landed ..." whatever ended the node
    if (landed) {
      RCLCPP_INFO(node_.get_logger(), "%s: landed and stopped in %.2f s (mode %s)", tag, took,
                  to_string(runner_->mode()));
    } else {
      RCLCPP_ERROR(node_.get_logger(), "%s: not landed within %.1f s: emergency stop sent (mode %s)", tag,
                   params_.shutdown_land_timeout_s, to_string(runner_->mode()));
    }
  }

  template <class Msg>
  using PublisherPtr = decltype(std::declval<NodeT &>().template create_publisher<Msg>(
      std::string(), rclcpp::QoS(1)));

  NodeT & node_;
  /// Declared first: its values configure the bridge; its on-set callback applies the live
  /// health thresholds and refuses every other key.
  tactile_common::NodeParameters parameters_;
  CrazyflieBridgeLogic::Params params_;
  BridgeHealth::Params health_;
  std::unique_ptr<BridgeRunner> runner_;  ///< the open link (configured)
  BridgeRunner::Sinks sinks_;
  std::mutex io_mutex_;  ///< the link's receive side, the runner's lifetime and the shutdown landing
  bool shut_down_ = false;
  std::atomic<bool> active_{false};  ///< streaming: timers run, services and setpoints are taken
  PublisherPtr<tactile_msgs::msg::BridgeStatus> status_pub_;
  static constexpr const char * kRobotDescriptionTopic = "robot_description";
  rclcpp::Publisher<std_msgs::msg::String>::SharedPtr description_pub_;
#ifdef TACTILE_HAVE_TF2
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> broadcaster_;
#endif
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
  /// The setpoint subscription (BridgeRunner::wire). Declared last: it goes first, no
  /// callback outlives the members it uses.
  tactile_common::RosPorts<NodeT> ports_{node_};
};

#ifdef CRAZYFLIE_BRIDGE_LIFECYCLE

/// The managed bridge (crazyflie_bridge README "Lifecycle"): unconfigured after load;
/// configure opens the link, activate streams, deactivate lands (if airborne) and stops
/// streaming, cleanup closes the link.
class CrazyflieBridgeComponent : public rclcpp_lifecycle::LifecycleNode {
public:
  using CallbackReturn = rclcpp_lifecycle::node_interfaces::LifecycleNodeInterface::CallbackReturn;
  using State = rclcpp_lifecycle::State;

  explicit CrazyflieBridgeComponent(const rclcpp::NodeOptions & options)
  : LifecycleNode(CrazyflieBridgeLogic::kNodeName, options), face_(*this)
  {
    RCLCPP_INFO(get_logger(), "unconfigured: configure opens %s (ros2 lifecycle set %s configure)",
                face_.params().uri.c_str(), get_fully_qualified_name());
  }

  ~CrazyflieBridgeComponent() override
  {
    // Unloaded from its container (or the process ends): the shutdown transition while
    // the context is still up (it lands first), else land and close directly.
    if (rclcpp::ok(get_node_base_interface()->get_context()) &&
      get_current_state().id() != lifecycle_msgs::msg::State::PRIMARY_STATE_FINALIZED)
    {
      shutdown();
    }
    face_.land_on_shutdown("the bridge component is destroyed");
    face_.close("the bridge component is destroyed");
  }

  CallbackReturn on_configure(const State &) override
  {
    try {
      face_.open();
    } catch (const std::exception & e) {
      RCLCPP_ERROR(get_logger(), "configure failed: cannot open %s: %s; the bridge stays unconfigured",
                   face_.params().uri.c_str(), e.what());
      face_.close("configure failed");
      return CallbackReturn::FAILURE;
    }
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_activate(const State & state) override
  {
    LifecycleNode::on_activate(state);  // the lifecycle publishers
    try {
      face_.start();
    } catch (const std::exception & e) {
      RCLCPP_ERROR(get_logger(), "activate failed: %s; the bridge stays inactive", e.what());
      LifecycleNode::on_deactivate(state);
      return CallbackReturn::FAILURE;
    }
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_deactivate(const State & state) override
  {
    // Lands first (publishers still active: odometry during the landing), then stops.
    if (!face_.stop("deactivate")) {return CallbackReturn::FAILURE;}
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_cleanup(const State &) override
  {
    face_.close("cleanup");
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_shutdown(const State & state) override
  {
    face_.land_on_shutdown("lifecycle shutdown");
    face_.close("lifecycle shutdown");
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_error(const State & state) override
  {
    // A transition threw: land if airborne, motors off, link closed -> unconfigured.
    RCLCPP_ERROR(get_logger(), "error in a transition from state %s: landing (if airborne) and closing the link",
                 state.label().c_str());
    face_.stop("error");
    face_.close("error");
    LifecycleNode::on_deactivate(state);
    return CallbackReturn::SUCCESS;
  }

private:
  BridgeRosFace<rclcpp_lifecycle::LifecycleNode> face_;
};

#else

/// The plain bridge: opens the link and streams from its constructor (a link that cannot
/// be opened throws: the container's load fails with the reason).
class CrazyflieBridgeComponent : public rclcpp::Node {
public:
  explicit CrazyflieBridgeComponent(const rclcpp::NodeOptions & options)
  : Node(CrazyflieBridgeLogic::kNodeName, options), face_(*this)
  {
    face_.open();
    face_.start();
  }

private:
  BridgeRosFace<rclcpp::Node> face_;
};

#endif

}  // namespace crazyflie_bridge

RCLCPP_COMPONENTS_REGISTER_NODE(crazyflie_bridge::CrazyflieBridgeComponent)
