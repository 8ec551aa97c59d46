#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "crazyflie_bridge/protocol.hpp"
#include "tactile_common/time.hpp"

namespace crazyflie_bridge {

using tactile_common::ParamMap;

namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kDegToRad = M_PI / 180.0;

struct Q {
  double x, y, z, w;
};
Q mul(const Q& a, const Q& b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
Q yaw_q(double yaw) { return {0, 0, std::sin(yaw / 2), std::cos(yaw / 2)}; }

/// Orientation, body rates and covariances of `o` from an attitude sample.
/// Roll and pitch come from the compressed quaternion (9-bit components:
/// ~0.1 deg); yaw is the state block's float stateEstimate.yaw, so that the
/// heading is exactly the logged one: q = Rz(yaw) * Rz(-yaw(q_z)) * q_z, which
/// keeps q_z's roll and pitch (Z-Y-X decomposition).
void fill_attitude(nav_msgs::msg::Odometry& o, const AttitudeBlock::Sample& a, double yaw,
                   const CrazyflieBridgeLogic::Params& p) {
  const Q qz{a.q.x, a.q.y, a.q.z, a.q.w};
  const double yaw_z = std::atan2(2 * (qz.w * qz.z + qz.x * qz.y), 1 - 2 * (qz.y * qz.y + qz.z * qz.z));
  Q q = mul(yaw_q(yaw), mul(yaw_q(-yaw_z), qz));
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  o.pose.pose.orientation.x = q.x / n;
  o.pose.pose.orientation.y = q.y / n;
  o.pose.pose.orientation.z = q.z / n;
  o.pose.pose.orientation.w = q.w / n;
  o.twist.twist.angular.x = a.rates[0];
  o.twist.twist.angular.y = a.rates[1];
  o.twist.twist.angular.z = a.rates[2];
  // 6x6 row-major (x, y, z, rot x, rot y, rot z): diagonals only.
  for (size_t i = 0; i < 3; ++i) {
    o.pose.covariance[7 * i] = a.have_variances ? a.position_variance[i] : p.position_variance;
    o.pose.covariance[7 * (i + 3)] = p.orientation_variance;
    o.twist.covariance[7 * i] = p.linear_velocity_variance;
    o.twist.covariance[7 * (i + 3)] = p.angular_velocity_variance;
  }
}

void positive(const char* field, double v) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw std::invalid_argument(std::string("CrazyflieBridgeLogic.") + field + ": must be finite and > 0, got " +
                                std::to_string(v));
  }
}
}  // namespace

const char* to_string(CrazyflieBridgeLogic::Mode m) {
  switch (m) {
    case CrazyflieBridgeLogic::Mode::kWaiting: return "waiting";
    case CrazyflieBridgeLogic::Mode::kForward: return "forward";
    case CrazyflieBridgeLogic::Mode::kHoverHold: return "hover_hold";
    case CrazyflieBridgeLogic::Mode::kLanding: return "landing";
    case CrazyflieBridgeLogic::Mode::kStopped: return "stopped";
  }
  return "?";
}

void CrazyflieBridgeLogic::Params::validate() const {
  parse_uri(uri);  // throws UriError naming the part
  if (left_pressure_vars.size() != 3 || right_pressure_vars.size() != 3) {
    throw std::invalid_argument("CrazyflieBridgeLogic.left/right_pressure_vars: must name 3 barometers each");
  }
  if (state_vars.size() != 6) {
    throw std::invalid_argument("CrazyflieBridgeLogic.state_vars: must name x, y, z, yaw, vx, vy (6), got " +
                                std::to_string(state_vars.size()));
  }
  positive("pressure_scale", pressure_scale);
  if (whisker_period_ms < 1 || whisker_period_ms > 65535 || state_period_ms < 1 || state_period_ms > 65535) {
    throw std::invalid_argument("CrazyflieBridgeLogic.whisker/state_period_ms: must be in [1, 65535] ms (u16 period)");
  }
  positive("setpoint_rate_hz", setpoint_rate_hz);
  if (setpoint_rate_hz < 2.0) {
    throw std::invalid_argument("CrazyflieBridgeLogic.setpoint_rate_hz: must be >= 2 Hz (firmware commander watchdog 500 ms), got " +
                                std::to_string(setpoint_rate_hz));
  }
  positive("max_velocity", max_velocity);
  positive("max_yaw_rate", max_yaw_rate);
  positive("max_height", max_height);
  if (!std::isfinite(min_height) || min_height < 0.0 || min_height >= max_height) {
    throw std::invalid_argument("CrazyflieBridgeLogic.min_height: must be in [0, max_height), got " + std::to_string(min_height));
  }
  positive("setpoint_timeout_s", setpoint_timeout_s);
  positive("log_timeout_s", log_timeout_s);
  positive("hover_hold_s", hover_hold_s);
  positive("land_speed", land_speed);
  positive("land_height", land_height);
  positive("position_variance", position_variance);
  positive("orientation_variance", orientation_variance);
  positive("linear_velocity_variance", linear_velocity_variance);
  positive("angular_velocity_variance", angular_velocity_variance);
}

