// A node's ports, declared once: the topics it subscribes and publishes (each with its
// QoS kind) and its timers. ROS-free: the node logic's header declares them in a
//
//   template <class Ports>
//   static void wire(Ports& p, Logic& l);
//
// and two hosts implement `Ports`:
//   - tactile_common::RosPorts (ros_ports.hpp, ROS builds only), used by the node's rclcpp
//     component: rclcpp subscriptions, publishers and timers on the node, with the QoS of
//     ros_qos.hpp;
//   - tactile_cli::HostPorts (tactile_cli/host_ports.hpp), used by the `tactile` host's
//     add_<node> functions: the host's Bus and Executor, in the node's namespace.
// So a topic name, a QoS, a callback or a timer period is written in one place, and the
// component and the host cannot drift apart.
//
// What `Ports` offers (both hosts):
//   p.template subscribe<Msg>(topic, Sub::k..., handler);
//       handler(const Msg&) or handler(const Msg&, int64_t receive_ns): the receive time is
//       the node's clock at delivery (rclcpp now(): sim time under use_sim_time; the host's
//       Executor::now_ns()), read only when the handler takes it.
//   auto pub = p.template publisher<Msg>(topic, Pub::k...);
//       pub(msg) publishes (the rclcpp host moves it into a unique_ptr, so under
//       intra-process delivery it reaches the subscriptions without a copy). Copyable:
//       handlers capture it by value.
//   p.timer(period_ns, handler, Clock::k...);   handler(int64_t now_ns), the node's clock.
// Subscriptions and timers are created in the order wire() declares them; the host's Bus
// delivers in subscription order and breaks timer ties by creation order, so that order is
// part of a node's (deterministic) behaviour in the `tactile` host.
#pragma once

#include <cstdint>
#include <type_traits>
#include <utility>

namespace tactile_common::ports {

/// QoS of a subscription (the rules: ros_qos.hpp).
enum class Sub {
  /// rclcpp::SensorDataQoS(): best effort, keep last 5, volatile. Every stream input (sensor
  /// data, estimates): matches reliable and best-effort publishers, never waits (REP 2003).
  kSensorData,
  /// Keep last 10, reliable, volatile: an input that must not be lost (a setpoint, an event).
  kReliable,
  /// Reliable, transient local, keep last 1, never intra-process (latched_subscription()):
  /// a late subscriber still gets the last map.
  kLatched,
};

/// QoS of a publisher (the rules: ros_qos.hpp).
enum class Pub {
  /// data_publisher(): keep last 10, reliable, volatile, QoS-overridable (REP 2003).
  kData,
  /// latched_publisher(): reliable, transient local, keep last 1, never intra-process.
  kLatched,
};

/// The clock a timer runs on. The handler gets the node's clock either way.
enum class Clock {
  /// The node's clock (rclcpp::create_timer on get_clock()): sim time under use_sim_time,
  /// so a node paced by it follows `ros2 bag play --clock` and the simulator.
  kNode,
  /// Wall time (create_wall_timer): a poll of hardware, which streams in real time whatever
  /// the ROS clock does (whisker_driver).
  kSteady,
};

/// Calls a subscription handler with the message, and with the receive time when it takes
/// one: `now()` is called only then.
template <class Handler, class Msg, class Now>
void deliver(Handler& handler, const Msg& msg, Now&& now) {
  if constexpr (std::is_invocable_v<Handler&, const Msg&, int64_t>) {
    handler(msg, static_cast<int64_t>(std::forward<Now>(now)()));
  } else {
    static_assert(std::is_invocable_v<Handler&, const Msg&>,
                  "a subscription handler takes (const Msg&) or (const Msg&, int64_t receive_ns)");
    handler(msg);
  }
}

}  // namespace tactile_common::ports
