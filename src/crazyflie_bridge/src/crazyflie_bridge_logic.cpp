#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <stdexcept>

#include "crazyflie_bridge/protocol.hpp"
#include "tactile_common/time.hpp"
#include "tactile_common/validation.hpp"
#include "tactile_sim/robot_model.hpp"

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

constexpr const char* kType = "CrazyflieBridgeLogic";  // names the fields in validation errors

}  // namespace

const char* to_string(CrazyflieBridgeLogic::Mode m) {
  switch (m) {
    case CrazyflieBridgeLogic::Mode::kGrounded: return "grounded";
    case CrazyflieBridgeLogic::Mode::kTakingOff: return "taking_off";
    case CrazyflieBridgeLogic::Mode::kHovering: return "hovering";
    case CrazyflieBridgeLogic::Mode::kGoTo: return "go_to";
    case CrazyflieBridgeLogic::Mode::kForward: return "forward";
    case CrazyflieBridgeLogic::Mode::kHoverHold: return "hover_hold";
    case CrazyflieBridgeLogic::Mode::kLanding: return "landing";
    case CrazyflieBridgeLogic::Mode::kStopped: return "stopped";
    case CrazyflieBridgeLogic::Mode::kEmergency: return "emergency";
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
  tactile_common::require_finite_positive(kType, "pressure_scale", pressure_scale);
  if (whisker_period_ms < 1 || whisker_period_ms > 65535 || state_period_ms < 1 || state_period_ms > 65535) {
    throw std::invalid_argument("CrazyflieBridgeLogic.whisker/state_period_ms: must be in [1, 65535] ms (u16 period)");
  }
  tactile_common::require_finite_positive(kType, "setpoint_rate_hz", setpoint_rate_hz);
  if (setpoint_rate_hz < 2.0) {
    throw std::invalid_argument("CrazyflieBridgeLogic.setpoint_rate_hz: must be >= 2 Hz (firmware commander watchdog 500 ms), got " +
                                std::to_string(setpoint_rate_hz));
  }
  tactile_common::require_finite_positive(kType, "max_velocity", max_velocity);
  tactile_common::require_finite_positive(kType, "max_yaw_rate", max_yaw_rate);
  tactile_common::require_finite_positive(kType, "max_height", max_height);
  if (!std::isfinite(min_height) || min_height < 0.0 || min_height >= max_height) {
    throw std::invalid_argument("CrazyflieBridgeLogic.min_height: must be in [0, max_height), got " + std::to_string(min_height));
  }
  tactile_common::require_finite_positive(kType, "setpoint_timeout_s", setpoint_timeout_s);
  tactile_common::require_finite_positive(kType, "log_timeout_s", log_timeout_s);
  tactile_common::require_finite_positive(kType, "hover_hold_s", hover_hold_s);
  tactile_common::require_finite_positive(kType, "land_speed", land_speed);
  tactile_common::require_finite_positive(kType, "land_height", land_height);
  if (!std::isfinite(touchdown_timeout_s) || touchdown_timeout_s <= 0.0 || touchdown_timeout_s > 10.0) {
    throw std::invalid_argument("CrazyflieBridgeLogic.touchdown_timeout_s: must be in (0, 10] s, got " +
                                std::to_string(touchdown_timeout_s));
  }
  tactile_common::require_finite_positive(kType, "position_variance", position_variance);
  tactile_common::require_finite_positive(kType, "orientation_variance", orientation_variance);
  tactile_common::require_finite_positive(kType, "linear_velocity_variance", linear_velocity_variance);
  tactile_common::require_finite_positive(kType, "angular_velocity_variance", angular_velocity_variance);
  if (land_height >= max_height) {
    throw std::invalid_argument("CrazyflieBridgeLogic.land_height: must be < max_height, got " + std::to_string(land_height));
  }
  if (!std::isfinite(takeoff_height) || takeoff_height <= land_height || takeoff_height > max_height ||
      takeoff_height < min_height) {
    throw std::invalid_argument("CrazyflieBridgeLogic.takeoff_height: must be in (land_height, max_height] and >= min_height, got " +
                                std::to_string(takeoff_height));
  }
  tactile_common::require_finite_positive(kType, "takeoff_duration_s", takeoff_duration_s);
  tactile_common::require_finite_positive(kType, "land_duration_s", land_duration_s);
  tactile_common::require_finite_positive(kType, "max_vertical_speed", max_vertical_speed);
  if (takeoff_height / takeoff_duration_s > max_vertical_speed) {
    throw std::invalid_argument("CrazyflieBridgeLogic.takeoff_duration_s: takeoff_height / takeoff_duration_s = " +
                                std::to_string(takeoff_height / takeoff_duration_s) + " m/s exceeds max_vertical_speed " +
                                std::to_string(max_vertical_speed));
  }
  if (max_height / land_duration_s > max_vertical_speed) {
    throw std::invalid_argument("CrazyflieBridgeLogic.land_duration_s: a land from max_height would descend at " +
                                std::to_string(max_height / land_duration_s) + " m/s > max_vertical_speed " +
                                std::to_string(max_vertical_speed));
  }
  if (status_vars.size() > 6) {
    throw std::invalid_argument("CrazyflieBridgeLogic.status_vars: at most 6 variables (one 26-byte log block), got " +
                                std::to_string(status_vars.size()));
  }
  if (status_period_ms < 10 || status_period_ms > 65535) {
    throw std::invalid_argument("CrazyflieBridgeLogic.status_period_ms: must be in [10, 65535] ms, got " +
                                std::to_string(status_period_ms));
  }
  if (!std::isfinite(low_battery_v) || low_battery_v < 0.0 || low_battery_v > 5.0) {
    throw std::invalid_argument("CrazyflieBridgeLogic.low_battery_v: must be in [0, 5] V (1-cell LiPo; 0 disables), got " +
                                std::to_string(low_battery_v));
  }
  tactile_common::require_finite_positive(kType, "low_battery_hold_s", low_battery_hold_s);
  tactile_common::require_finite_positive(kType, "shutdown_land_timeout_s", shutdown_land_timeout_s);
  tactile_common::validate_frame_prefix(frame_prefix, "CrazyflieBridgeLogic.frame_prefix");
  if (initial_position.size() != 3 || !std::isfinite(initial_position[0]) || !std::isfinite(initial_position[1]) ||
      !std::isfinite(initial_position[2])) {
    std::string got;
    for (const double v : initial_position) got += (got.empty() ? "" : ", ") + std::to_string(v);
    throw std::invalid_argument("CrazyflieBridgeLogic.initial_position: must be [x, y, z], 3 finite values in m, got [" +
                                got + "]");
  }
  if (shutdown_land_timeout_s < land_duration_s) {
    throw std::invalid_argument("CrazyflieBridgeLogic.shutdown_land_timeout_s: must be >= land_duration_s (" +
                                std::to_string(land_duration_s) + " s), got " + std::to_string(shutdown_land_timeout_s));
  }
}

ParamMap CrazyflieBridgeLogic::default_parameters() {
  const Params d;
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  ParamMap m(kNodeName, "defaults");
  // The flight parameters' spec (README "Parameters"): value, description, unit and the
  // range validate() accepts alone (the relations between heights, durations and speeds
  // are validate()'s). None is live: the link, log blocks, clamps and the safety chain
  // are set up at configure; `ros2 param set` refuses them (read-only).
  m.set("uri", d.uri,
        {"cflib URI of the Crazyflie (radio://, usb://, udp:// for the simulated one)", "", {}, false, choice()});
  m.set("left_pressure_vars", d.left_pressure_vars,
        {"log variables of the left whisker's 3 barometers (whisker deck driver)", "", {}, false,
         choice("the whisker deck driver's log variables")});
  m.set("right_pressure_vars", d.right_pressure_vars,
        {"log variables of the right whisker's 3 barometers", "", {}, false,
         choice("the whisker deck driver's log variables")});
  m.set("pressure_scale", d.pressure_scale,
        {"log unit -> Pa (100 for a deck logging hPa)", "Pa/unit", positive(), false, choice()});
  m.set("state_vars", d.state_vars,
        {"state estimate log variables: x, y, z, yaw, vx, vy (6)", "", {}, false, choice()});
  m.set("whisker_period_ms", d.whisker_period_ms,
        {"whisker log block period (000: barometers at 50 Hz); u16", "ms", closed(1, 65535), false,
         paper("000 Methods: barometers at 50 Hz")});
  m.set("state_period_ms", d.state_period_ms,
        {"state log block period (100 Hz, as the SITL /odom); u16", "ms", closed(1, 65535), false,
         choice("100 Hz, as the SITL /odom")});
  m.set("setpoint_rate_hz", d.setpoint_rate_hz,
        {"setpoint send rate; >= 2 Hz (firmware commander watchdog 500 ms)", "Hz", at_least(2.0), false,
         choice("crazyflie-firmware commander watchdog 500 ms")});
  m.set("max_velocity", d.max_velocity,
        {"setpoint clamp, also the go-to limit (choice)", "m/s", positive(), false, choice()});
  m.set("max_yaw_rate", d.max_yaw_rate,
        {"yaw-rate clamp (choice)", "rad/s", positive(), false, choice()});
  m.set("min_height", d.min_height,
        {"height clamp, in [0, max_height)", "m", at_least(0.0), false, choice()});
  m.set("max_height", d.max_height,
        {"height clamp (choice)", "m", positive(), false, choice()});
  m.set("setpoint_timeout_s", d.setpoint_timeout_s,
        {"behaviour setpoints older than this are stale: hover hold (10 ticks at 50 Hz)", "s", positive(), false,
         choice("10 ticks at 50 Hz")});
  m.set("log_timeout_s", d.log_timeout_s,
        {"log data older than this is a degraded link: hover hold", "s", positive(), false, choice()});
  m.set("hover_hold_s", d.hover_hold_s,
        {"hover in place this long before the safety landing", "s", positive(), false, choice()});
  m.set("land_speed", d.land_speed,
        {"safety-chain landing descent speed (as the SITL's)", "m/s", positive(), false, choice("as the SITL's")});
  m.set("land_height", d.land_height,
        {"motors off below this height; < max_height", "m", positive(), false, choice()});
  m.set("touchdown_timeout_s", d.touchdown_timeout_s,
        {"motors stop when the measured height is down, or after this long (choice)", "s", ParamRange{0.0, 10.0, true, false}, false,
         choice()});
  m.set("position_variance", d.position_variance,
        {"odometry position covariance diagonal where the firmware logs none", "m^2", positive(), false, choice()});
  m.set("orientation_variance", d.orientation_variance,
        {"odometry orientation covariance diagonal", "rad^2", positive(), false, choice()});
  m.set("linear_velocity_variance", d.linear_velocity_variance,
        {"odometry linear velocity covariance diagonal", "(m/s)^2", positive(), false, choice()});
  m.set("angular_velocity_variance", d.angular_velocity_variance,
        {"odometry angular velocity covariance diagonal", "(rad/s)^2", positive(), false, choice()});
  m.set("autostart", d.autostart,
        {"forward the behaviour as soon as setpoints and log are fresh (lockstep SITL only)", "", {}, false, choice()});
  m.set("takeoff_height", d.takeoff_height,
        {"default take-off height; in (land_height, max_height]", "m", {}, false, choice()});
  m.set("takeoff_duration_s", d.takeoff_duration_s,
        {"default take-off duration; height / duration <= max_vertical_speed", "s", positive(), false, choice()});
  m.set("land_duration_s", d.land_duration_s,
        {"default operator and shutdown land duration; max_height / duration <= max_vertical_speed", "s", positive(), false,
         choice()});
  m.set("max_vertical_speed", d.max_vertical_speed,
        {"take-off / land / go-to ramps faster than this are refused (choice)", "m/s", positive(), false, choice()});
  m.set("status_vars", d.status_vars,
        {"status log block variables (at most 6; missing ones skipped with a warning)", "", {}, false, choice()});
  m.set("status_period_ms", d.status_period_ms,
        {"status log block period", "ms", closed(10, 65535), false, choice()});
  m.set("low_battery_v", d.low_battery_v,
        {"land at this battery voltage (firmware PM_BAT_LOW_VOLTAGE 3.2 V); 0 disables", "V", closed(0.0, 5.0), false,
         choice("crazyflie-firmware pm.h PM_BAT_LOW_VOLTAGE 3.2 V")});
  m.set("low_battery_hold_s", d.low_battery_hold_s,
        {"below low_battery_v this long: land", "s", positive(), false, choice()});
  m.set("shutdown_land_timeout_s", d.shutdown_land_timeout_s,
        {"bound of the Ctrl-C / SIGTERM land, then emergency stop; >= land_duration_s", "s", positive(), false,
         choice()});
  m.set("frame_prefix", d.frame_prefix,
        {"prefix of every frame but map, for several vehicles (cf1/: cf1/odom, cf1/base_link)", "", {}, false,
         choice("REP 105 frames per vehicle")});
  m.set("initial_position", d.initial_position,
        {"where the Crazyflie stands at take-off in map, [x, y, z] finite (robots file); map -> odom is this "
         "translation",
         "m", {}, false, choice("robots file")});
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
  p.touchdown_timeout_s = m.get_double("touchdown_timeout_s");
  p.position_variance = m.get_double("position_variance");
  p.orientation_variance = m.get_double("orientation_variance");
  p.linear_velocity_variance = m.get_double("linear_velocity_variance");
  p.angular_velocity_variance = m.get_double("angular_velocity_variance");
  p.autostart = m.get_bool("autostart");
  p.takeoff_height = m.get_double("takeoff_height");
  p.takeoff_duration_s = m.get_double("takeoff_duration_s");
  p.land_duration_s = m.get_double("land_duration_s");
  p.max_vertical_speed = m.get_double("max_vertical_speed");
  p.status_vars = m.get_string_array("status_vars");
  p.status_period_ms = m.get_int64("status_period_ms", 10, 65535);
  p.low_battery_v = m.get_double("low_battery_v");
  p.low_battery_hold_s = m.get_double("low_battery_hold_s");
  p.shutdown_land_timeout_s = m.get_double("shutdown_land_timeout_s");
  p.frame_prefix = m.get_string("frame_prefix");
  p.initial_position = m.get_double_array("initial_position");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw tactile_common::ParamError(m.source() + ": " + kNodeName + ": " + e.what());
  }
  return p;
}