ParamMap CrazyflieBridgeLogic::default_parameters() {
  const Params d;
  ParamMap m(kNodeName, "defaults");
  m.set("uri", d.uri);
  m.set("left_pressure_vars", d.left_pressure_vars);
  m.set("right_pressure_vars", d.right_pressure_vars);
  m.set("pressure_scale", d.pressure_scale);
  m.set("state_vars", d.state_vars);
  m.set("whisker_period_ms", d.whisker_period_ms);  // 000: barometers at 50 Hz
  m.set("state_period_ms", d.state_period_ms);
  m.set("setpoint_rate_hz", d.setpoint_rate_hz);
  m.set("max_velocity", d.max_velocity);
  m.set("max_yaw_rate", d.max_yaw_rate);
  m.set("min_height", d.min_height);
  m.set("max_height", d.max_height);
  m.set("setpoint_timeout_s", d.setpoint_timeout_s);
  m.set("log_timeout_s", d.log_timeout_s);
  m.set("hover_hold_s", d.hover_hold_s);
  m.set("land_speed", d.land_speed);
  m.set("land_height", d.land_height);
  m.set("position_variance", d.position_variance);
  m.set("orientation_variance", d.orientation_variance);
  m.set("linear_velocity_variance", d.linear_velocity_variance);
  m.set("angular_velocity_variance", d.angular_velocity_variance);
  return m;
}

CrazyflieBridgeLogic::Params CrazyflieBridgeLogic::params_from(const ParamMap& m) {
  Params p;
  p.uri = m.get_string("uri");
  p.left_pressure_vars = m.get_string_array("left_pressure_vars");
  p.right_pressure_vars = m.get_string_array("right_pressure_vars");
  p.pressure_scale = m.get_double("pressure_scale");
  p.state_vars = m.get_string_array("state_vars");
  p.whisker_period_ms = m.get_int64("whisker_period_ms", 1, 65535);  // u16 log period
  p.state_period_ms = m.get_int64("state_period_ms", 1, 65535);
  p.setpoint_rate_hz = m.get_double("setpoint_rate_hz");
  p.max_velocity = m.get_double("max_velocity");
  p.max_yaw_rate = m.get_double("max_yaw_rate");
  p.min_height = m.get_double("min_height");
  p.max_height = m.get_double("max_height");
  p.setpoint_timeout_s = m.get_double("setpoint_timeout_s");
  p.log_timeout_s = m.get_double("log_timeout_s");
  p.hover_hold_s = m.get_double("hover_hold_s");
  p.land_speed = m.get_double("land_speed");
  p.land_height = m.get_double("land_height");
  p.position_variance = m.get_double("position_variance");
  p.orientation_variance = m.get_double("orientation_variance");
  p.linear_velocity_variance = m.get_double("linear_velocity_variance");
  p.angular_velocity_variance = m.get_double("angular_velocity_variance");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw tactile_common::ParamError(m.source() + ": " + kNodeName + ": " + e.what());
  }
  return p;
}

CrazyflieBridgeLogic::CrazyflieBridgeLogic(const Params& params) : params_(params) { params_.validate(); }

std::vector<std::string> CrazyflieBridgeLogic::whisker_block() const {
  std::vector<std::string> v = params_.left_pressure_vars;
  v.insert(v.end(), params_.right_pressure_vars.begin(), params_.right_pressure_vars.end());
  return v;
}

void CrazyflieBridgeLogic::set_block_ids(uint8_t whisker, uint8_t state) {
  whisker_block_ = whisker;
  state_block_ = state;
  clock_.add_block(whisker, static_cast<uint32_t>(params_.whisker_period_ms));
  clock_.add_block(state, static_cast<uint32_t>(params_.state_period_ms));
}

