// When an event-driven node runs its control step: on the arrival of the input that
// drives it (a behaviour on TactileDepth, the bridge on a HoverSetpoint), with a
// periodic watchdog that steps it when that input stops, so stale-input fail-safes
// (which act in the step) keep running at at least the watchdog's rate. ROS-free: the
// rclcpp components and the real-time standalone host (`tactile fly`) use it the same way.
//
// Rules, with T = period_ns (the node's nominal step period, e.g. the FSM's 50 Hz):
//   1. on_event(t): step now, unless the last event step was less than T/2 ago (a burst
//      of inputs, or inputs faster than 2/T, is rate-limited to 2/T; the newest input is
//      kept by the node and used at its next step, the watchdog's at the latest: see 2)
//      -> skipped_events. A watchdog step
//      just before does not hold an arrival back: the input is never delayed by the
//      watchdog's phase.
//   2. on_watchdog(), called every T by a timer: step if no step (event or watchdog)
//      happened since the previous watchdog call, or an arrival was held back by rule 1
//      since the last step; otherwise the events are driving the node and the watchdog
//      stays quiet. So the node steps at least once per watchdog
//      period whatever the inputs do (the timer-driven design's guarantee), and on the
//      input's arrival while they flow (no timer phase in the latency).
// Steps are counted by cause (event_steps, watchdog_steps); `t` is the node's clock in ns
// (sim time under use_sim_time); if it goes back, the rate limit starts over.
#pragma once

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace tactile_common {

class EventTick {
 public:
  struct Stats {
    uint64_t event_steps = 0;     ///< steps on an input's arrival (rule 1)
    uint64_t watchdog_steps = 0;  ///< steps of the watchdog: no input since its previous call (rule 2)
    uint64_t skipped_events = 0;  ///< arrivals within T/2 of the last event step (rule 1, rate limit)
  };

  /// period_ns > 0: throws std::invalid_argument naming it otherwise.
  explicit EventTick(int64_t period_ns) : period_ns_(period_ns) {
    if (period_ns <= 0) {
      throw std::invalid_argument("EventTick: period_ns must be > 0 (got " + std::to_string(period_ns) + ")");
    }
  }

  /// Rule 1: true if the node steps now on this arrival.
  bool on_event(int64_t now_ns) {
    // A clock that went back (a bag played again, a simulator restarted) starts over.
    if (last_event_ns_ != kNever && now_ns < last_event_ns_) last_event_ns_ = kNever;
    if (last_event_ns_ != kNever && now_ns - last_event_ns_ < period_ns_ / 2) {
      ++stats_.skipped_events;
      held_back_ = true;
      return false;
    }
    ++stats_.event_steps;
    last_event_ns_ = now_ns;
    stepped_since_watchdog_ = true;
    held_back_ = false;
    return true;
  }

  /// Rule 2: true if the node steps now on its watchdog (no step since the previous call).
  bool on_watchdog() {
    const bool step = !stepped_since_watchdog_ || held_back_;
    stepped_since_watchdog_ = false;
    held_back_ = false;
    if (!step) return false;
    ++stats_.watchdog_steps;  // stepped_since_watchdog_ stays false: its own step does not silence the next call
    return true;
  }

  int64_t period_ns() const { return period_ns_; }
  const Stats& stats() const { return stats_; }

 private:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::min();

  int64_t period_ns_;
  int64_t last_event_ns_ = kNever;
  bool stepped_since_watchdog_ = false;
  bool held_back_ = false;  ///< an arrival skipped by rule 1 since the last step
  Stats stats_;
};

}  // namespace tactile_common
