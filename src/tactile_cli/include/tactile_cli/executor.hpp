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
#include <typeindex>
#include <utility>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"

namespace tactile_cli {

/// Joins a namespace and a relative topic like rclcpp does: ("whisker/left",
/// "pressure") -> "/whisker/left/pressure"; absolute topics are kept.
std::string resolve_topic(const std::string& ns, const std::string& topic);

/// Receives every message published on the bus (e.g. the bag recorder).
class BusTap {
 public:
  virtual ~BusTap() = default;
  /// `serialize` produces the CDR bytes of the message on demand.
  virtual void on_message(const std::string& topic, const std::string& type_name,
                          const std::string& definition, int64_t stamp_ns,
                          const std::function<std::vector<uint8_t>()>& serialize) = 0;
};

/// Typed publish/subscribe by topic name. Delivery is synchronous and in
/// subscription order, so a run is deterministic.
class Bus {
 public:
  template <class T>
  using Callback = std::function<void(const T&)>;

  template <class T>
  void subscribe(const std::string& topic, Callback<T> cb) {
    check_type<T>(topic);
    subscribers_[topic].push_back([cb = std::move(cb)](const void* msg) {
      cb(*static_cast<const T*>(msg));
    });
  }

  /// Publishes `msg` at simulated time `now_ns` (the bag timestamp).
  template <class T>
  void publish(const std::string& topic, const T& msg, int64_t now_ns) {
    using Traits = tactile_msgs::cdr::MessageTraits<T>;
    check_type<T>(topic);
    ++published_[topic];
    for (auto* tap : taps_) {
      tap->on_message(topic, Traits::type_name, Traits::definition(), now_ns,
                      [&msg] { return tactile_msgs::cdr::serialize(msg); });
    }
    auto it = subscribers_.find(topic);
    if (it == subscribers_.end()) return;
    for (auto& cb : it->second) cb(&msg);
  }

  void add_tap(BusTap* tap) { taps_.push_back(tap); }
  const std::map<std::string, uint64_t>& published_counts() const { return published_; }

 private:
  template <class T>
  void check_type(const std::string& topic) {
    auto [it, inserted] = types_.emplace(topic, std::type_index(typeid(T)));
    if (!inserted && it->second != std::type_index(typeid(T))) {
      throw std::logic_error("topic " + topic + " is used with two different message types");
    }
  }

  std::map<std::string, std::type_index> types_;
  std::map<std::string, std::vector<std::function<void(const void*)>>> subscribers_;
  std::map<std::string, uint64_t> published_;
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
