// Time helpers: nanoseconds <-> builtin_interfaces/Time-like stamps.
// Templates, so they work with the ROS-free generated types and with rosidl's.
#pragma once

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

}  // namespace tactile_common