std::vector<std::string> CrazyflieBridgeLogic::attitude_block(bool with_variances) const {
  auto v = AttitudeBlock::compressed_vars();
  if (with_variances) {
    for (const auto& n : AttitudeBlock::variance_vars()) v.push_back(n);
  }
  return v;
}

void CrazyflieBridgeLogic::set_attitude_block_id(uint8_t id) {
  attitude_block_ = id;
  clock_.add_block(id, static_cast<uint32_t>(params_.state_period_ms));
}

CrazyflieBridgeLogic::LogOutputs CrazyflieBridgeLogic::on_log_sample(const LogSample& s, int64_t now_ns) {
  LogOutputs out;
  const bool whisker = s.block_id == whisker_block_ && s.values.size() == 6;
  const bool state = s.block_id == state_block_ && s.values.size() == 6;
  const bool attitude = s.block_id == attitude_block_ && (s.values.size() == 4 || s.values.size() == 7);
  if (!whisker && !state && !attitude) {
    ++stats_.dropped_unknown_block;
    return out;
  }
  for (double v : s.values) {
    if (!std::isfinite(v)) {
      ++stats_.dropped_nonfinite;
      return out;
    }
  }
  ++stats_.log_samples;
  have_log_ = true;
  log_ns_ = now_ns;
  // Sequence and stamp from the firmware's log timestamp (LogClock): a lost
  // log packet is a gap in the sequence; the stamp is firmware time on the
  // host clock, not the receive time.
  const LogClock::Stamp ts = clock_.on_sample(s.block_id, s.timestamp_ms, now_ns);
  stats_.log_samples_missed += ts.missed;
  if (ts.restart) ++stats_.log_clock_restarts;
  if (attitude) {
    auto a = AttitudeBlock::decode(s.values, s.timestamp_ms);
    if (a) {
      attitude_ = *a;
      ++stats_.attitude_samples;
    } else {
      ++stats_.dropped_attitude_invalid;
    }
    return out;
  }
  if (whisker) {
    for (int w = 0; w < 2; ++w) {
      tactile_msgs::msg::WhiskerPressure m;
      tactile_common::to_stamp(ts.stamp_ns, m.header.stamp);
      m.header.frame_id = w == 0 ? "whisker_left" : "whisker_right";
      m.whisker_id = w == 0 ? tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT : tactile_msgs::msg::WhiskerPressure::WHISKER_RIGHT;
      for (size_t i = 0; i < 3; ++i) {
        m.pressure[i] = s.values[3 * static_cast<size_t>(w) + i] * params_.pressure_scale;
        m.temperature[i] = NAN;  // not logged over the radio
      }
      m.sequence = ts.sequence;
      (w == 0 ? out.left : out.right) = m;
    }
    return out;
  }
  // State estimate: x, y, z [m], yaw [deg] (firmware unit), vx, vy [m/s, world].
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ts.stamp_ns, o.header.stamp);
  o.header.frame_id = "odom";
  o.child_frame_id = "base_link";
  o.pose.pose.position.x = s.values[0];
  o.pose.pose.position.y = s.values[1];
  o.pose.pose.position.z = s.values[2];
  const double yaw = s.values[3] * kDegToRad;
  height_ = s.values[2];
  if (attitude_block_ >= 0) {
    // The latest attitude sample, less than two periods from this one in
    // firmware time: the one of the same tick, or the previous one when that
    // was lost. (The two blocks are started by separate requests, so on a
    // real link their ticks are a phase 0 <= phi < period apart: the previous
    // attitude sample is period + phi away.)
    const uint32_t d = (s.timestamp_ms - (attitude_ ? attitude_->timestamp_ms : 0)) & 0xFFFFFF;
    const int64_t dt_ms = d < 0x800000 ? static_cast<int64_t>(d) : static_cast<int64_t>(d) - 0x1000000;
    if (!attitude_ || std::llabs(dt_ms) >= 2 * params_.state_period_ms) {
      ++stats_.odom_without_attitude;
      return out;
    }
    fill_attitude(o, *attitude_, yaw, params_);
  } else {
    o.pose.pose.orientation.z = std::sin(yaw / 2);
    o.pose.pose.orientation.w = std::cos(yaw / 2);
  }
  // REP-105: twist in the body frame (yaw rotation only; roll/pitch not logged).
  const double c = std::cos(yaw), sn = std::sin(yaw);
  o.twist.twist.linear.x = c * s.values[4] + sn * s.values[5];
  o.twist.twist.linear.y = -sn * s.values[4] + c * s.values[5];
  out.odom = o;
  return out;
}

