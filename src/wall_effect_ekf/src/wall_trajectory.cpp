#include "wall_effect_ekf/wall_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "tactile_common/frames.hpp"
#include "tactile_common/time.hpp"

namespace wall_effect_ekf {

namespace {
void pos_check(const char* f, double v) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument(std::string("TrajectoryParams.") + f + ": must be finite and > 0, got " + std::to_string(v));
}
}  // namespace

int sweep_segment(const TrajectoryParams& p, double t) {
  if (t < p.t_start) return -1;
  const auto k = static_cast<size_t>((t - p.t_start) / p.sweep_hold_s);
  return k < p.sweep_distances.size() ? static_cast<int>(k) : -1;
}

void TrajectoryParams::validate() const {
  if (mode != "estimation_flight" && mode != "hold" && mode != "sweep")
    throw std::invalid_argument("TrajectoryParams.mode: must be 'estimation_flight', 'hold' or 'sweep', got '" + mode + "'");
  pos_check("sweep_hold_s", sweep_hold_s);
  tactile_common::validate_frame_prefix(frame_prefix, "TrajectoryParams.frame_prefix");
  if (sweep_distances.empty()) throw std::invalid_argument("TrajectoryParams.sweep_distances: must not be empty");
  for (double d : sweep_distances) pos_check("sweep_distances", d);
  auto pos = [](const char* f, double v) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("TrajectoryParams.") + f + ": must be finite and > 0, got " + std::to_string(v));
  };
  // Not range-checked, but each must be finite: a NaN x is a NaN setpoint position, which the
  // INDI controller takes as a velocity-only axis; a NaN frequency or yaw a NaN y_d or psi_d.
  auto finite = [](const char* f, double v) {
    if (!std::isfinite(v))
      throw std::invalid_argument(std::string("TrajectoryParams.") + f + ": must be finite, got " + std::to_string(v));
  };
  finite("x", x);
  finite("angular_frequency", angular_frequency);
  finite("yaw_deg", yaw_deg);
  pos("start_y", start_y);
  pos("height", height);
  pos("wall_distance", wall_distance);
  pos("yaw_ramp_s", yaw_ramp_s);
  if (!(amplitude >= 0.0 && amplitude < wall_distance))
    throw std::invalid_argument("TrajectoryParams.amplitude: must be in [0, wall_distance), got " + std::to_string(amplitude));
  if (!(t_start >= 0.0 && t_sine >= t_start && t_sine_end >= t_sine && t_yaw1 >= t_start && t_yaw2 >= t_yaw1))
    throw std::invalid_argument("TrajectoryParams.t_start: times must be ordered t_start <= t_sine <= t_sine_end, t_start <= t_yaw1 <= t_yaw2");
}

TrajectorySetpoint trajectory_setpoint(const TrajectoryParams& p, double t) {
  TrajectorySetpoint s;
  const double yaw0 = p.yaw_deg * M_PI / 180.0;
  s.yaw = yaw0;
  if (t < p.t_start) {  // take off at the start point
    s.position = Vec3(p.x, p.start_y, p.height);
    return s;
  }
  s.position = Vec3(p.x, p.wall_distance, p.height);
  if (p.mode == "hold") return s;
  if (p.mode == "sweep") {
    const int k = sweep_segment(p, t);
    s.position.y() = k >= 0 ? p.sweep_distances[static_cast<size_t>(k)] : p.start_y;
    return s;
  }
  auto sine = [&](double t0, double t1) {
    if (t >= t0 && t < t1) {
      const double w = p.angular_frequency;
      s.position.y() = p.wall_distance - p.amplitude * std::sin(w * (t - t0));  // 004: 0.18 - 0.03 sin(t - 25)
      s.velocity.y() = -p.amplitude * w * std::cos(w * (t - t0));
    }
  };
  sine(p.t_sine, p.t_sine_end);
  // Between the ramps the sinusoid repeats (004: "in between ... repeated").
  const double hold_start = p.t_yaw1 + p.yaw_ramp_s;
  sine(hold_start, std::min(hold_start + (p.t_sine_end - p.t_sine), p.t_yaw2));
  auto ramp = [&](double t0) { return std::clamp((t - t0) / p.yaw_ramp_s, 0.0, 1.0); };
  s.yaw = yaw0 - M_PI / 2.0 * (ramp(p.t_yaw1) + ramp(p.t_yaw2));
  s.yaw = std::atan2(std::sin(s.yaw), std::cos(s.yaw));
  return s;
}

