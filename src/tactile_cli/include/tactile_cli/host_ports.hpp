// The `tactile` host of a node's ports (tactile_common/ports.hpp): the Bus and the
// Executor of a Host, in the node's namespace. The add_<node> functions wire a logic with
//
//   HostPorts ports(host, ns);
//   Logic::wire(ports, *logic);
//
// the same wire() its rclcpp component calls with tactile_common::RosPorts.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "tactile_cli/executor.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_common/ports.hpp"

namespace tactile_cli {

class HostPorts {
 public:
  /// Topic remappings, like a launch file's: resolved name -> name on the bus.
  using Remap = std::map<std::string, std::string>;

  /// @param ns    the node's namespace: relative topics resolve in it (resolve_topic()).
  /// @param remap the node's remappings; every one must name a topic the node declares
  ///              (check_remaps_used()).
  /// @param clock the node's clock for receive times and publish stamps, when it is not
  ///              the executor's: a real-time host (`tactile fly`) delivers messages
  ///              between the executor's runs, at a wall clock the executor lags. Timers
  ///              run on the executor either way (their handler gets the due time).
  HostPorts(Host& host, std::string ns, Remap remap = {}, std::function<int64_t()> clock = {})
      : bus_(&host.bus()),
        executor_(&host.executor()),
        ns_(std::move(ns)),
        remap_(std::move(remap)),
        clock_(std::move(clock)) {}

  /// The bus name of a topic the node declares: resolved in the namespace, then remapped.
  std::string name(std::string_view topic) {
    std::string resolved = resolve_topic(ns_, std::string(topic));
    auto it = remap_.find(resolved);
    if (it == remap_.end()) return resolved;
    used_.insert(it->first);
    return it->second;
  }

  /// The QoS kind has no effect on the bus: delivery is synchronous and lossless.
  template <class Msg, class Handler>
  void subscribe(std::string_view topic, tactile_common::ports::Sub /*qos*/, Handler handler) {
    Executor* ex = executor_;
    bus_->subscribe<Msg>(name(topic), [ex, clock = clock_, handler = std::move(handler)](const Msg& msg) {
      // Receive time: the node's clock (the host's unless given) when the message is delivered.
      tactile_common::ports::deliver(handler, msg, [&] { return clock ? clock() : ex->now_ns(); });
    });
  }

  /// Publishes on the bus at the node's clock (the host's unless given): the bag timestamp.
  template <class Msg>
  struct Publish {
    Bus* bus;
    const Executor* executor;
    std::string topic;
    std::function<int64_t()> clock;
    void operator()(const Msg& msg) const { bus->publish(topic, msg, clock ? clock() : executor->now_ns()); }
  };

  template <class Msg>
  Publish<Msg> publisher(std::string_view topic, tactile_common::ports::Pub /*qos*/) {
    return Publish<Msg>{bus_, executor_, name(topic), clock_};
  }

  /// First call now, then every period_ns of the host's clock (either Clock kind).
  template <class Handler>
  void timer(int64_t period_ns, Handler handler, tactile_common::ports::Clock /*clock*/ = {}) {
    executor_->add_timer(period_ns, std::move(handler), executor_->now_ns());
  }

  /// Throws std::logic_error naming a remapping no declared topic matched (a typo would
  /// otherwise leave the node on its own topic, silently).
  void check_remaps_used() const {
    for (const auto& [from, to] : remap_) {
      if (!used_.count(from)) {
        throw std::logic_error("remapping " + from + " -> " + to + " in namespace '" + ns_ +
                               "': the node declares no topic " + from);
      }
    }
  }

 private:
  Bus* bus_;
  Executor* executor_;
  std::string ns_;
  Remap remap_;
  std::function<int64_t()> clock_;  ///< empty: the executor's
  std::set<std::string> used_;
};

/// Wires `logic` into the host in namespace `ns` through its Logic::wire() (the ports its
/// rclcpp component has too), with `remap` applied.
template <class Logic>
void wire(Host& host, const std::string& ns, Logic& logic, HostPorts::Remap remap = {}) {
  HostPorts ports(host, ns, std::move(remap));
  Logic::wire(ports, logic);
  ports.check_remaps_used();
}

}  // namespace tactile_cli
