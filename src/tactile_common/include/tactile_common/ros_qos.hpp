// QoS rules of the rclcpp components. Header-only and included only by rclcpp
// components, so the ROS-free build never sees rclcpp.
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

#include "rclcpp/rclcpp.hpp"

namespace tactile_common {

// Options of a latched publisher: intra-process off (see above).
inline rclcpp::PublisherOptions latched_publisher_options() {
  rclcpp::PublisherOptions options;
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

// The same on a node's topics interface: for a lifecycle node, whose own
// create_publisher() makes a lifecycle publisher that drops messages until activation
// (crazyflie_bridge's robot_description is there from construction).
template <class MessageT>
std::shared_ptr<rclcpp::Publisher<MessageT>> latched_publisher(
    rclcpp::node_interfaces::NodeTopicsInterface::SharedPtr topics, const std::string& topic,
    size_t depth = 1) {
  // By value: Jazzy's rclcpp takes the interface pointer by non-const reference only.
  return rclcpp::create_publisher<MessageT>(topics, topic, rclcpp::QoS(depth).reliable().transient_local(),
                                            latched_publisher_options());
}

}  // namespace tactile_common