tactile_common::ParamMap WallTrajectoryLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::paper;
  using tactile_common::positive;
  const TrajectoryParams d;
  const double inf = std::numeric_limits<double>::infinity();
  const tactile_common::ParamRange any_finite{-inf, inf, true, true};
  tactile_common::ParamMap m(kNodeName, "defaults");
  // The setpoint script's parameter spec: value, description (from the TrajectoryParams
  // comments and the protocol in wall_trajectory.hpp), unit, the range validate() takes for
  // the key alone (the times' order and amplitude < wall_distance are named in the
  // descriptions), and none live: the script is fixed at start, so `ros2 param set` refuses
  // every key (read-only). x, angular_frequency and yaw_deg are not range-checked, only
  // finite: (-inf, inf).
  m.set("mode", d.mode,
        {"setpoint script: estimation_flight (004 Fig. 4a), hold or sweep (004 Fig. 5)", "", {}, false,
         paper("004 Fig. 4a (estimation_flight), Fig. 5 (sweep)")});
  m.set("x", d.x, {"position along the wall; finite", "m", any_finite, false, choice()});
  m.set("start_y", d.start_y, {"take-off distance from the wall (004: ~40 cm)", "m", positive(), false,
        paper("004 Fig. 4a: ~40 cm")});
  m.set("height", d.height, {"flight height (004: 1.0 m)", "m", positive(), false, paper("004 Fig. 4a: 1.0 m")});
  m.set("wall_distance", d.wall_distance, {"y_d from t_start (004: 18 cm)", "m", positive(), false,
        paper("004 Fig. 4a: 18 cm")});
  m.set("amplitude", d.amplitude,
        {"amplitude of the sinusoid in y_d (004: 0.03 m); < wall_distance", "m", at_least(0.0), false,
         paper("004 Fig. 4a: 0.18 - 0.03 sin(t - 25)")});
  m.set("angular_frequency", d.angular_frequency,
        {"w of the sinusoid sin(w (t - t0)) (004: sin(t - 25)); finite", "rad/s", any_finite, false,
         paper("004 Fig. 4a: sin(t - 25)")});
  m.set("t_start", d.t_start,
        {"take-off until then, then y_d = wall_distance (004: 5 s); t_start <= t_sine, t_start <= t_yaw1", "s",
         at_least(0.0), false, paper("004 Fig. 4a: 5 s")});
  m.set("t_sine", d.t_sine, {"the sinusoid starts (004: 25 s); t_start <= t_sine <= t_sine_end", "s",
                             at_least(0.0), false, paper("004 Fig. 4a: 25 s")});
  // validate() takes an infinite t_sine_end or t_yaw2 (never: the sinusoid does not end, there
  // is no second ramp); their ranges keep it: [0, inf].
  const tactile_common::ParamRange up_to_inf{0.0, inf, false, false};
  m.set("t_sine_end", d.t_sine_end,
        {"the sinusoid ends (004: 41 s); >= t_sine; inf: never", "s", up_to_inf, false, paper("004 Fig. 4a: 41 s")});
  m.set("t_yaw1", d.t_yaw1, {"the first -90 deg yaw ramp starts (004: 41 s); t_start <= t_yaw1 <= t_yaw2", "s",
                             at_least(0.0), false, paper("004 Fig. 4a: 41 s")});
  m.set("t_yaw2", d.t_yaw2,
        {"the second -90 deg yaw ramp starts (004: 66 s); >= t_yaw1; inf: no second ramp", "s", up_to_inf, false,
         paper("004 Fig. 4a: 66 s")});
  m.set("yaw_ramp_s", d.yaw_ramp_s,
        {"duration of each 90 deg yaw ramp (choice: 004's \"90 deg in 30 s\" would overlap the ramps)", "s",
         positive(), false, choice()});
  m.set("yaw_deg", d.yaw_deg,
        {"psi_d of hold and sweep, and before the ramps (004: 0); finite", "deg", any_finite, false,
         paper("004 Fig. 4a: 0")});
  m.set("sweep_distances", d.sweep_distances,
        {"y_d of the sweep segments, not empty, each finite and > 0 (004 Fig. 5: 13 to 23 cm)", "m", {}, false,
         paper("004 Fig. 5: 13 to 23 cm")});
  m.set("sweep_hold_s", d.sweep_hold_s, {"hold of each sweep segment (004: 60 s)", "s", positive(), false,
        paper("004 Fig. 5: 60 s per setpoint")});
  m.set("frame_prefix", d.frame_prefix,
        {"the setpoints are in <prefix>odom (REP 105): \"\" or a relative name ending in '/' (cf1/)", "", {},
         false, choice("REP 105")});
  return m;
}

