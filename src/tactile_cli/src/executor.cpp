#include "tactile_cli/executor.hpp"

#include <limits>

namespace tactile_cli {

std::string resolve_topic(const std::string& ns, const std::string& topic) {
  if (!topic.empty() && topic.front() == '/') return topic;
  std::string out = "/";
  std::string n = ns;
  while (!n.empty() && n.front() == '/') n.erase(n.begin());
  while (!n.empty() && n.back() == '/') n.pop_back();
  if (!n.empty()) out += n + "/";
  return out + topic;
}

void Executor::add_timer(int64_t period_ns, TimerCallback cb, int64_t first_ns) {
  if (period_ns <= 0) throw std::invalid_argument("Executor::add_timer: period must be > 0");
  timers_.push_back(Timer{period_ns, first_ns, std::move(cb)});
}

void Executor::run_until(int64_t end_ns) {
  stopped_ = false;
  while (!stopped_) {
    // Earliest due timer; ties go to the one created first.
    size_t next = timers_.size();
    int64_t due = std::numeric_limits<int64_t>::max();
    for (size_t i = 0; i < timers_.size(); ++i) {
      if (timers_[i].next_ns < due) {
        due = timers_[i].next_ns;
        next = i;
      }
    }
    if (next == timers_.size() || due > end_ns) break;
    now_ns_ = due;
    timers_[next].next_ns += timers_[next].period_ns;
    timers_[next].cb(now_ns_);
  }
  if (!stopped_ && now_ns_ < end_ns) now_ns_ = end_ns;
}

}  // namespace tactile_cli
