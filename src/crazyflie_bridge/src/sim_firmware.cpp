#include "crazyflie_bridge/sim_firmware.hpp"

#include <algorithm>
#include <cmath>

#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace crazyflie_bridge {

namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kDegToRad = M_PI / 180.0;

/// Body vector rotated to the world frame by q.
void rotate(const geometry_msgs::msg::Quaternion& q, double bx, double by, double bz, double out[3]) {
  const double w = q.w, x = q.x, y = q.y, z = q.z;
  out[0] = (1 - 2 * (y * y + z * z)) * bx + 2 * (x * y - w * z) * by + 2 * (x * z + w * y) * bz;
  out[1] = 2 * (x * y + w * z) * bx + (1 - 2 * (x * x + z * z)) * by + 2 * (y * z - w * x) * bz;
  out[2] = 2 * (x * z - w * y) * bx + 2 * (y * z + w * x) * by + (1 - 2 * (x * x + y * y)) * bz;
}
}  // namespace

SimulatedCrazyflieFirmware::SimulatedCrazyflieFirmware(double loss_rate)
    : SimulatedCrazyflieFirmware([loss_rate] {
        Options o;
        o.loss_rate = loss_rate;
        return o;
      }()) {}

namespace {
FirmwareEmulator::Options emulator_options(const SimulatedCrazyflieFirmware::Options& o) {
  FirmwareEmulator::Options e;
  e.auto_arm = !o.require_arming;
  return e;
}
}  // namespace

SimulatedCrazyflieFirmware::SimulatedCrazyflieFirmware(const Options& options)
    : fw_(emulator_options(options)), opt_(options) {
  using logp::Type;
  const double loss_rate = options.loss_rate;
  id_left_ = fw_.add_log_variable("Whisker", "Barometer1_1", Type::kFloat);
  fw_.add_log_variable("Whisker", "Barometer1_2", Type::kFloat);
  fw_.add_log_variable("Whisker", "Barometer1_3", Type::kFloat);
  id_right_ = fw_.add_log_variable("Whisker1", "Barometer2_1", Type::kFloat);
  fw_.add_log_variable("Whisker1", "Barometer2_2", Type::kFloat);
  fw_.add_log_variable("Whisker1", "Barometer2_3", Type::kFloat);
  id_state_ = fw_.add_log_variable("stateEstimate", "x", Type::kFloat);
  for (const char* n : {"y", "z", "yaw", "vx", "vy", "vz"}) fw_.add_log_variable("stateEstimate", n, Type::kFloat);
  id_vbat_ = fw_.add_log_variable("pm", "vbat", Type::kFloat);
  fw_.set_log_value(id_vbat_, opt_.vbat_full);
  id_truth_ = fw_.add_log_variable("sitl", "truthX", Type::kFloat);
  fw_.add_log_variable("sitl", "truthY", Type::kFloat);
  fw_.add_log_variable("sitl", "truthZ", Type::kFloat);
  if (opt_.status_log) {
    // Types as the firmware logs them (pm.state int8, supervisor.info uint16,
    // radio.rssi uint8).
    id_pm_state_ = fw_.add_log_variable("pm", "state", Type::kInt8);
    id_supervisor_ = fw_.add_log_variable("supervisor", "info", Type::kUint16);
    id_rssi_ = fw_.add_log_variable("radio", "rssi", Type::kUint8);
    fw_.set_log_value(static_cast<uint16_t>(id_rssi_), opt_.rssi_dbm);
    fw_.set_log_value(static_cast<uint16_t>(id_supervisor_), fw_.supervisor_info(0));
  }
  fw_.add_param("deck", "bcWhisker", param::kUint8, 1, true);
  fw_.add_param("commander", "enHighLevel", param::kUint8, 0, false);
  p_stop_ = fw_.add_param("stabilizer", "stop", param::kUint8, 0, false);
  p_loss_ = fw_.add_param("sitl", "lossPct", param::kUint8, std::round(loss_rate * 100.0), false);
}

double SimulatedCrazyflieFirmware::battery_voltage() const {
  return std::isfinite(vbat_override_) ? vbat_override_ : opt_.vbat_full - opt_.vbat_drain_v_per_s * motors_on_s_;
}

double SimulatedCrazyflieFirmware::loss_rate() const { return std::clamp(fw_.param_value(p_loss_) / 100.0, 0.0, 0.99); }