TrajectoryParams WallTrajectoryLogic::params_from(const tactile_common::ParamMap& m) {
  TrajectoryParams p;
  p.mode = m.get_string("mode");
  p.x = m.get_double("x");
  p.start_y = m.get_double("start_y");
  p.height = m.get_double("height");
  p.wall_distance = m.get_double("wall_distance");
  p.amplitude = m.get_double("amplitude");
  p.angular_frequency = m.get_double("angular_frequency");
  p.t_start = m.get_double("t_start");
  p.t_sine = m.get_double("t_sine");
  p.t_sine_end = m.get_double("t_sine_end");
  p.t_yaw1 = m.get_double("t_yaw1");
  p.t_yaw2 = m.get_double("t_yaw2");
  p.yaw_ramp_s = m.get_double("yaw_ramp_s");
  p.yaw_deg = m.get_double("yaw_deg");
  p.sweep_distances = m.get_double_array("sweep_distances");
  p.sweep_hold_s = m.get_double("sweep_hold_s");
  p.frame_prefix = m.get_string("frame_prefix");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const std::string field = what.substr(0, what.find(':'));
    throw m.error(field.substr(field.rfind('.') + 1), what);
  }
  return p;
}

WallTrajectoryLogic::WallTrajectoryLogic(const TrajectoryParams& p) : p_(p) { p_.validate(); }

nav_msgs::msg::Odometry WallTrajectoryLogic::on_timer(int64_t now_ns) const {
  const TrajectorySetpoint s = trajectory_setpoint(p_, tactile_common::to_seconds(now_ns));
  nav_msgs::msg::Odometry m;
  tactile_common::to_stamp(now_ns, m.header.stamp);
  // Positions and the (world) velocity in odom: the controller tracks them with the
  // odometry (they were labelled map).
  m.header.frame_id = tactile_common::prefixed(p_.frame_prefix, tactile_common::frames::kOdom);
  m.child_frame_id = m.header.frame_id;
  m.pose.pose.position.x = s.position.x();
  m.pose.pose.position.y = s.position.y();
  m.pose.pose.position.z = s.position.z();
  m.pose.pose.orientation.z = std::sin(0.5 * s.yaw);
  m.pose.pose.orientation.w = std::cos(0.5 * s.yaw);
  m.twist.twist.linear.x = s.velocity.x();
  m.twist.twist.linear.y = s.velocity.y();
  m.twist.twist.linear.z = s.velocity.z();
  return m;
}

}  // namespace wall_effect_ekf