CrazyflieBridgeLogic::CrazyflieBridgeLogic(const Params& params) : params_(params) {
  params_.validate();
  namespace frames = tactile_common::frames;
  odom_frame_ = tactile_common::prefixed(params_.frame_prefix, frames::kOdom);
  base_frame_ = tactile_common::prefixed(params_.frame_prefix, frames::kBaseLink);
  whisker_frame_[0] = tactile_common::prefixed(params_.frame_prefix, frames::kWhiskerLeft);
  whisker_frame_[1] = tactile_common::prefixed(params_.frame_prefix, frames::kWhiskerRight);
}

std::vector<tactile_common::StaticFrame> CrazyflieBridgeLogic::static_frames() const {
  tactile_common::RigidTransform map_to_odom;
  for (int i = 0; i < 3; ++i) map_to_odom.xyz[static_cast<size_t>(i)] = params_.initial_position[static_cast<size_t>(i)];
  std::vector<tactile_common::StaticFrame> out{{tactile_common::frames::kMap, odom_frame_, map_to_odom}};
  for (auto& f : tactile_common::static_frames(tactile_sim::robot_model(tactile_sim::CrazyflieParams{}),
                                               params_.frame_prefix)) {
    out.push_back(std::move(f));
  }
  return out;
}

std::string CrazyflieBridgeLogic::robot_description() const {
  return tactile_common::to_urdf(tactile_sim::robot_model(tactile_sim::CrazyflieParams{}), params_.frame_prefix);
}

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

