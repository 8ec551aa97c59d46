#include "xplorer_force_est/xplorer_force_est_logic.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "tactile_common/time.hpp"

namespace xplorer_force_est {

using tactile_common::ParamMap;

namespace {

bool finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

std::array<double, 4> four(const ParamMap& m, const std::string& key) {
  const std::vector<double> v = m.get_double_array(key);
  if (v.size() != 4) throw m.error(key, "must have 4 elements (one per arm), got " + std::to_string(v.size()));
  return {v[0], v[1], v[2], v[3]};
}

geometry_msgs::msg::WrenchStamped wrench(const std_msgs::msg::Header& h, const std::string& frame, const Vec3& f,
                                         double yaw_torque) {
  geometry_msgs::msg::WrenchStamped w;
  w.header.stamp = h.stamp;
  w.header.frame_id = frame;
  w.wrench.force.x = f.x();
  w.wrench.force.y = f.y();
  w.wrench.force.z = f.z();
  w.wrench.torque.z = yaw_torque;  // about z (world z = body z near hover)
  return w;
}

}  // namespace

void XplorerForceEstLogic::Params::validate() const {
  estimator.validate();
  if (!std::isfinite(max_sample_gap_s) || max_sample_gap_s <= 0.0)
    throw std::invalid_argument("XplorerForceEstLogic.max_sample_gap_s: must be finite and > 0, got " +
                                std::to_string(max_sample_gap_s));
  if (!(max_arm_angle > 0.0) || !std::isfinite(max_arm_angle))
    throw std::invalid_argument("XplorerForceEstLogic.max_arm_angle: must be finite and > 0, got " +
                                std::to_string(max_arm_angle));
  if (world_frame.empty()) throw std::invalid_argument("XplorerForceEstLogic.world_frame: must not be empty");
  if (body_frame.empty()) throw std::invalid_argument("XplorerForceEstLogic.body_frame: must not be empty");
}

ParamMap XplorerForceEstLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::positive;
  const xplorer_force_est::Params d;
  const Params n;
  ParamMap m(kNodeName, "defaults");
  // The estimator's parameter spec: value, description (from the Params comments; README
  // "Parameters"), unit, the range params_from()/validate() take for the key alone (a bound
  // set by another key is named in the description), and none live: the filters and
  // observers are built at start, so `ros2 param set` refuses every key (read-only).
  m.set("arm_rate_hz", d.arm_rate_hz, {"arm IMU rate (001 Sec. V-A2: BNO055 at 50 Hz)", "Hz", positive(), false,
        paper("001 Sec. V-A2: BNO055 at 50 Hz")});
  m.set("imu_rate_hz", d.imu_rate_hz,
        {"flight-controller IMU rate (choice: the SITL IMU rate)", "Hz", positive(), false,
         choice("the SITL IMU rate")});
  m.set("arm_median_window", static_cast<int64_t>(d.arm_median_window),
        {"median filter of the arm angles, odd (001 Sec. V-A2 median low-pass; choice: removes single-sample "
         "spikes)", "samples", closed(1, MedianFilter::kMaxWindow), false,
         choice("001 Sec. V-A2 names the filter, not its window")});
  m.set("arm_lowpass_hz", d.arm_lowpass_hz,
        {"first-order low-pass cut-off of the arm angles (001 Sec. V-A2; choice); < arm_rate_hz / 2", "Hz",
         positive(), false, choice("001 Sec. V-A2 names the filter, not its band")});
  m.set("arm_bandstop", d.arm_bandstop, {"band-stop the arm angles at arm_bandstop_hz (001 Sec. V-A2)", "", {}, false,
        paper("001 Sec. V-A2: band-stop filter of the arm angles")});
  m.set("arm_bandstop_hz", d.arm_bandstop_hz,
        {"band-stop centre: the arm's damped natural frequency sqrt(k/J - (b/2J)^2) / 2pi (choice); "
         "< arm_rate_hz / 2", "Hz", positive(), false,
         choice("the arm's damped natural frequency from 001 eq. 2 J, b, k")});
  m.set("arm_bandstop_q", d.arm_bandstop_q, {"band-stop quality factor (choice)", "", positive(), false, choice()});
  m.set("arm_hold_samples", static_cast<int64_t>(d.arm_hold_samples),
        {"a missing/NaN arm sample holds the last angle this many samples, then the arm is dropped (choice)",
         "samples", closed(0, std::numeric_limits<int>::max()), false, choice()});
  m.set("arm_inertia", d.arm_inertia, {"J_zz of an arm (001 eq. 2, Sec. V-A2)", "kg m^2", positive(), false,
        paper("001 eq. 2, Sec. V-A2 system identification")});
  m.set("arm_damping", d.arm_damping, {"b of an arm (001 eq. 2, Sec. V-A2)", "N m s/rad", at_least(0.0), false,
        paper("001 eq. 2, Sec. V-A2 system identification")});
  m.set("arm_stiffness", d.arm_stiffness, {"k of an arm (001 eq. 2, Sec. V-A2)", "N m/rad", positive(), false,
        paper("001 eq. 2, Sec. V-A2 system identification")});
  m.set("lever_arm", d.lever_arm,
        {"l of 001 eq. 2, not given by 001: 0.15 m x cos^2(45 deg) (calibration choice, README)", "m", positive(),
         false, choice("calibration: 0.15 m x cos^2(45 deg), 001 gives no l (README)")});
  m.set("observer_gain", d.observer_gain,
        {"K_I of 001 eq. 3 (choice); < arm_rate_hz (stable discrete observer)", "1/s", positive(), false, choice()});
  m.set("arm_directions", std::vector<double>(d.arm_directions.begin(), d.arm_directions.end()),
        {"undeflected arm directions in the body frame, arms counter-clockwise from the front-right one "
         "(ArmImu.arm_id); 4 finite values", "rad", {}, false, choice("the X frame's arms at +-45 and +-135 deg")});
  m.set("mass", d.mass, {"vehicle mass (001 Sec. V-A1)", "kg", positive(), false, paper("001 Sec. V-A1")});
  m.set("thrust_scale", d.thrust_scale,
        {"thrust = normalised command x this (001 Sec. V-A3: 32.5 N)", "N", positive(), false,
         paper("001 Sec. V-A3: 32.5 N")});
  m.set("gravity", d.gravity, {"gravitational acceleration of 001 eq. 5", "m/s^2", positive(), false,
        paper("001 eq. 5")});
  m.set("com_median_window", static_cast<int64_t>(d.com_median_window),
        {"median filter of the CoM estimate at imu_rate_hz, odd (choice)", "samples",
         closed(1, MedianFilter::kMaxWindow), false, choice()});
  m.set("com_lowpass_hz", d.com_lowpass_hz,
        {"low-pass cut-off of the CoM estimate (choice: 001 Fig. 4 converges slower than the arms); "
         "< imu_rate_hz / 2", "Hz", positive(), false, choice("slower than the arm estimate, as 001 Fig. 4")});
  m.set("contact_threshold", d.contact_threshold,
        {"theta_th on sum |theta_i| of 001 eq. 6 (choice; a 1 N face push gives ~0.08)", "rad", positive(),
         false, choice("a 1 N face push gives ~0.08 rad")});
  m.set("xi_f", d.xi_f,
        {"xi_f of 001 eq. 7 (choice): [s/N] in rate mode, [1/N] in magnitude mode", "", at_least(0.0), false,
         choice("001 eq. 7 gives no value")});
  m.set("kappa_mode", std::string(to_string(d.kappa_mode)),
        {"kappa of 001 eq. 7 from the rate or the magnitude of the force: rate or magnitude", "", {}, false,
         paper("001 Sec. III-A3 text (rate); eq. 7 as printed (magnitude)")});
  m.set("yaw_inertia", d.yaw_inertia,
        {"I_zz of the yaw-torque observer (001 Sec. III-A3; estimate, the SITL vehicle's)", "kg m^2", positive(),
         false, choice("the SITL vehicle's I_zz")});
  m.set("yaw_observer_gain", d.yaw_observer_gain,
        {"K_o of the yaw-torque observer (choice); < imu_rate_hz", "1/s", positive(), false, choice()});
  m.set("torque_coefficient", d.torque_coefficient,
        {"rotor drag torque per thrust (choice, 5\" propeller)", "m", at_least(0.0), false,
         choice("5-inch propeller")});
  m.set("spin_sign", std::vector<double>(d.spin_sign.begin(), d.spin_sign.end()),
        {"yaw torque sign per rotor: 4 values, each +1 or -1", "", {}, false,
         choice("the SITL vehicle's rotor directions")});
  m.set("world_frame", n.world_frame,
        {"frame of the IMU attitude that rotates the force (REP 105); not empty", "", {}, false, choice("REP 105")});
  m.set("body_frame", n.body_frame, {"frame of the body wrench; not empty", "", {}, false, choice("REP 105")});
  m.set("max_sample_gap_s", n.max_sample_gap_s,
        {"a larger stamp gap on the arm or IMU stream resets the filters; an arm set this long after the last "
         "IMU sample publishes no wrench (choice: 25 arm samples)", "s", positive(), false, choice("25 arm samples")});
  m.set("max_arm_angle", n.max_arm_angle,
        {"|arm_angle| above this is not a deflection (arms stop at 30 deg, 001 Sec. II): missing (choice)", "rad",
         positive(), false, choice("beyond the 30 deg end stops of 001 Sec. II")});
  return m;
}

