// Fault injection on the simulator's output messages, as declared in the
// scenario (sensor dropout, NaN / out-of-range samples, stuck channel, drift
// spikes, latency, message loss). Node-logic layer: works on message types.
#pragma once

#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "sensor_msgs/msg/range.hpp"
#include "tactile_common/time.hpp"
#include "tactile_msgs/msg/arm_imu_array.hpp"
#include "tactile_msgs/msg/optical_flow.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "tactile_sim/scenario.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_sim {

/// The numeric channels of a message a fault can corrupt. Channel i of a
/// WhiskerPressure is pressure[i]; of an Imu: 0-2 angular velocity x,y,z,
/// 3-5 linear acceleration x,y,z; of a Range: 0 = range; of an Odometry: 0-2
/// position x,y,z; of an OpticalFlow: 0 = flow_x, 1 = flow_y; of an
/// ArmImuArray: arms[i].arm_angle; of a ThrustCommand: rotor_thrust[i].
template <class T>
struct FaultChannels;

template <>
struct FaultChannels<tactile_msgs::msg::WhiskerPressure> {
  static size_t count(const tactile_msgs::msg::WhiskerPressure&) { return 3; }
  static double& at(tactile_msgs::msg::WhiskerPressure& m, size_t i) { return m.pressure[i]; }
};
template <>
struct FaultChannels<sensor_msgs::msg::Imu> {
  static size_t count(const sensor_msgs::msg::Imu&) { return 6; }
  static double& at(sensor_msgs::msg::Imu& m, size_t i) {
    auto& v = i < 3 ? m.angular_velocity : m.linear_acceleration;
    const size_t k = i % 3;
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
  }
};
template <>
struct FaultChannels<sensor_msgs::msg::Range> {
  static size_t count(const sensor_msgs::msg::Range&) { return 1; }
  static float& at(sensor_msgs::msg::Range& m, size_t) { return m.range; }
};
template <>
struct FaultChannels<nav_msgs::msg::Odometry> {
  static size_t count(const nav_msgs::msg::Odometry&) { return 3; }
  static double& at(nav_msgs::msg::Odometry& m, size_t i) {
    auto& p = m.pose.pose.position;
    return i == 0 ? p.x : (i == 1 ? p.y : p.z);
  }
};
template <>
struct FaultChannels<tactile_msgs::msg::OpticalFlow> {
  static size_t count(const tactile_msgs::msg::OpticalFlow&) { return 2; }
  static double& at(tactile_msgs::msg::OpticalFlow& m, size_t i) { return i == 0 ? m.flow_x : m.flow_y; }
};
template <>
struct FaultChannels<tactile_msgs::msg::ArmImuArray> {
  static size_t count(const tactile_msgs::msg::ArmImuArray& m) { return m.arms.size(); }
  static double& at(tactile_msgs::msg::ArmImuArray& m, size_t i) { return m.arms[i].arm_angle; }
};

template <>
struct FaultChannels<tactile_msgs::msg::ThrustCommand> {
  static size_t count(const tactile_msgs::msg::ThrustCommand& m) { return m.rotor_thrust.size(); }
  static double& at(tactile_msgs::msg::ThrustCommand& m, size_t i) { return m.rotor_thrust[i]; }
};

/// Counters of injected faults, by type name.
using FaultCounts = std::map<std::string, uint64_t>;

/// The faults of one topic of message type T. push() takes every message the
/// simulator produces (in time order) and appends what is delivered now;
/// latency holds messages back until their delivery time.
template <class T>
class TopicFaults {
 public:
  TopicFaults(std::vector<FaultSpec> rules, uint64_t seed) : rules_(std::move(rules)), rng_(seed) {}

  bool empty() const { return rules_.empty(); }

  void push(T msg, int64_t now_ns, std::vector<T>& out, FaultCounts& counts) {
    const double t = tactile_common::to_seconds(now_ns);
    double delay = 0.0;
    for (size_t r = 0; r < rules_.size(); ++r) {
      const FaultSpec& f = rules_[r];
      const bool active = t >= f.start_s && t < f.start_s + f.duration_s;
      if (f.type == FaultSpec::Type::kStuck) {
        if (!active) {
          stuck_.erase(r);
          continue;
        }
        auto [it, first] = stuck_.emplace(r, std::vector<double>{});
        for (size_t c = 0; c < FaultChannels<T>::count(msg); ++c) {
          if (f.channel >= 0 && static_cast<size_t>(f.channel) != c) continue;
          if (first) it->second.push_back(FaultChannels<T>::at(msg, c));
          const size_t k = f.channel >= 0 ? 0 : c;
          if (k < it->second.size()) FaultChannels<T>::at(msg, c) = static_cast<std::decay_t<decltype(FaultChannels<T>::at(msg, c))>>(it->second[k]);
        }
        ++counts[to_string(f.type)];
        continue;
      }
      if (!active) continue;
      // Every rule draws once per message, so the noise of one rule does not
      // depend on whether another one fired.
      const bool fire = uniform_(rng_) < f.probability;
      if (!fire) continue;
      switch (f.type) {
        case FaultSpec::Type::kDropout:
        case FaultSpec::Type::kLoss:
          ++counts[to_string(f.type)];
          return;
        case FaultSpec::Type::kLatency:
          delay = std::max(delay, f.delay_s);
          ++counts[to_string(f.type)];
          break;
        case FaultSpec::Type::kNan:
        case FaultSpec::Type::kOutOfRange:
        case FaultSpec::Type::kSpike:
          for (size_t c = 0; c < FaultChannels<T>::count(msg); ++c) {
            if (f.channel >= 0 && static_cast<size_t>(f.channel) != c) continue;
            auto& v = FaultChannels<T>::at(msg, c);
            using V = std::decay_t<decltype(v)>;
            if (f.type == FaultSpec::Type::kNan) v = std::numeric_limits<V>::quiet_NaN();
            if (f.type == FaultSpec::Type::kOutOfRange) v = static_cast<V>(1e9);
            if (f.type == FaultSpec::Type::kSpike) v = static_cast<V>(v + f.magnitude);
          }
          ++counts[to_string(f.type)];
          break;
        case FaultSpec::Type::kStuck:
          break;
      }
    }
    if (delay > 0.0) {
      delayed_.emplace_back(now_ns + tactile_common::from_seconds(delay), std::move(msg));
    } else {
      flush(now_ns, out);
      out.push_back(std::move(msg));
    }
  }

  /// Appends the delayed messages due at `now_ns`.
  void flush(int64_t now_ns, std::vector<T>& out) {
    while (!delayed_.empty() && delayed_.front().first <= now_ns) {
      out.push_back(std::move(delayed_.front().second));
      delayed_.pop_front();
    }
  }

 private:
  std::vector<FaultSpec> rules_;
  Rng rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::map<size_t, std::vector<double>> stuck_;  // rule -> held values
  std::deque<std::pair<int64_t, T>> delayed_;
};

/// Faults of the rules that name `topic`.
inline std::vector<FaultSpec> faults_for(const std::vector<FaultSpec>& all, const std::string& topic) {
  std::vector<FaultSpec> out;
  for (const auto& f : all) {
    if (f.topic == topic) out.push_back(f);
  }
  return out;
}

}  // namespace tactile_sim