void CrazyflieBridgeLogic::set_status_block(uint8_t block_id, std::vector<std::string> names) {
  status_block_ = block_id;
  status_names_ = std::move(names);
  // Its lost packets are gaps too (log_samples_missed counts every block's).
  clock_.add_block(block_id, static_cast<uint32_t>(params_.status_period_ms));
}

CrazyflieBridgeLogic::LogOutputs CrazyflieBridgeLogic::on_log_sample(const LogSample& s, int64_t now_ns) {
  if (status_block_ >= 0 && s.block_id == status_block_) return on_status_sample(s, now_ns);
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
      m.header.frame_id = whisker_frame_[w];
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
  o.header.frame_id = odom_frame_;
  o.child_frame_id = base_frame_;
  o.pose.pose.position.x = s.values[0];
  o.pose.pose.position.y = s.values[1];
  o.pose.pose.position.z = s.values[2];
  const double yaw = s.values[3] * kDegToRad;
  height_ = s.values[2];
  x_ = s.values[0];
  y_ = s.values[1];
  yaw_ = yaw;
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

CrazyflieBridgeLogic::LogOutputs CrazyflieBridgeLogic::on_status_sample(const LogSample& s, int64_t now_ns) {
  if (s.values.size() != status_names_.size()) {
    ++stats_.dropped_unknown_block;
    return {};
  }
  for (double v : s.values) {
    if (!std::isfinite(v)) {
      ++stats_.dropped_nonfinite;
      return {};
    }
  }
  ++stats_.status_samples;
  const LogClock::Stamp ts = clock_.on_sample(s.block_id, s.timestamp_ms, now_ns);
  stats_.log_samples_missed += ts.missed;
  if (ts.restart) ++stats_.log_clock_restarts;
  for (size_t i = 0; i < status_names_.size(); ++i) {
    const std::string& n = status_names_[i];
    const double v = s.values[i];
    if (n == "pm.vbat") {
      battery_v_ = v;
    } else if (n == "pm.state") {
      pm_state_ = static_cast<int>(v);
    } else if (n == "supervisor.info") {
      supervisor_info_ = static_cast<int>(v);
    } else if (n == "radio.rssi") {
      rssi_ = static_cast<int>(v);
    }
  }
  return {};
}

bool CrazyflieBridgeLogic::log_fresh(int64_t now_ns) const {
  return have_log_ && tactile_common::to_seconds(now_ns - log_ns_) <= params_.log_timeout_s;
}
bool CrazyflieBridgeLogic::setpoint_fresh(int64_t now_ns) const {
  return have_setpoint_ && tactile_common::to_seconds(now_ns - setpoint_ns_) <= params_.setpoint_timeout_s;
}

bool CrazyflieBridgeLogic::airborne() const {
  switch (mode_) {
    case Mode::kTakingOff:
    case Mode::kHovering:
    case Mode::kGoTo:
    case Mode::kForward:
    case Mode::kHoverHold:
    case Mode::kLanding:
      return true;
    case Mode::kGrounded:
    case Mode::kStopped:
    case Mode::kEmergency:
      return false;
  }
  return false;
}

// ---------------------------------------------------------------------------
// Transitions

void CrazyflieBridgeLogic::transition(Mode to, const char* guard, std::string reason, int64_t now_ns) {
  const Mode from = mode_;
  mode_ = to;
  ++stats_.transitions_total;
  ++stats_.transitions[std::string(to_string(from)) + "->" + to_string(to) + ":" + guard];
  if (history_.size() < kMaxHistory) history_.push_back({now_ns, from, to, guard, std::move(reason)});
  enter(to, now_ns);
}

void CrazyflieBridgeLogic::enter(Mode to, int64_t now_ns) {
  switch (to) {
    case Mode::kGrounded:
      emergency_latched_ = false;
      break;
    case Mode::kTakingOff:
    case Mode::kGoTo:
      break;  // the command set ramp_ before the transition
    case Mode::kHovering:
      // Hold the height last commanded, zero velocity.
      hold_height_ = command_.height;
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.land = false;
      break;
    case Mode::kForward:
      handback_ns_ = -1;
      break;
    case Mode::kHoverHold:
      hold_start_ns_ = now_ns;
      ++stats_.stale_events;
      command_.vx = command_.vy = command_.yaw_rate = 0.0;  // hover in place at the last height
      break;
    case Mode::kLanding:
      ++stats_.landings;
      floor_since_ns_ = -1;
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.land = true;
      break;
    case Mode::kStopped:
      stops_sent_ = 0;
      break;
    case Mode::kEmergency:
      emergency_latched_ = true;
      ++stats_.emergency_stops;
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.height = 0.0;
      command_.land = true;
      // The first stop packet leaves at once (the caller sends the outbox),
      // then one every tick.
      outbox_.push_back(commander::stop());
      break;
  }
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::refuse(std::string reason) {
  ++stats_.commands_refused;
  return {false, std::move(reason)};
}
CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::accept(std::string reason) {
  ++stats_.commands_accepted;
  return {true, std::move(reason)};
}

std::vector<CrtpPacket> CrazyflieBridgeLogic::take_outbox() {
  std::vector<CrtpPacket> v(outbox_.begin(), outbox_.end());
  outbox_.clear();
  return v;
}

CrtpPacket CrazyflieBridgeLogic::hover_packet(double vx, double vy, double yaw_rate_rad, double height) const {
  return commander::hover(static_cast<float>(vx), static_cast<float>(vy), static_cast<float>(yaw_rate_rad * kRadToDeg),
                          static_cast<float>(height));
}

bool CrazyflieBridgeLogic::on_the_ground(int64_t now_ns) const {
  if (supervisor_info_ >= 0 && (supervisor_info_ & kIsFlying)) return false;
  return log_fresh(now_ns) && height_ <= params_.land_height;
}

const char* CrazyflieBridgeLogic::touchdown(bool log_is_fresh, int64_t now_ns) const {
  // The commanded height leads the measured one down the ramp (by up to 0.1 m plus the
  // height controller's lag: 0.13 m in the SITL): stopping on the command alone dropped
  // the vehicle the last ~0.1 m. The floor of the command stays landing_target_ (0 unless
  // the land service asked for more), so the vehicle keeps descending meanwhile.
  if (log_is_fresh && height_ <= params_.land_height) return "measured height at land_height";
  if (floor_since_ns_ < 0) return nullptr;
  if (!log_is_fresh) return "commanded height at land_height, no fresh log";
  if (tactile_common::to_seconds(now_ns - floor_since_ns_) >= params_.touchdown_timeout_s) {
    return "commanded height at land_height for touchdown_timeout_s, measured height still above";
  }
  return nullptr;
}

bool CrazyflieBridgeLogic::low_battery(int64_t now_ns) {
  const bool in_flight = mode_ == Mode::kTakingOff || mode_ == Mode::kHovering || mode_ == Mode::kGoTo ||
                         mode_ == Mode::kForward || mode_ == Mode::kHoverHold;
  if (!in_flight || !std::isfinite(battery_v_) || battery_v_ >= params_.low_battery_v) {
    low_batt_since_ns_ = -1;
    return false;
  }
  if (low_batt_since_ns_ < 0) low_batt_since_ns_ = now_ns;
  return tactile_common::to_seconds(now_ns - low_batt_since_ns_) >= params_.low_battery_hold_s;
}

namespace {
std::string fmt(double v, int digits = 2) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}
/// Ramp progress in [0, 1].
double progress(int64_t start_ns, double duration_s, int64_t now_ns) {
  if (duration_s <= 0.0) return 1.0;
  return std::clamp(tactile_common::to_seconds(now_ns - start_ns) / duration_s, 0.0, 1.0);
}
}  // namespace

// ---------------------------------------------------------------------------
// Timer: guards first, then the mode's output.

std::optional<CrtpPacket> CrazyflieBridgeLogic::on_timer(int64_t now_ns) {
  const double dt = last_timer_ns_ > 0 ? tactile_common::to_seconds(now_ns - last_timer_ns_) : 1.0 / params_.setpoint_rate_hz;
  last_timer_ns_ = now_ns;
  const bool sp_fresh = setpoint_fresh(now_ns);
  const bool lg_fresh = log_fresh(now_ns);
  switch (mode_) {
    case Mode::kGrounded:
      if (params_.autostart && sp_fresh && lg_fresh) {
        transition(Mode::kForward, "autostart", "autostart: setpoints and log data fresh", now_ns);
      }
      break;
    case Mode::kTakingOff:
      if (ramp_done_) {  // the ramp's last setpoint was sent on the previous tick
        command_.height = ramp_.z1;
        transition(Mode::kHovering, "takeoff_done", "reached " + fmt(ramp_.z1) + " m", now_ns);
      }
      break;
    case Mode::kGoTo:
      if (ramp_done_) {
        command_.height = ramp_.z1;
        transition(Mode::kHovering, "goto_done", "reached (" + fmt(ramp_.x1) + ", " + fmt(ramp_.y1) + ", " + fmt(ramp_.z1) + ")",
                   now_ns);
      }
      break;
    case Mode::kForward:
      if (handback_ns_ >= 0) {
        if (now_ns >= handback_ns_) {
          transition(Mode::kHovering, "notify_setpoints_stop", "hand-back: last setpoint's validity ran out", now_ns);
        }
      } else if (!sp_fresh || !lg_fresh) {
        transition(Mode::kHoverHold, "stale", !sp_fresh ? "setpoints stale" : "log data stale", now_ns);
      }
      break;
    case Mode::kHoverHold:
      if (sp_fresh && lg_fresh) {
        transition(Mode::kForward, "fresh_again", "setpoints and log data fresh again", now_ns);
      } else if (tactile_common::to_seconds(now_ns - hold_start_ns_) >= params_.hover_hold_s) {
        landing_speed_ = params_.land_speed;
        landing_target_ = 0.0;
        transition(Mode::kLanding, "hold_expired", "stale for hover_hold_s = " + fmt(params_.hover_hold_s) + " s", now_ns);
      }
      break;
    case Mode::kHovering:  // leaves on a command, low battery (below) or lost telemetry (below)
    case Mode::kLanding:   // touchdown is decided with the output below
    case Mode::kStopped:
    case Mode::kEmergency:
      break;
  }
  // Lost telemetry in the operator's modes. They fly on the firmware's own estimate, but a
  // ground station that no longer hears the vehicle sees neither its height nor its
  // battery: a go-to stops where it is at once (log_stale), and after hover_hold_s more of
  // stale log data the vehicle lands (log_lost), as the behaviour's safety chain does.
  if (mode_ == Mode::kGoTo && !lg_fresh) {
    transition(Mode::kHovering, "log_stale", "log data stale during a go-to: hover in place", now_ns);
  }
  if ((mode_ == Mode::kTakingOff || mode_ == Mode::kHovering) && !lg_fresh &&
      tactile_common::to_seconds(now_ns - log_ns_) >= params_.log_timeout_s + params_.hover_hold_s) {
    landing_speed_ = params_.land_speed;
    landing_target_ = 0.0;
    transition(Mode::kLanding, "log_lost",
               "no log data for " + fmt(tactile_common::to_seconds(now_ns - log_ns_)) + " s (log_timeout_s + hover_hold_s)",
               now_ns);
  }
  if (low_battery(now_ns)) {
    ++stats_.low_battery_events;
    landing_speed_ = params_.land_speed;
    landing_target_ = 0.0;
    transition(Mode::kLanding, "low_battery",
               "battery " + fmt(battery_v_) + " V < low_battery_v " + fmt(params_.low_battery_v) + " V for " +
                   fmt(params_.low_battery_hold_s) + " s",
               now_ns);
  }

  std::optional<CrtpPacket> pk;
  switch (mode_) {
    case Mode::kGrounded:
      return std::nullopt;  // nothing is sent to the motors on the ground
    case Mode::kTakingOff: {
      const double f = progress(ramp_.start_ns, ramp_.duration_s, now_ns);
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.land = false;
      command_.height = ramp_.z0 + (ramp_.z1 - ramp_.z0) * f;
      ramp_done_ = f >= 1.0;
      pk = hover_packet(0.0, 0.0, 0.0, command_.height);
      break;
    }
    case Mode::kHovering:
      command_.height = hold_height_;
      pk = hover_packet(0.0, 0.0, 0.0, hold_height_);
      break;
    case Mode::kGoTo: {
      const double f = progress(ramp_.start_ns, ramp_.duration_s, now_ns);
      const double x = ramp_.x0 + (ramp_.x1 - ramp_.x0) * f;
      const double y = ramp_.y0 + (ramp_.y1 - ramp_.y0) * f;
      const double z = ramp_.z0 + (ramp_.z1 - ramp_.z0) * f;
      const double yaw = ramp_.yaw0 + (ramp_.yaw1 - ramp_.yaw0) * f;
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.height = z;
      ramp_done_ = f >= 1.0;
      pk = commander::position(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z),
                               static_cast<float>(yaw * kRadToDeg));
      break;
    }
    case Mode::kForward:
      if (handback_ns_ < 0) command_ = setpoint_;  // during a hand-back the last setpoint stays valid
      if (command_.land) {
        command_.height = height_;
        landing_speed_ = params_.land_speed;
        landing_target_ = 0.0;
        transition(Mode::kLanding, "behaviour_land", "the behaviour asked to land", now_ns);
      } else {
        pk = hover_packet(command_.vx, command_.vy, command_.yaw_rate, command_.height);
        break;
      }
      [[fallthrough]];
    case Mode::kLanding:
      command_.vx = command_.vy = command_.yaw_rate = 0.0;
      command_.land = true;
      command_.height = std::max(landing_target_, std::min(command_.height, height_ + 0.1) - landing_speed_ * dt);
      if (command_.height <= params_.land_height && floor_since_ns_ < 0) floor_since_ns_ = now_ns;
      if (const char* why = touchdown(lg_fresh, now_ns)) {
        transition(Mode::kStopped, "touchdown", why, now_ns);
        pk = commander::stop();
      } else {
        pk = hover_packet(0.0, 0.0, 0.0, command_.height);
      }
      break;
    case Mode::kHoverHold:
      pk = hover_packet(0.0, 0.0, 0.0, command_.height);
      break;
    case Mode::kStopped:
      // Stop is repeated a few times (a lost packet must not leave the motors
      // on), then nothing: the firmware keeps them off.
      if (stops_sent_ >= kStopRepeats) return std::nullopt;
      pk = commander::stop();
      break;
    case Mode::kEmergency:
      pk = commander::stop();  // every tick until arm(true) on the ground
      break;
  }
  if (pk) pk = commander::for_protocol(*pk, protocol_version_);  // cflib's packet for this firmware generation
  if (pk && mode_ == Mode::kStopped && commander::decode(*pk).kind == commander::Setpoint::Kind::kStop) ++stops_sent_;
  ++stats_.packets_out;
  return pk;
}

