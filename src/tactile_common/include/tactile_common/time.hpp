// Time helpers: nanoseconds <-> builtin_interfaces/Time-like stamps.
// Templates, so they work with the ROS-free generated types and with rosidl's.
#pragma once

#include <cmath>
#include <cstdint>

namespace tactile_common {

constexpr int64_t kNanosPerSecond = 1000000000LL;

/// Fills a builtin_interfaces::msg::Time from nanoseconds (non-negative).
template <class Stamp>
void to_stamp(int64_t ns, Stamp& stamp) {
  int64_t sec = ns / kNanosPerSecond;
  int64_t rem = ns % kNanosPerSecond;
  if (rem < 0) {
    rem += kNanosPerSecond;
    --sec;
  }
  stamp.sec = static_cast<decltype(stamp.sec)>(sec);
  stamp.nanosec = static_cast<decltype(stamp.nanosec)>(rem);
}

/// Nanoseconds of a builtin_interfaces::msg::Time.
template <class Stamp>
int64_t from_stamp(const Stamp& stamp) {
  return static_cast<int64_t>(stamp.sec) * kNanosPerSecond + static_cast<int64_t>(stamp.nanosec);
}

constexpr double to_seconds(int64_t ns) { return static_cast<double>(ns) * 1e-9; }
constexpr int64_t from_seconds(double s) { return static_cast<int64_t>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)); }

/// The staleness rule of every behaviour and controller (their fail-safes): an input is
/// fresh when it is at most max_age old, with 1 ns of tolerance for ages computed from
/// integer nanoseconds (to_seconds(300000000) - 0.3 > 0). An age that is NaN (never
/// received) is stale; a negative age (stamped ahead of the tick's clock) is fresh.
inline bool age_is_fresh(double age, double max_age) { return age <= max_age + 1e-9; }

/// The same rule on a stamp: fresh at time t when stamped (finite) and at most max_age old.
inline bool input_is_fresh(double t, double stamp, double max_age) {
  return std::isfinite(stamp) && age_is_fresh(t - stamp, max_age);
}

}  // namespace tactile_common
