// QoS rules of the rclcpp components. Header-only and included only by rclcpp
// components, so the ROS-free build never sees rclcpp.
//
// REP 2003 (sensor data and map QoS): a driver publishes sensor data with the default
// profile -- reliable, volatile -- and a subscriber takes rclcpp::SensorDataQoS (best
// effort, which matches a reliable publisher), so RViz, Foxglove, Nav2 and `ros2 bag`,
// which subscribe reliable by default, get every topic, and our own subscribers never
// wait for a retransmission. So every data output of the workspace (the drivers', the
// simulator's, the estimators' and the controllers' setpoints) is created with
// publisher_qos() (rclcpp::QoS(10): keep last 10, reliable, volatile); rclcpp's
// SystemDefaultsQoS would leave history and depth to the RMW, and intra-process delivery
// refuses anything but an explicit keep-last depth > 0. Maps (/gpis/map, the XPLORER
// contact cloud) are latched: reliable + transient local, latched_publisher() below.
//
// Each of these publishers takes overridable_publisher_options(): rclcpp's
// QosOverridingOptions with the default policies (history, depth, reliability), so a user
// re-tunes a topic at start without a rebuild, e.g. in a parameter file
//   qos_overrides./whisker/depth.publisher.reliability: best_effort
// (read-only parameters of the node, read when the publisher is created). Durability is
// not overridable: a transient-local publisher under intra-process would throw on Humble.
//
// Latched topics (a late subscriber gets the last message: /sim/done, /gpis/map,
// /gpis/target) are transient local. The launch files compose every graph in one
// container with use_intra_process_comms: true, and ROS 2 Humble's rclcpp refuses
// intra-process communication for anything but volatile durability: creating such a
// publisher throws std::invalid_argument("intraprocess communication allowed only with
// volatile durability") (rclcpp 16.x, publisher.hpp / subscription.hpp; transient local
// under intra-process came with Jazzy, rclcpp PR 2303). So every transient-local
// publisher is created through latched_publisher(), which turns intra-process off for
// that publisher only: it goes over DDS (a latched topic is rare and small), the
// node's other publishers keep intra-process delivery, and the same code runs on Humble,
// Jazzy and Kilted. tactile_ros_tests test_humble_intra_process.py checks every launch
// graph for a transient-local publisher under intra-process.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "rclcpp/rclcpp.hpp"

namespace tactile_common {

/// The QoS of every data publisher (REP 2003, see above): keep last 10, reliable, volatile.
inline rclcpp::QoS publisher_qos() { return rclcpp::QoS(10).reliable().durability_volatile(); }

/// Publisher options that let a user override history, depth and reliability through the
/// node's `qos_overrides.<topic>.publisher.<policy>` parameters (rclcpp QosOverridingOptions).
inline rclcpp::PublisherOptions overridable_publisher_options() {
  rclcpp::PublisherOptions options;
  options.qos_overriding_options = rclcpp::QosOverridingOptions::with_default_policies();
  return options;
}

/// A data publisher (sensor data, estimates, setpoints): publisher_qos(), overridable.
/// NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode.
template <class MessageT, class NodeT>
auto data_publisher(NodeT& node, const std::string& topic) {
  return node.template create_publisher<MessageT>(topic, publisher_qos(), overridable_publisher_options());
}

// Options of a latched publisher: intra-process off (see above), QoS overridable.
inline rclcpp::PublisherOptions latched_publisher_options() {
  rclcpp::PublisherOptions options = overridable_publisher_options();
  options.use_intra_process_comm = rclcpp::IntraProcessSetting::Disable;
  return options;
}

// A reliable, transient-local publisher keeping the last `depth` messages, never
// intra-process (Humble-safe inside an intra-process container).
template <class MessageT>
std::shared_ptr<rclcpp::Publisher<MessageT>> latched_publisher(rclcpp::Node& node, const std::string& topic,
                                                              size_t depth = 1) {
  return node.create_publisher<MessageT>(topic, rclcpp::QoS(depth).reliable().transient_local(),
                                         latched_publisher_options());
}

// A reliable, transient-local subscription to a latched topic (a late subscriber still gets
// the last `depth` messages), never intra-process (Humble refuses transient local with it,
// as for latched_publisher()).
template <class MessageT, class CallbackT>
std::shared_ptr<rclcpp::Subscription<MessageT>> latched_subscription(rclcpp::Node& node, const std::string& topic,
                                                                    CallbackT&& callback, size_t depth = 1) {
  rclcpp::SubscriptionOptions options;
  options.use_intra_process_comm = rclcpp::IntraProcessSetting::Disable;
  return node.create_subscription<MessageT>(topic, rclcpp::QoS(depth).reliable().transient_local(),
                                            std::forward<CallbackT>(callback), options);
}

// The same on a node's topics interface: for a lifecycle node, whose own
// create_publisher() makes a lifecycle publisher that drops messages until activation
// (crazyflie_bridge's robot_description is there from construction).
// Not QoS-overridable: rclcpp declares the qos_overrides parameters through the node's
// parameters interface, which a topics interface alone does not give (creating it with
// QosOverridingOptions throws "passed non-default qos overriding options without providing
// a parameters interface": the lifecycle bridge then failed to load).
template <class MessageT>
std::shared_ptr<rclcpp::Publisher<MessageT>> latched_publisher(
    rclcpp::node_interfaces::NodeTopicsInterface::SharedPtr topics, const std::string& topic,
    size_t depth = 1) {
  rclcpp::PublisherOptions options;
  options.use_intra_process_comm = rclcpp::IntraProcessSetting::Disable;
  // By value: Jazzy's rclcpp takes the interface pointer by non-const reference only.
  return rclcpp::create_publisher<MessageT>(topics, topic, rclcpp::QoS(depth).reliable().transient_local(),
                                            options);
}

}  // namespace tactile_common
