// Deterministic single-threaded host for node logic objects: a simulated
// clock, fixed-period timers and an in-process typed topic bus. It composes
// node logic exactly as the launch files compose the rclcpp components: the
// same node names, namespaces, topic names and parameter files.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeindex>
#include <utility>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"

namespace tactile_cli {

/// Joins a namespace and a relative topic like rclcpp does: ("whisker/left",
/// "pressure") -> "/whisker/left/pressure"; absolute topics are kept.
std::string resolve_topic(const std::string& ns, const std::string& topic);

/// The name a topic of the node logic (relative, "odom") has on this host's bus and in the
/// bags it records: the host runs one vehicle at the root namespace, so "/odom" -- the
/// names bags recorded before the topic names became relative carry too.
inline std::string root_topic(std::string_view topic) { return resolve_topic("", std::string(topic)); }

/// A topic as a tap sees it: name, type and definition, stable for the bus's lifetime.
struct TapTopic {
  const std::string& name;
  const char* type_name;        ///< "pkg/msg/Type"
  const std::string& definition;  ///< ros2msg definition text
};

/// Receives every message published on the bus (e.g. the bag recorder).
class BusTap {
 public:
  virtual ~BusTap() = default;
  /// `serialize_into` writes the CDR bytes of the message into the buffer it is given
  /// (replacing its contents, reusing its capacity), on demand.
  virtual void on_message(const TapTopic& topic, int64_t stamp_ns,
                          const std::function<void(std::vector<uint8_t>&)>& serialize_into) = 0;
};

/// Typed publish/subscribe by topic name. Delivery is synchronous and in
/// subscription order, so a run is deterministic. A relative name is resolved at the root
/// namespace ("odom" and "/odom" are one topic, named "/odom" to taps and in
/// published_counts()), as rclcpp resolves the node logic's relative names for a node
/// without a namespace.
///
/// Per message a publish costs one topic lookup (no allocation: topic names are
/// looked up as string_views) and, with a tap, one serialization into a buffer the
/// tap reuses; a simulated run publishes ~800 messages per simulated second.
class Bus {
 public:
  template <class T>
  using Callback = std::function<void(const T&)>;

  template <class T>
  void subscribe(std::string_view topic, Callback<T> cb) {
    slot<T>(topic).subscribers.push_back([cb = std::move(cb)](const void* msg) {
      cb(*static_cast<const T*>(msg));
    });
  }

  /// Publishes `msg` at simulated time `now_ns` (the bag timestamp).
  template <class T>
  void publish(std::string_view topic, const T& msg, int64_t now_ns) {
    using Traits = tactile_msgs::cdr::MessageTraits<T>;
    Slot& s = slot<T>(topic);
    ++s.published;
    if (!taps_.empty()) {
      const TapTopic t{s.name, Traits::type_name, Traits::definition()};
      const std::function<void(std::vector<uint8_t>&)> ser = [&msg](std::vector<uint8_t>& out) {
        tactile_msgs::cdr::serialize_into(msg, out);
      };
      for (auto* tap : taps_) tap->on_message(t, now_ns, ser);
    }
    for (auto& cb : s.subscribers) cb(&msg);
  }

  void add_tap(BusTap* tap) { taps_.push_back(tap); }
  /// Messages published per topic (topics that were only subscribed are not listed).
  std::map<std::string, uint64_t> published_counts() const {
    std::map<std::string, uint64_t> out;
    for (const auto& [name, s] : slots_) {
      if (s.published > 0) out.emplace(name, s.published);
    }
    return out;
  }

 private:
  struct Slot {
    std::string name;
    std::type_index type;
    uint64_t published = 0;
    std::vector<std::function<void(const void*)>> subscribers;
  };

  /// Orders names as resolved at the root: a leading '/' is ignored (keys always have one),
  /// so a relative name finds its slot without building the absolute one.
  struct RootOrder {
    using is_transparent = void;
    static std::string_view relative(std::string_view t) {
      return !t.empty() && t.front() == '/' ? t.substr(1) : t;
    }
    bool operator()(std::string_view a, std::string_view b) const { return relative(a) < relative(b); }
  };

  /// The topic's slot, created on first use; one topic carries one message type.
  template <class T>
  Slot& slot(std::string_view topic) {
    auto it = slots_.find(topic);
    if (it == slots_.end()) {
      const std::string name = root_topic(topic);
      it = slots_.emplace(name, Slot{name, std::type_index(typeid(T)), 0, {}}).first;
    } else if (it->second.type != std::type_index(typeid(T))) {
      throw std::logic_error("topic " + std::string(topic) + " is used with two different message types");
    }
    return it->second;
  }

  std::map<std::string, Slot, RootOrder> slots_;  // std::map: slot references stay valid
  std::vector<BusTap*> taps_;
};

/// Simulated clock with fixed-period timers. Timers fire in order of due
/// time, ties broken by creation order.
class Executor {
 public:
  using TimerCallback = std::function<void(int64_t now_ns)>;

  /// Adds a timer with `period_ns` whose first call is at `first_ns`.
  void add_timer(int64_t period_ns, TimerCallback cb, int64_t first_ns = 0);

  /// Sets the clock (before the first run; e.g. to the start time of a bag).
  void set_time(int64_t now_ns) { now_ns_ = now_ns; }
  /// Runs until `end_ns` (inclusive) or until stop() is called.
  void run_until(int64_t end_ns);
  void stop() { stopped_ = true; }
  bool stopped() const { return stopped_; }
  int64_t now_ns() const { return now_ns_; }

 private:
  struct Timer {
    int64_t period_ns;
    int64_t next_ns;
    TimerCallback cb;
  };
  std::vector<Timer> timers_;
  int64_t now_ns_ = 0;
  bool stopped_ = false;
};

}  // namespace tactile_cli