// ---------------------------------------------------------------------------
// Operator commands

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::arm(bool on, int64_t now_ns) {
  const char* what = on ? "arm" : "disarm";
  if (airborne()) {
    return refuse(std::string(what) + " refused: airborne (mode " + to_string(mode_) + "); use land or emergency_stop");
  }
  if (on && mode_ == Mode::kEmergency && !on_the_ground(now_ns)) {
    return refuse("arm refused: emergency latched and the vehicle is not confirmed on the ground (" +
                  std::string(log_fresh(now_ns) ? "measured height " + fmt(height_) + " m > land_height" : "no fresh state estimate") +
                  (supervisor_info_ >= 0 && (supervisor_info_ & kIsFlying) ? ", supervisor says flying" : "") + ")");
  }
  arm_requested_ = on;
  outbox_.push_back(arming::request(on, protocol_version_));
  std::string reason = std::string(what) + " request sent (" +
                       (protocol_version_ >= arming::kSupervisorProtocolVersion ? "supervisor port" : "legacy platform port") + ")";
  if (supervisor_info_ < 0) reason += "; firmware logs no supervisor.info: arming state cannot be confirmed";
  if (on && mode_ == Mode::kEmergency) {
    transition(Mode::kGrounded, "arm", "arm(true) on the ground clears the emergency latch", now_ns);
    reason += "; emergency latch cleared";
  }
  return accept(reason);
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::takeoff(double height_m, double duration_s, int64_t now_ns) {
  if (mode_ != Mode::kGrounded && mode_ != Mode::kStopped) {
    return refuse(std::string("takeoff refused: mode is ") + to_string(mode_) +
                  (mode_ == Mode::kEmergency ? " (emergency latched: arm(true) on the ground first)" : ""));
  }
  if (!std::isfinite(height_m) || height_m <= params_.land_height || height_m > params_.max_height ||
      height_m < params_.min_height) {
    return refuse("takeoff refused: height " + fmt(height_m) + " m outside (land_height " + fmt(params_.land_height) +
                  ", max_height " + fmt(params_.max_height) + "] m");
  }
  if (!std::isfinite(duration_s) || duration_s <= 0.0) return refuse("takeoff refused: duration " + fmt(duration_s) + " s must be > 0");
  if (!log_fresh(now_ns)) return refuse("takeoff refused: no fresh state estimate (log data stale or never received)");
  const double z0 = std::max(0.0, height_);
  if ((height_m - z0) / duration_s > params_.max_vertical_speed) {
    return refuse("takeoff refused: " + fmt(height_m - z0) + " m in " + fmt(duration_s) + " s exceeds max_vertical_speed " +
                  fmt(params_.max_vertical_speed) + " m/s");
  }
  if (std::isfinite(battery_v_) && battery_v_ < params_.low_battery_v) {
    return refuse("takeoff refused: battery " + fmt(battery_v_) + " V < low_battery_v " + fmt(params_.low_battery_v) + " V");
  }
  if (supervisor_info_ >= 0) {
    if (supervisor_info_ & (kIsTumbled | kIsLocked)) {
      return refuse("takeoff refused: supervisor.info " + std::to_string(supervisor_info_) +
                    ((supervisor_info_ & kIsLocked) ? " (locked: restart the Crazyflie)" : " (tumbled)"));
    }
    if (!(supervisor_info_ & kIsArmed)) {
      return refuse("takeoff refused: not armed (supervisor.info " + std::to_string(supervisor_info_) + "): call arm(true) first");
    }
  }
  ramp_ = Ramp{};
  ramp_.x0 = ramp_.x1 = x_;
  ramp_.y0 = ramp_.y1 = y_;
  ramp_.yaw0 = ramp_.yaw1 = yaw_;
  ramp_.z0 = z0;
  ramp_.z1 = height_m;
  ramp_.start_ns = now_ns;
  ramp_.duration_s = duration_s;
  ramp_done_ = false;
  command_ = tactile_msgs::msg::HoverSetpoint{};
  command_.height = z0;
  const std::string r = "takeoff to " + fmt(height_m) + " m in " + fmt(duration_s) + " s";
  transition(Mode::kTakingOff, "takeoff", r, now_ns);
  return accept(r);
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::land(double height_m, double duration_s, int64_t now_ns) {
  if (!airborne()) return refuse(std::string("land refused: not airborne (mode ") + to_string(mode_) + ")");
  if (mode_ == Mode::kLanding) return refuse("land refused: already landing");
  if (!std::isfinite(height_m) || height_m < 0.0 || height_m > params_.land_height) {
    return refuse("land refused: height " + fmt(height_m) + " m outside [0, land_height " + fmt(params_.land_height) +
                  "] m (the motors stop at land_height)");
  }
  if (!std::isfinite(duration_s) || duration_s <= 0.0) return refuse("land refused: duration " + fmt(duration_s) + " s must be > 0");
  const double z0 = std::min(command_.height, height_ + 0.1);
  // Descent speed from the height to go and the duration, bounded: never
  // faster than max_vertical_speed, never slower than land_speed / 4.
  landing_speed_ = std::clamp(std::max(z0 - height_m, 0.0) / duration_s, params_.land_speed / 4, params_.max_vertical_speed);
  landing_target_ = height_m;
  const std::string r = "land to " + fmt(height_m) + " m in " + fmt(duration_s) + " s (" + fmt(landing_speed_) + " m/s)";
  transition(Mode::kLanding, "land", r, now_ns);
  return accept(r);
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::go_to(double x, double y, double z, double yaw_rad, double duration_s,
                                                                bool relative, int64_t now_ns) {
  if (mode_ != Mode::kHovering && mode_ != Mode::kGoTo) {
    return refuse(std::string("go_to refused: mode is ") + to_string(mode_) + " (allowed from hovering / go_to)");
  }
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(yaw_rad)) {
    return refuse("go_to refused: non-finite goal");
  }
  if (!std::isfinite(duration_s) || duration_s <= 0.0) return refuse("go_to refused: duration " + fmt(duration_s) + " s must be > 0");
  if (!log_fresh(now_ns)) return refuse("go_to refused: no fresh state estimate");
  Ramp r;
  r.x0 = x_;
  r.y0 = y_;
  r.z0 = command_.height;
  r.yaw0 = yaw_;
  r.x1 = relative ? x_ + x : x;
  r.y1 = relative ? y_ + y : y;
  r.z1 = relative ? command_.height + z : z;
  r.yaw1 = relative ? yaw_ + yaw_rad : yaw_rad;
  if (r.z1 <= params_.land_height || r.z1 > params_.max_height || r.z1 < params_.min_height) {
    return refuse("go_to refused: z " + fmt(r.z1) + " m outside (land_height, max_height " + fmt(params_.max_height) + "] m");
  }
  const double horiz = std::hypot(r.x1 - r.x0, r.y1 - r.y0) / duration_s;
  if (horiz > params_.max_velocity) {
    return refuse("go_to refused: " + fmt(horiz) + " m/s horizontal exceeds max_velocity " + fmt(params_.max_velocity) +
                  " m/s (longer duration)");
  }
  if (std::abs(r.z1 - r.z0) / duration_s > params_.max_vertical_speed) {
    return refuse("go_to refused: vertical speed exceeds max_vertical_speed " + fmt(params_.max_vertical_speed) + " m/s");
  }
  if (std::abs(r.yaw1 - r.yaw0) / duration_s > params_.max_yaw_rate) {
    return refuse("go_to refused: yaw rate exceeds max_yaw_rate " + fmt(params_.max_yaw_rate) + " rad/s");
  }
  r.start_ns = now_ns;
  r.duration_s = duration_s;
  ramp_ = r;
  ramp_done_ = false;
  const std::string why = "go_to (" + fmt(r.x1) + ", " + fmt(r.y1) + ", " + fmt(r.z1) + ") yaw " + fmt(r.yaw1) + " rad in " +
                          fmt(duration_s) + " s";
  transition(Mode::kGoTo, "go_to", why, now_ns);
  return accept(why);
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::start_behaviour(int64_t now_ns) {
  if (mode_ != Mode::kHovering) {
    return refuse(std::string("start_behaviour refused: mode is ") + to_string(mode_) + " (allowed from hovering)");
  }
  if (!setpoint_fresh(now_ns)) {
    return refuse(std::string("start_behaviour refused: no fresh ") + kSetpointTopic + " setpoint (" +
                  (have_setpoint_ ? "last " + fmt(tactile_common::to_seconds(now_ns - setpoint_ns_)) + " s ago" : "none yet") + ")");
  }
  if (!log_fresh(now_ns)) return refuse("start_behaviour refused: log data stale");
  transition(Mode::kForward, "start_behaviour", "hand-over to the behaviour", now_ns);
  return accept("hand-over: forwarding the behaviour's setpoints");
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::notify_setpoints_stop(uint32_t remain_valid_ms, int64_t now_ns) {
  if (mode_ == Mode::kHoverHold) {
    transition(Mode::kHovering, "notify_setpoints_stop", "hand-back while holding", now_ns);
    return accept("hand-back: hovering");
  }
  if (mode_ != Mode::kForward) {
    return refuse(std::string("notify_setpoints_stop refused: mode is ") + to_string(mode_) + " (allowed from forward)");
  }
  if (handback_ns_ >= 0) return refuse("notify_setpoints_stop refused: a hand-back is already pending");
  // The last setpoint stays valid for remain_valid_ms (hover height and
  // velocity held), bounded by the stale timeout's hover_hold_s.
  const double remain_s = std::min(remain_valid_ms / 1000.0, params_.hover_hold_s);
  handback_ns_ = now_ns + static_cast<int64_t>(remain_s * 1e9);
  command_ = setpoint_;
  command_.vx = command_.vy = command_.yaw_rate = 0.0;  // the held setpoint does not move the vehicle
  return accept("hand-back in " + fmt(remain_s, 3) + " s");
}

CrazyflieBridgeLogic::CommandResult CrazyflieBridgeLogic::emergency_stop(int64_t now_ns) {
  if (mode_ == Mode::kEmergency) {
    outbox_.push_back(commander::stop());
    return accept("emergency stop (already latched): stop sent again");
  }
  transition(Mode::kEmergency, "emergency_stop", std::string("operator emergency stop in ") + to_string(mode_), now_ns);
  return accept("emergency stop: motors off, latched until arm(true) on the ground");
}

CrazyflieBridgeLogic::Status CrazyflieBridgeLogic::status(int64_t now_ns) const {
  Status st;
  st.mode = mode_;
  st.armed = supervisor_info_ >= 0 ? (supervisor_info_ & kIsArmed) != 0 : arm_requested_;
  st.emergency_latched = emergency_latched_;
  st.battery_v = battery_v_;
  st.pm_state = pm_state_;
  st.supervisor_info = supervisor_info_;
  st.rssi_dbm = rssi_;
  st.setpoint_age_s = have_setpoint_ ? tactile_common::to_seconds(now_ns - setpoint_ns_) : NAN;
  st.log_age_s = have_log_ ? tactile_common::to_seconds(now_ns - log_ns_) : NAN;
  st.low_battery_events = stats_.low_battery_events;
  return st;
}

}  // namespace crazyflie_bridge