void CrazyflieBridgeLogic::on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns) {
  if (!std::isfinite(msg.vx) || !std::isfinite(msg.vy) || !std::isfinite(msg.yaw_rate) || !std::isfinite(msg.height)) {
    ++stats_.dropped_setpoint_nonfinite;
    return;
  }
  ++stats_.setpoints_in;
  setpoint_ = msg;
  const auto clamp = [&](double& v, double lo, double hi) {
    const double c = std::clamp(v, lo, hi);
    if (c != v) {
      v = c;
      return true;
    }
    return false;
  };
  bool clamped = clamp(setpoint_.vx, -params_.max_velocity, params_.max_velocity);
  clamped |= clamp(setpoint_.vy, -params_.max_velocity, params_.max_velocity);
  clamped |= clamp(setpoint_.yaw_rate, -params_.max_yaw_rate, params_.max_yaw_rate);
  if (!msg.land) clamped |= clamp(setpoint_.height, params_.min_height, params_.max_height);
  if (clamped) ++stats_.setpoints_clamped;
  have_setpoint_ = true;
  setpoint_ns_ = now_ns;
}

std::optional<CrtpPacket> CrazyflieBridgeLogic::on_timer(int64_t now_ns) {
  const double dt = last_timer_ns_ > 0 ? tactile_common::to_seconds(now_ns - last_timer_ns_) : 1.0 / params_.setpoint_rate_hz;
  last_timer_ns_ = now_ns;
  const bool setpoint_fresh = have_setpoint_ && tactile_common::to_seconds(now_ns - setpoint_ns_) <= params_.setpoint_timeout_s;
  const bool log_fresh = have_log_ && tactile_common::to_seconds(now_ns - log_ns_) <= params_.log_timeout_s;
  switch (mode_) {
    case Mode::kWaiting:
      if (setpoint_fresh && log_fresh) mode_ = Mode::kForward;
      break;
    case Mode::kForward:
      if (!setpoint_fresh || !log_fresh) {
        mode_ = Mode::kHoverHold;
        hold_start_ns_ = now_ns;
        ++stats_.stale_events;
        command_.vx = command_.vy = command_.yaw_rate = 0.0;  // hover in place at the last height
      }
      break;
    case Mode::kHoverHold:
      if (setpoint_fresh && log_fresh) {
        mode_ = Mode::kForward;
      } else if (tactile_common::to_seconds(now_ns - hold_start_ns_) >= params_.hover_hold_s) {
        mode_ = Mode::kLanding;
        ++stats_.landings;
      }
      break;
    case Mode::kLanding:
    case Mode::kStopped:
      break;
  }
  std::optional<CrtpPacket> pk;
  switch (mode_) {
    case Mode::kWaiting:
      return std::nullopt;  // nothing sent until the pipeline and the link are up
    case Mode::kForward:
      command_ = setpoint_;
      if (setpoint_.land) {
        mode_ = Mode::kLanding;
        ++stats_.landings;
        command_.height = height_;
      } else {
        pk = commander::hover(static_cast<float>(command_.vx), static_cast<float>(command_.vy),
                              static_cast<float>(command_.yaw_rate * kRadToDeg), static_cast<float>(command_.height));
        break;
      }
      [[fallthrough]];
    case Mode::kLanding:
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.land = true;
      command_.height = std::max(0.0, std::min(command_.height, height_ + 0.1) - params_.land_speed * dt);
      if (command_.height <= params_.land_height || (log_fresh && height_ <= params_.land_height)) {
        mode_ = Mode::kStopped;
        pk = commander::stop();
      } else {
        pk = commander::hover(0.f, 0.f, 0.f, static_cast<float>(command_.height));
      }
      break;
    case Mode::kHoverHold:
      pk = commander::hover(0.f, 0.f, 0.f, static_cast<float>(command_.height));
      break;
    case Mode::kStopped:
      // Stop is repeated a few times (a lost packet must not leave the motors
      // on), then nothing: the firmware keeps them off.
      if (stops_sent_ >= kStopRepeats) return std::nullopt;
      pk = commander::stop();
      break;
  }
  if (pk) pk = commander::for_protocol(*pk, protocol_version_);  // cflib's packet for this firmware generation
  if (pk && commander::decode(*pk).kind == commander::Setpoint::Kind::kStop) ++stops_sent_;
  ++stats_.packets_out;
  return pk;
}

}  // namespace crazyflie_bridge