void SimulatedCrazyflieFirmware::on_pressure(const tactile_msgs::msg::WhiskerPressure& m) {
  const uint16_t base = m.whisker_id == tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT ? id_left_ : id_right_;
  for (uint16_t i = 0; i < 3; ++i) fw_.set_log_value(static_cast<uint16_t>(base + i), m.pressure[i]);
}

void SimulatedCrazyflieFirmware::on_estimate(const nav_msgs::msg::Odometry& o) {
  const auto& pose = o.pose.pose;
  yaw_ = tactile_common::yaw_of(pose.orientation);
  double vw[3];
  rotate(pose.orientation, o.twist.twist.linear.x, o.twist.twist.linear.y, o.twist.twist.linear.z, vw);
  const double vals[7] = {pose.position.x, pose.position.y, pose.position.z, yaw_ * kRadToDeg, vw[0], vw[1], vw[2]};
  for (uint16_t i = 0; i < 7; ++i) fw_.set_log_value(static_cast<uint16_t>(id_state_ + i), vals[i]);
}

void SimulatedCrazyflieFirmware::on_truth(const nav_msgs::msg::Odometry& o) {
  fw_.set_log_value(id_truth_, o.pose.pose.position.x);
  fw_.set_log_value(static_cast<uint16_t>(id_truth_ + 1), o.pose.pose.position.y);
  fw_.set_log_value(static_cast<uint16_t>(id_truth_ + 2), o.pose.pose.position.z);
}

SimulatedCrazyflieFirmware::Command SimulatedCrazyflieFirmware::command(int64_t now_ns, double dt) {
  using Mode = FirmwareEmulator::CommanderOutput::Mode;
  using Kind = commander::Setpoint::Kind;
  Command out;
  const auto now_ms = static_cast<uint32_t>(now_ns / 1000000);
  auto c = fw_.commander(now_ms);
  if (fw_.param_value(p_stop_) != 0) c.mode = Mode::kShutdown;
  // Status log: battery model, power state, supervisor.
  if (fw_.motors_on(now_ms) && fw_.param_value(p_stop_) == 0) motors_on_s_ += dt;
  const double vbat = battery_voltage();
  fw_.set_log_value(id_vbat_, vbat);
  if (id_pm_state_ >= 0) {
    // pm.state: 0 battery, 3 low power below PM_BAT_LOW_VOLTAGE 3.2 V (pm_stm32f4.c).
    fw_.set_log_value(static_cast<uint16_t>(id_pm_state_), vbat < 3.2 ? 3 : 0);
    fw_.set_log_value(static_cast<uint16_t>(id_supervisor_), fw_.supervisor_info(now_ms));
  }
  tactile_msgs::msg::HoverSetpoint hs;
  tactile_common::to_stamp(now_ns, hs.header.stamp);
  switch (c.mode) {
    case Mode::kIdle:
      return out;  // motors off until the first setpoint
    case Mode::kSetpoint: {
      const auto& s = c.setpoint;
      if (s.kind == Kind::kHover) {
        hs.vx = s.a;
        hs.vy = s.b;
        hs.yaw_rate = s.c * kDegToRad;  // type 10: deg/s, CCW positive
        hs.height = s.d;
        height_cmd_ = s.d;
        hs.land = hs.height <= 0.0;
      } else if (s.kind == Kind::kVelocityWorld) {
        // World velocity -> body-yaw frame; vz integrates the height setpoint.
        hs.vx = std::cos(yaw_) * s.a + std::sin(yaw_) * s.b;
        hs.vy = -std::sin(yaw_) * s.a + std::cos(yaw_) * s.b;
        height_cmd_ = std::max(0.0, height_cmd_ + s.c * dt);
        hs.height = height_cmd_;
        hs.yaw_rate = s.d * kDegToRad;
      } else if (s.kind == Kind::kPosition) {
        geometry_msgs::msg::PoseStamped ps;
        ps.header.stamp = hs.header.stamp;
        ps.pose.position.x = s.a;
        ps.pose.position.y = s.b;
        ps.pose.position.z = s.c;
        ps.pose.orientation.z = std::sin(s.d * kDegToRad / 2);
        ps.pose.orientation.w = std::cos(s.d * kDegToRad / 2);
        height_cmd_ = s.c;
        out.position = ps;
        return out;
      }
      break;
    }
    case Mode::kStabilize:
      hs.height = height_cmd_;  // level out: zero velocity, hold the height
      break;
    case Mode::kShutdown:
      hs.land = true;  // motors off (the simulated vehicle descends and stops)
      hs.height = 0.0;
      break;
  }
  out.hover = hs;
  return out;
}

}  // namespace crazyflie_bridge