XplorerForceEstLogic::Params XplorerForceEstLogic::params_from(const ParamMap& m) {
  Params p;
  auto& e = p.estimator;
  e.arm_rate_hz = m.get_double("arm_rate_hz");
  e.imu_rate_hz = m.get_double("imu_rate_hz");
  e.arm_median_window = m.get_int("arm_median_window", 1, MedianFilter::kMaxWindow);  // odd: validate()
  e.arm_lowpass_hz = m.get_double("arm_lowpass_hz");
  e.arm_bandstop = m.get_bool("arm_bandstop");
  e.arm_bandstop_hz = m.get_double("arm_bandstop_hz");
  e.arm_bandstop_q = m.get_double("arm_bandstop_q");
  e.arm_hold_samples = m.get_int("arm_hold_samples", 0, std::numeric_limits<int>::max());
  e.arm_inertia = m.get_double("arm_inertia");
  e.arm_damping = m.get_double("arm_damping");
  e.arm_stiffness = m.get_double("arm_stiffness");
  e.lever_arm = m.get_double("lever_arm");
  e.observer_gain = m.get_double("observer_gain");
  e.arm_directions = four(m, "arm_directions");
  e.mass = m.get_double("mass");
  e.thrust_scale = m.get_double("thrust_scale");
  e.gravity = m.get_double("gravity");
  e.com_median_window = m.get_int("com_median_window", 1, MedianFilter::kMaxWindow);  // odd: validate()
  e.com_lowpass_hz = m.get_double("com_lowpass_hz");
  e.contact_threshold = m.get_double("contact_threshold");
  e.xi_f = m.get_double("xi_f");
  const std::string km = m.get_string("kappa_mode");
  try {
    e.kappa_mode = kappa_mode_from_string(km);
  } catch (const std::invalid_argument&) {
    throw m.error("kappa_mode", "must be \"rate\" or \"magnitude\", got \"" + km + "\"");
  }
  e.yaw_inertia = m.get_double("yaw_inertia");
  e.yaw_observer_gain = m.get_double("yaw_observer_gain");
  e.torque_coefficient = m.get_double("torque_coefficient");
  e.spin_sign = four(m, "spin_sign");
  p.world_frame = m.get_string("world_frame");
  p.body_frame = m.get_string("body_frame");
  p.max_sample_gap_s = m.get_double("max_sample_gap_s");
  p.max_arm_angle = m.get_double("max_arm_angle");
  try {
    p.validate();
  } catch (const std::invalid_argument& ex) {
    throw m.error_from(ex);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

XplorerForceEstLogic::XplorerForceEstLogic(const Params& params)
    : params_((params.validate(), params)), estimator_(params.estimator) {}

void XplorerForceEstLogic::on_imu(const sensor_msgs::msg::Imu& msg) {
  ++stats_.received_imu;
  const auto& a = msg.linear_acceleration;
  const auto& g = msg.angular_velocity;
  const auto& q = msg.orientation;
  const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!finite(a.x, a.y, a.z) || !finite(g.x, g.y, g.z) || !finite(q.x, q.y, q.z) || !std::isfinite(q.w) ||
      !(std::abs(qn - 1.0) < 1e-3)) {
    ++stats_.dropped_nonfinite_imu;
    return;
  }
  const int64_t t = tactile_common::from_stamp(msg.header.stamp);
  double dt = 1.0 / params_.estimator.imu_rate_hz;
  if (have_imu_stamp_) {
    if (t <= last_imu_ns_) {
      ++stats_.dropped_out_of_order;
      return;
    }
    dt = tactile_common::to_seconds(t - last_imu_ns_);
    if (dt > params_.max_sample_gap_s) {
      dt = 1.0 / params_.estimator.imu_rate_hz;
      ++stats_.resets_on_gap;
      estimator_.reset();
    }
  }
  have_imu_stamp_ = true;
  last_imu_ns_ = t;
  q_wb_ = Quat(q.w, q.x, q.y, q.z).normalized();
  have_attitude_ = true;
  estimator_.update_imu(Vec3(a.x, a.y, a.z), Vec3(g.x, g.y, g.z), q_wb_, dt);
}

void XplorerForceEstLogic::on_thrust(const tactile_msgs::msg::ThrustCommand& msg) {
  ++stats_.received_thrust;
  double f = std::isfinite(msg.normalized) ? msg.normalized * params_.estimator.thrust_scale  // 001 Sec. V-A3
                                           : msg.total_thrust;
  if (!std::isfinite(f) || f < 0.0) {
    ++stats_.dropped_nonfinite_thrust;
    return;
  }
  estimator_.set_thrust(f);
  if (msg.rotor_thrust.size() == 4) {
    std::array<double, 4> t{};
    for (size_t i = 0; i < 4; ++i) t[i] = msg.rotor_thrust[i];
    if (finite(t[0], t[1], t[2]) && std::isfinite(t[3])) estimator_.set_rotor_thrusts(t);
  }
}

XplorerForceEstLogic::Outputs XplorerForceEstLogic::on_arm_imu(const tactile_msgs::msg::ArmImuArray& msg) {
  ++stats_.received_arm;
  Outputs out;
  const int64_t t = tactile_common::from_stamp(msg.header.stamp);
  double dt = 1.0 / params_.estimator.arm_rate_hz;
  if (have_arm_stamp_) {
    if (t <= last_arm_ns_) {
      ++stats_.dropped_out_of_order;
      return out;
    }
    dt = tactile_common::to_seconds(t - last_arm_ns_);
    if (dt > params_.max_sample_gap_s) {
      dt = 1.0 / params_.estimator.arm_rate_hz;
      ++stats_.resets_on_gap;
      estimator_.reset();
    }
  }
  have_arm_stamp_ = true;
  last_arm_ns_ = t;
  if (have_imu_stamp_ && t - last_imu_ns_ > tactile_common::from_seconds(params_.max_sample_gap_s)) {
    // The IMU stopped: the wrench would be fresh-stamped but built on a stale
    // attitude (world frame) and acceleration (CoM part, eq. 5). No wrench:
    // the XPLORER FSM sees its input go stale and holds (issue 33).
    ++stats_.dropped_imu_stale;
    return out;
  }

  std::array<double, 4> theta;
  theta.fill(std::numeric_limits<double>::quiet_NaN());
  std::array<bool, 4> seen{};
  for (const auto& arm : msg.arms) {
    if (arm.arm_id > 3 || seen[arm.arm_id]) {
      ++stats_.arm_bad_id;
      continue;
    }
    seen[arm.arm_id] = true;
    double th = arm.arm_angle;
    if (std::isfinite(th) && std::abs(th) > params_.max_arm_angle) {
      ++stats_.arm_out_of_range;
      th = std::numeric_limits<double>::quiet_NaN();
    }
    if (!std::isfinite(th) && have_attitude_) {
      // BNO055-style attitude of the arm (arm -> world): theta = yaw of
      // (body^-1 arm) minus the arm's undeflected direction (001 Sec. V-A2).
      const auto& q = arm.orientation;
      const double qn = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
      if (finite(q.x, q.y, q.z) && std::isfinite(q.w) && std::abs(qn - 1.0) < 1e-3) {
        const Mat3 rel = (q_wb_.conjugate() * Quat(q.w, q.x, q.y, q.z)).toRotationMatrix();
        th = std::remainder(std::atan2(rel(1, 0), rel(0, 0)) - params_.estimator.arm_directions[arm.arm_id], 2 * M_PI);
        if (std::abs(th) > params_.max_arm_angle) {
          th = std::numeric_limits<double>::quiet_NaN();
        } else {
          ++stats_.arm_from_orientation;
        }
      }
    }
    theta[arm.arm_id] = th;
  }
  for (size_t i = 0; i < 4; ++i) {
    if (!std::isfinite(theta[i])) ++stats_.arm_missing[i];
  }
  const Estimate& e = estimator_.update_arms(theta, dt);
  out.world = wrench(msg.header, params_.world_frame, e.force_world, e.yaw_torque);
  out.body = wrench(msg.header, params_.body_frame, e.force_body, e.yaw_torque);
  ++stats_.published;
  if (e.degraded) ++stats_.published_degraded;
  return out;
}

}  // namespace xplorer_force_est
