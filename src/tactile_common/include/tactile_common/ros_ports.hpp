// The rclcpp host of a node's ports (ports.hpp): a component wires its logic with
//
//   tactile_common::RosPorts<> ports_{*this};   // a member declared after logic_
//   Logic::wire(ports_, logic_);                 // in the constructor
//
// Subscriptions and timers live as long as the RosPorts (declare it after the logic, so
// they are destroyed first and no callback outlives the logic); publishers as long as the
// callables wire() keeps. The QoS of each kind is the one of ros_qos.hpp. Header-only and
// included only by rclcpp components, like ros_qos.hpp.
#pragma once

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "rclcpp/create_timer.hpp"
#include "rclcpp/rclcpp.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_common/ros_qos.hpp"

namespace tactile_common {

/// NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode (whose publishers are lifecycle
/// publishers: they publish once the node is active).
template <class NodeT = rclcpp::Node>
class RosPorts {
 public:
  explicit RosPorts(NodeT& node) : node_(node) {}
  RosPorts(const RosPorts&) = delete;
  RosPorts& operator=(const RosPorts&) = delete;

  template <class Msg, class Handler>
  void subscribe(const std::string& topic, ports::Sub qos, Handler handler) {
    NodeT* node = &node_;
    auto callback = [node, handler = std::move(handler)](const Msg& msg) {
      // Receive time: this node's clock (sim time under ros2 bag play --clock).
      ports::deliver(handler, msg, [node] { return node->now().nanoseconds(); });
    };
    switch (qos) {
      case ports::Sub::kSensorData:
        keep(node_.template create_subscription<Msg>(topic, rclcpp::SensorDataQoS(), std::move(callback)));
        return;
      case ports::Sub::kReliable:
        keep(node_.template create_subscription<Msg>(topic, rclcpp::QoS(10).reliable().durability_volatile(),
                                                     std::move(callback)));
        return;
      case ports::Sub::kLatched:
        if constexpr (std::is_base_of_v<rclcpp::Node, NodeT>) {
          keep(latched_subscription<Msg>(static_cast<rclcpp::Node&>(node_), topic, std::move(callback)));
          return;
        } else {
          throw std::logic_error("RosPorts: latched subscription to " + topic + " on a node that is not an rclcpp::Node");
        }
    }
    throw std::logic_error("RosPorts: unknown subscription QoS kind for " + topic);
  }

  template <class Msg>
  auto publisher(const std::string& topic, ports::Pub qos) {
    using Ptr = decltype(data_publisher<Msg>(node_, topic));
    Ptr pub;
    switch (qos) {
      case ports::Pub::kData:
        pub = data_publisher<Msg>(node_, topic);
        break;
      case ports::Pub::kLatched:
        if constexpr (std::is_base_of_v<rclcpp::Node, NodeT>) {
          pub = latched_publisher<Msg>(static_cast<rclcpp::Node&>(node_), topic);
          break;
        } else {
          throw std::logic_error("RosPorts: latched publisher " + topic + " on a node that is not an rclcpp::Node");
        }
    }
    if (!pub) throw std::logic_error("RosPorts: unknown publisher QoS kind for " + topic);
    return Publish<Msg, Ptr>{std::move(pub)};
  }

  template <class Handler>
  void timer(int64_t period_ns, Handler handler, ports::Clock clock = ports::Clock::kNode) {
    NodeT* node = &node_;
    auto callback = [node, handler = std::move(handler)]() { handler(node->now().nanoseconds()); };
    const std::chrono::nanoseconds period(period_ns);
    if (clock == ports::Clock::kSteady) {
      timers_.push_back(node_.create_wall_timer(period, std::move(callback)));
    } else {
      timers_.push_back(rclcpp::create_timer(&node_, node_.get_clock(), period, std::move(callback)));
    }
  }

  /// Stops every timer (a lifecycle node's deactivate); start_timers() restarts them,
  /// each a full period from then (rclcpp TimerBase::reset()).
  void cancel_timers() {
    for (auto& t : timers_) t->cancel();
  }
  void start_timers() {
    for (auto& t : timers_) t->reset();
  }

 private:
  /// Publishes into a unique_ptr: under use_intra_process_comms the message then moves to
  /// the subscriptions in the same container (publish(const T&) copies it first).
  template <class Msg, class Ptr>
  struct Publish {
    Ptr publisher;
    void operator()(Msg msg) const { publisher->publish(std::make_unique<Msg>(std::move(msg))); }
  };

  void keep(std::shared_ptr<rclcpp::SubscriptionBase> s) { subscriptions_.push_back(std::move(s)); }

  NodeT& node_;
  std::vector<std::shared_ptr<rclcpp::SubscriptionBase>> subscriptions_;
  std::vector<rclcpp::TimerBase::SharedPtr> timers_;
};

}  // namespace tactile_common
