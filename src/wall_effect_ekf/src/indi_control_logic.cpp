#include "wall_effect_ekf/indi_control_logic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/time.hpp"

namespace wall_effect_ekf {

using tactile_common::ParamMap;

Mat3 wall_frame_attitude(const Mat3& R_wb, double psi) {
  // Direction to the wall: body (cos psi, sin psi, 0) -> world, horizontal.
  Vec3 u = R_wb * Vec3(std::cos(psi), std::sin(psi), 0.0);
  u.z() = 0.0;
  if (u.norm() < 1e-9) u = Vec3::UnitX();
  u.normalize();
  const Vec3 y_w = -u, z_w = Vec3::UnitZ();
  const Vec3 x_w = y_w.cross(z_w);
  Mat3 W;  // rows: wall axes in world coordinates
  W.row(0) = x_w.transpose();
  W.row(1) = y_w.transpose();
  W.row(2) = z_w.transpose();
  return W * R_wb;
}

void IndiControlLogic::Params::validate() const {
  indi.validate();
  auto fail = [](const char* f, double v) {
    throw std::invalid_argument(std::string("IndiControlLogic.") + f + ": must be finite and > 0, got " + std::to_string(v));
  };
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) fail("rate_hz", rate_hz);
  if (!(outer_rate_hz > 0.0) || !std::isfinite(outer_rate_hz) || outer_rate_hz > rate_hz)
    throw std::invalid_argument("IndiControlLogic.outer_rate_hz: must be in (0, rate_hz], got " + std::to_string(outer_rate_hz));
  if (!(max_input_age_s > 0.0) || !std::isfinite(max_input_age_s)) fail("max_input_age_s", max_input_age_s);
  if (!(failsafe_descent_speed > 0.0) || !std::isfinite(failsafe_descent_speed))
    fail("failsafe_descent_speed", failsafe_descent_speed);
  if (!(touchdown_confirm_s > 0.0) || !std::isfinite(touchdown_confirm_s)) fail("touchdown_confirm_s", touchdown_confirm_s);
  if (!(failsafe_max_descent_s > 0.0) || !std::isfinite(failsafe_max_descent_s))
    fail("failsafe_max_descent_s", failsafe_max_descent_s);
  if (!std::isfinite(failsafe_floor_z))
    throw std::invalid_argument("IndiControlLogic.failsafe_floor_z: must be finite, got " + std::to_string(failsafe_floor_z));
  if (!(accel_bias_time_constant_s > 0.0) || !std::isfinite(accel_bias_time_constant_s))
    fail("accel_bias_time_constant_s", accel_bias_time_constant_s);
}

const char* to_string(IndiFailsafeState s) {
  switch (s) {
    case IndiFailsafeState::kWaitingForInput: return "WAITING_FOR_INPUT";
    case IndiFailsafeState::kNominal: return "NOMINAL";
    case IndiFailsafeState::kOdometryLost: return "ODOMETRY_LOST";
    case IndiFailsafeState::kMotorsStopped: return "MOTORS_STOPPED";
  }
  return "?";
}

namespace {
using tactile_msgs::msg::FsmState;
static_assert(static_cast<uint8_t>(IndiReason::kInputsReady) == FsmState::REASON_INDI_INPUTS_READY);
static_assert(static_cast<uint8_t>(IndiReason::kImuLost) == FsmState::REASON_INDI_IMU_LOST);
static_assert(static_cast<uint8_t>(IndiReason::kOdometryLost) == FsmState::REASON_INDI_ODOMETRY_LOST);
static_assert(static_cast<uint8_t>(IndiReason::kDescentTimedOut) == FsmState::REASON_INDI_DESCENT_TIMED_OUT);
static_assert(static_cast<uint8_t>(IndiReason::kTouchdown) == FsmState::REASON_INDI_TOUCHDOWN);
static_assert(static_cast<uint8_t>(IndiReason::kCrashed) == FsmState::REASON_INDI_CRASHED);

// A guard that must hold for hold_s (the land detector, the crash tilt): since_ns is the tick
// it began (-1: not holding), set on its first tick and cleared on the first tick without it.
bool held(bool guard, int64_t& since_ns, int64_t now_ns, double hold_s) {
  if (!guard) {
    since_ns = -1;
    return false;
  }
  if (since_ns < 0) since_ns = now_ns;
  return tactile_common::to_seconds(now_ns - since_ns) >= hold_s;
}
}  // namespace

namespace indi_guards {
namespace {
// The workspace's one staleness rule (tactile_common/time.hpp), on a received input's age.
bool fresh(bool have, double age_s, double max_age_s) { return have && tactile_common::age_is_fresh(age_s, max_age_s); }
}  // namespace
bool inputs_ready(const InputAges& in, double max_age_s) {
  return fresh(in.have_odometry, in.odometry_age_s, max_age_s) && fresh(in.have_imu, in.imu_age_s, max_age_s);
}
bool imu_lost(const InputAges& in, double max_age_s) { return !fresh(in.have_imu, in.imu_age_s, max_age_s); }
bool odometry_lost(const InputAges& in, double max_age_s) {
  return fresh(in.have_imu, in.imu_age_s, max_age_s) && !fresh(in.have_odometry, in.odometry_age_s, max_age_s);
}
bool touchdown(double commanded_thrust_n, const Vec3& accel_world, double mass) {
  return commanded_thrust_n < kTouchdownThrustFraction * mass * kGravity && accel_world.norm() < kRestingAccel;
}
bool below_floor(double height_estimate, double floor_z) { return height_estimate < floor_z - kBelowFloorMargin; }
double floor_probe_thrust(double start_thrust_n, double probe_s) {
  return std::max(0.0, start_thrust_n * (1.0 - probe_s / kFloorProbeRampS));
}
bool airborne_in_probe(const Vec3& accel_world) { return accel_world.z() < kAirborneAccel; }
bool descent_timed_out(double descent_s, double max_descent_s) { return descent_s >= max_descent_s; }
// R(2,2) = e3 . R e3: the cosine of the body z axis's angle from the vertical (NaN: not a crash).
bool crash_attitude(const Mat3& R_world_body) { return R_world_body(2, 2) < std::cos(kCrashTilt); }
bool crashed_before_loss(double since_crash_attitude_s) { return since_crash_attitude_s <= kCrashMemoryS; }
}  // namespace indi_guards

ParamMap IndiControlLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::paper;
  using tactile_common::tuned;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  const Params d;
  const IndiParams& i = d.indi;
  ParamMap m(kNodeName, "defaults");
  auto v3 = [](const Vec3& v) { return std::vector<double>{v.x(), v.y(), v.z()}; };
  // The controller's parameter spec: value, description (from the Params comments; README
  // "Parameters"), unit, the range params_from()/validate() take for the key alone (a bound
  // set by another key is named in the description), and none live: gains, limits and the
  // vehicle model are read at start, so `ros2 param set` refuses every key (read-only).
  m.set("rate_hz", d.rate_hz,
        {"inner-loop rate (choice: the simulated vehicle's IMU rate)", "Hz", positive(), false,
         choice("the simulated vehicle's IMU rate")});
  m.set("outer_rate_hz", d.outer_rate_hz,
        {"outer-loop rate (004: 100 Hz ground station); <= rate_hz", "Hz", positive(), false,
         paper("004 Methods: 100 Hz on the ground station")});
  m.set("use_wall_in_allocation", d.use_wall_in_allocation,
        {"control effectiveness B with the wall estimate when a wall is detected (004 eq. 36)", "", {}, false,
         paper("004 eq. 36: wall effect integrated into B")});
  m.set("max_input_age_s", d.max_input_age_s,
        {"odometry older than this (IMU fresh): descent on the IMU (ODOMETRY_LOST); IMU older than this: "
         "motors stopped (MOTORS_STOPPED)", "s", positive(), false, choice()});
  m.set("failsafe_descent_speed", d.failsafe_descent_speed,
        {"ODOMETRY_LOST: descent speed, flown on the IMU-integrated velocity", "m/s", positive(), false,
         choice("wall_effect_nav's FAILSAFE_LAND speed")});
  m.set("touchdown_confirm_s", d.touchdown_confirm_s,
        {"ODOMETRY_LOST: the land detector (thrust < m g / 2 at rest) holds this long, then the motors stop", "s",
         positive(), false, choice()});
  m.set("failsafe_max_descent_s", d.failsafe_max_descent_s,
        {"ODOMETRY_LOST: the motors stop after this long in the descent, touched down or not", "s", positive(), false,
         choice("a 2 m height bound at 0.25 m/s is 8 s, plus 2 s")});
  const double inf = std::numeric_limits<double>::infinity();
  m.set("failsafe_floor_z", d.failsafe_floor_z,
        {"ODOMETRY_LOST: z of the floor in the odometry frame; when the IMU dead-reckoned height is 0.1 m below "
         "it a floor probe ramps the thrust down (the land detector's fallback); finite", "m", ParamRange{-inf, inf, true, true}, false,
         choice("the motion-capture and simulator floor")});
  m.set("accel_bias_time_constant_s", d.accel_bias_time_constant_s,
        {"time constant of the accelerometer bias estimate (IMU minus odometry velocity change, while odometry "
         "flows), subtracted in ODOMETRY_LOST's dead reckoning", "s", positive(), false,
         tuned("SITL ducted_track_0, odometry lost at 12 s, accel_bias_sigma 0.1: seeds 1-20 (docs/tuning/wall_effect_ekf.md)")});
  m.set("k_p", v3(i.k_p), {"K_p of 004 eq. 26 per axis, each finite and >= 0 (choice)", "1/s^2", {}, false,
        choice("004 gives no gains")});
  m.set("k_d", v3(i.k_d), {"K_d of 004 eq. 26 per axis, each finite and >= 0 (choice)", "1/s", {}, false,
        choice("004 gives no gains")});
  m.set("k_i", v3(i.k_i), {"K_i of the position integral per axis, each finite and >= 0 (choice)", "1/s^3", {},
                           false, choice("004 gives no gains")});
  m.set("integral_limit", i.integral_limit,
        {"|K_i int e| limit per axis (choice)", "m/s^2", at_least(0.0), false, choice()});
  m.set("integral_zone", i.integral_zone,
        {"the integral runs only while |p_d - p| is below this on that axis (anti-windup; choice)", "m",
         positive(), false, choice()});
  m.set("max_accel_xy", i.max_accel_xy, {"horizontal limit of the target acceleration of 004 eq. 26", "m/s^2",
                                         positive(), false, choice()});
  m.set("attitude_time_constant", i.attitude_time_constant,
        {"tau of 004 eq. 32-33 (choice: 0.05-0.1 s is stable on the simulated vehicle); 0: the outer-loop period "
         "(004's Delta t)", "s", at_least(0.0), false,
         choice("004's Delta t oscillates with a first-order rate loop (README)")});
  m.set("max_rate_xy", i.max_rate_xy, {"|w_d,x|, |w_d,y| limit", "rad/s", positive(), false, choice()});
  m.set("max_tilt", i.max_tilt, {"no rate setpoint tilts further than this; below the fail-safe's crash tilt "
                                  "(60 deg = 1.047 rad)", "rad", ParamRange{0.0, 1.0, true, true},
                                 false, choice()});
  m.set("kappa_d", v3(i.kappa_d), {"kappa_d of 004 eq. 35 per axis, each finite and >= 0 (choice)", "1/s", {},
                                   false, choice("004 gives no gains")});
  m.set("kappa_p_yaw", i.kappa_p_yaw, {"kappa_p of 004 eq. 35 (choice)", "1/s^2", at_least(0.0), false,
        choice("004 gives no gains")});
  m.set("max_yaw_accel", i.max_yaw_accel, {"|w_dot_d,z| limit", "rad/s^2", positive(), false, choice()});
  m.set("vehicle.mass", i.vehicle.mass,
        {"m (004: 280 g); the four rotors must carry it: mass g < 4 vehicle.max_rotor_thrust", "kg", positive(),
         false, paper("004: 280 g")});
  m.set("vehicle.inertia_diag", v3(i.vehicle.inertia_diag),
        {"J diagonal, each finite and > 0 (choice: the simulated vehicle's estimate)", "kg m^2", {}, false,
         choice("the simulated vehicle's estimate")});
  m.set("vehicle.rotor_offset", i.vehicle.rotor_offset,
        {"L of the rotor positions (+-L, +-L, 0) (004: d* = 17 cm with a 5 cm gap gives 0.082 m)", "m",
         positive(), false, paper("004: d* = 17 cm with a 5 cm duct gap, d_bar = 2.1 at 0.2 m")});
  m.set("vehicle.torque_coefficient", i.vehicle.torque_coefficient,
        {"c_tau of 004 eq. 7 (choice)", "m", at_least(0.0), false, choice("004 eq. 7 gives no value")});
  m.set("vehicle.max_rotor_thrust", i.vehicle.max_rotor_thrust,
        {"per rotor (004: over 440 g of thrust in total); > vehicle.mass g / 4", "N", positive(), false,
         paper("004: over 440 g of thrust in total")});
  return m;
}

IndiControlLogic::Params IndiControlLogic::params_from(const ParamMap& map) {
  Params p;
  auto v3 = [&map](const char* key) {
    const std::vector<double> v = map.get_double_array(key);
    if (v.size() != 3) throw map.error(key, "must have 3 entries, got " + std::to_string(v.size()));
    return Vec3(v[0], v[1], v[2]);
  };
  IndiParams& i = p.indi;
  p.rate_hz = map.get_double("rate_hz");
  p.outer_rate_hz = map.get_double("outer_rate_hz");
  p.use_wall_in_allocation = map.get_bool("use_wall_in_allocation");
  p.max_input_age_s = map.get_double("max_input_age_s");
  p.failsafe_descent_speed = map.get_double("failsafe_descent_speed");
  p.touchdown_confirm_s = map.get_double("touchdown_confirm_s");
  p.failsafe_max_descent_s = map.get_double("failsafe_max_descent_s");
  p.failsafe_floor_z = map.get_double("failsafe_floor_z");
  p.accel_bias_time_constant_s = map.get_double("accel_bias_time_constant_s");
  i.k_p = v3("k_p");
  i.k_d = v3("k_d");
  i.k_i = v3("k_i");
  i.integral_limit = map.get_double("integral_limit");
  i.integral_zone = map.get_double("integral_zone");
  i.max_accel_xy = map.get_double("max_accel_xy");
  i.attitude_time_constant = map.get_double("attitude_time_constant");
  i.max_rate_xy = map.get_double("max_rate_xy");
  i.max_tilt = map.get_double("max_tilt");
  i.kappa_d = v3("kappa_d");
  i.kappa_p_yaw = map.get_double("kappa_p_yaw");
  i.max_yaw_accel = map.get_double("max_yaw_accel");
  i.vehicle.mass = map.get_double("vehicle.mass");
  i.vehicle.inertia_diag = v3("vehicle.inertia_diag");
  i.vehicle.rotor_offset = map.get_double("vehicle.rotor_offset");
  i.vehicle.torque_coefficient = map.get_double("vehicle.torque_coefficient");
  i.vehicle.max_rotor_thrust = map.get_double("vehicle.max_rotor_thrust");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const std::string field = what.substr(0, what.find(':'));
    std::string leaf = field.substr(field.rfind('.') + 1);
    leaf = leaf.substr(0, leaf.find('['));
    const std::string key = map.has(leaf) ? leaf : (map.has("vehicle." + leaf) ? "vehicle." + leaf : "rate_hz");
    throw map.error(key, what);
  }
  return p;
}

IndiControlLogic::IndiControlLogic(const Params& params)
    : params_((params.validate(), params)), ctl_(params.indi) {
  outer_every_ = std::max(1, static_cast<int>(std::lround(params_.rate_hz / params_.outer_rate_hz)));
}

int64_t IndiControlLogic::period_ns() const { return tactile_common::from_seconds(1.0 / params_.rate_hz); }

void IndiControlLogic::on_setpoint(const nav_msgs::msg::Odometry& msg) {
  ++stats_.setpoints;
  const auto& q = msg.pose.pose.orientation;
  const Vec3 v(msg.twist.twist.linear.x, msg.twist.twist.linear.y, msg.twist.twist.linear.z);
  const Quat qq(q.w, q.x, q.y, q.z);
  if (!v.allFinite() || !qq.coeffs().allFinite() || qq.norm() < 0.5) {
    ++stats_.dropped_nonfinite;
    return;
  }
  const double p[3] = {msg.pose.pose.position.x, msg.pose.pose.position.y, msg.pose.pose.position.z};
  for (int i = 0; i < 3; ++i) {
    sp_.position_control[static_cast<size_t>(i)] = std::isfinite(p[i]);
    sp_.position[i] = std::isfinite(p[i]) ? p[i] : 0.0;
  }
  sp_.velocity = v;
  const Vec3 x = qq.normalized() * Vec3::UnitX();
  sp_.yaw = std::atan2(x.y(), x.x());
  have_sp_ = true;
}

void IndiControlLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.odometry;
  const auto& pp = msg.pose.pose;
  const Vec3 p(pp.position.x, pp.position.y, pp.position.z);
  const Quat q(pp.orientation.w, pp.orientation.x, pp.orientation.y, pp.orientation.z);
  const Vec3 vb(msg.twist.twist.linear.x, msg.twist.twist.linear.y, msg.twist.twist.linear.z);
  if (!p.allFinite() || !q.coeffs().allFinite() || !vb.allFinite() || q.norm() < 0.5) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (stats_.state == IndiFailsafeState::kOdometryLost || stats_.state == IndiFailsafeState::kMotorsStopped) {
    ++stats_.odometry_ignored;  // the descent is terminal: odometry that comes back does not resume (README)
    return;
  }
  const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
  if (have_odom_ && stamp <= odom_ns_) {
    ++stats_.dropped_out_of_order;  // a duplicate or an older one would restart the IMU integrals
    return;
  }
  if (!msg.child_frame_id.empty()) body_frame_ = msg.child_frame_id;
  const Vec3 v = q.normalized() * vb;  // REP-105: twist in the body frame
  update_accel_bias(v, stamp);
  imu_dv_since_odom_.setZero();
  imu_dp_since_odom_.setZero();
  imu_dt_since_odom_ = 0.0;
  pos_ = p;
  vel_ = v;
  odom_ns_ = stamp;
  if (!have_odom_ && !have_sp_) {  // hold where we are until a setpoint comes
    sp_.position = p;
    const Vec3 x = q.normalized() * Vec3::UnitX();
    sp_.yaw = std::atan2(x.y(), x.x());
  }
  have_odom_ = true;
}

// The accelerometer bias from one odometry interval: what the IMU integrated (bias
// subtracted) minus what the odometry measured is the remaining bias, plus noise and the
// misalignment of the two windows (zero on average). Only over an interval the IMU covered
// (half to twice its length) and no longer than max_input_age_s.
std::optional<Vec3> accel_bias_update(const Vec3& bias, const Vec3& imu_dv, const Vec3& odometry_dv, double dt,
                                      const Mat3& R, double time_constant_s) {
  const Vec3 residual_body = R.transpose() * ((imu_dv - odometry_dv) / dt);
  if (!(residual_body.cwiseAbs().maxCoeff() <= kAccelResidualGate)) return std::nullopt;  // NaN too
  const Vec3 b = bias + std::min(1.0, dt / time_constant_s) * residual_body;
  return b.cwiseMax(-kMaxAccelBias).cwiseMin(kMaxAccelBias);
}

void IndiControlLogic::update_accel_bias(const Vec3& velocity, int64_t stamp_ns) {
  if (!have_odom_ || !have_imu_) return;
  const double dt = tactile_common::to_seconds(stamp_ns - odom_ns_);
  if (!(dt > 0.0) || dt > params_.max_input_age_s) return;
  if (imu_dt_since_odom_ < 0.5 * dt || imu_dt_since_odom_ > 2.0 * dt) return;
  const auto b = accel_bias_update(stats_.accel_bias, imu_dv_since_odom_, velocity - vel_, dt, R_,
                                   params_.accel_bias_time_constant_s);
  if (!b) {
    ++stats_.accel_bias_gated;
    return;
  }
  stats_.accel_bias = *b;
  ++stats_.accel_bias_updates;
}

void IndiControlLogic::on_imu(const sensor_msgs::msg::Imu& msg) {
  ++stats_.imu;
  const Quat q(msg.orientation.w, msg.orientation.x, msg.orientation.y, msg.orientation.z);
  const Vec3 a(msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z);
  const Vec3 w(msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z);
  if (!q.coeffs().allFinite() || q.norm() < 0.5 || !a.allFinite() || !w.allFinite()) {
    ++stats_.dropped_nonfinite;
    return;
  }
  const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
  R_ = q.normalized().toRotationMatrix();
  // Velocity change since the last odometry, for the ODOMETRY_LOST descent: the world
  // specific force minus g e3 (004 eq. 30's measured acceleration) over the time since the
  // previous sample (at most max_input_age_s: a longer gap is a lost IMU anyway).
  if (have_imu_ && have_odom_) {
    const double dt = std::clamp(tactile_common::to_seconds(stamp - imu_ns_), 0.0, params_.max_input_age_s);
    imu_dv_since_odom_ += (R_ * (a - stats_.accel_bias) - kGravity * Vec3::UnitZ()) * dt;
    imu_dp_since_odom_ += (vel_ + imu_dv_since_odom_) * dt;
    imu_dt_since_odom_ += dt;
  }
  acc_ = a;
  gyro_ = w;
  imu_ns_ = stamp;
  have_imu_ = true;
}

void IndiControlLogic::on_wall(const tactile_msgs::msg::WallEstimate& msg) {
  ++stats_.walls;
  if (!std::isfinite(msg.distance) || !std::isfinite(msg.direction)) {
    ++stats_.dropped_nonfinite;
    wall_detected_ = false;
    return;
  }
  wall_detected_ = msg.wall_detected;
  wall_distance_ = msg.distance;
  wall_direction_ = msg.direction;
  wall_ns_ = tactile_common::from_stamp(msg.header.stamp);
  have_wall_ = true;
}

void IndiControlLogic::transition(IndiFailsafeState to, IndiReason code, const char* reason, int64_t now_ns) {
  stats_.previous = stats_.state;
  stats_.state = to;
  stats_.reason = reason;
  stats_.reason_code = code;
  ++stats_.transitions;
  stats_.state_since_ns = now_ns;
  if (to == IndiFailsafeState::kOdometryLost) {
    const Vec3 xb = R_.col(0);
    yaw_hold_ = std::atan2(xb.y(), xb.x());
    resting_since_ns_ = -1;
    tilted_since_ns_ = -1;
    probe_since_ns_ = -1;
    floor_bound_off_ = false;
    stats_.commanded_thrust = ctl_.last_outer().thrust;
  }
}

void IndiControlLogic::update_state(int64_t now_ns) {
  using namespace indi_guards;
  InputAges in;
  in.have_odometry = have_odom_;
  in.have_imu = have_imu_;
  in.odometry_age_s = tactile_common::to_seconds(now_ns - odom_ns_);
  in.imu_age_s = tactile_common::to_seconds(now_ns - imu_ns_);
  const double max_age = params_.max_input_age_s;
  if (have_imu_ && crash_attitude(R_)) crash_attitude_ns_ = now_ns;
  switch (stats_.state) {
    case IndiFailsafeState::kWaitingForInput:
      if (inputs_ready(in, max_age)) transition(IndiFailsafeState::kNominal, IndiReason::kInputsReady, "odometry and IMU fresh", now_ns);
      break;
    case IndiFailsafeState::kNominal:
      if (imu_lost(in, max_age)) {
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kImuLost, "IMU stale: no attitude, flight terminated",
                   now_ns);
      } else if (odometry_lost(in, max_age) && crash_attitude_ns_ >= 0 &&
                 crashed_before_loss(tactile_common::to_seconds(now_ns - crash_attitude_ns_))) {
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kCrashed,
                   "odometry stale within 1 s of a crash (tilt beyond 60 deg): no velocity to descend on", now_ns);
      } else if (odometry_lost(in, max_age)) {
        transition(IndiFailsafeState::kOdometryLost, IndiReason::kOdometryLost, "odometry stale: descent on the IMU",
                   now_ns);
      }
      break;
    case IndiFailsafeState::kOdometryLost: {
      if (imu_lost(in, max_age)) {
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kImuLost, "IMU stale in the descent: flight terminated",
                   now_ns);
        break;
      }
      if (held(crash_attitude(R_), tilted_since_ns_, now_ns, kCrashConfirmS - 1e-9)) {
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kCrashed,
                   "crash: tilted beyond 60 deg for 0.3 s in the descent", now_ns);
        break;
      }
      if (descent_timed_out(tactile_common::to_seconds(now_ns - stats_.state_since_ns), params_.failsafe_max_descent_s)) {
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kDescentTimedOut, "descent lasted failsafe_max_descent_s",
                   now_ns);
        break;
      }
      const Vec3 a_world = R_ * (acc_ - stats_.accel_bias) - kGravity * Vec3::UnitZ();
      if (probe_since_ns_ < 0 && !floor_bound_off_ &&
          below_floor(pos_.z() + imu_dp_since_odom_.z(), params_.failsafe_floor_z)) {
        probe_since_ns_ = now_ns;  // no transition: the probe only lowers the thrust (README)
        probe_start_thrust_ = stats_.commanded_thrust;
        ++stats_.floor_probes;
      } else if (probe_since_ns_ >= 0 && airborne_in_probe(a_world)) {
        probe_since_ns_ = -1;  // in the air: back to the descent loop, from hover thrust
        floor_bound_off_ = true;
        ++stats_.floor_probes_aborted;
        ctl_.reset();
        stats_.commanded_thrust = ctl_.previous_thrust();
      }
      if (held(touchdown(stats_.commanded_thrust, a_world, params_.indi.vehicle.mass), resting_since_ns_, now_ns,
               params_.touchdown_confirm_s))
        transition(IndiFailsafeState::kMotorsStopped, IndiReason::kTouchdown,
                   "touchdown: low thrust at rest for touchdown_confirm_s", now_ns);
      break;
    }
    case IndiFailsafeState::kMotorsStopped:
      break;  // terminal
  }
}

std::optional<tactile_msgs::msg::ThrustCommand> IndiControlLogic::on_timer(int64_t now_ns) {
  update_state(now_ns);
  switch (stats_.state) {
    case IndiFailsafeState::kWaitingForInput:
      ++stats_.ticks_without_input;
      return std::nullopt;  // on the ground, motors idle: nothing was ever commanded
    case IndiFailsafeState::kNominal:
      ++stats_.ticks_nominal;
      return nominal(now_ns);
    case IndiFailsafeState::kOdometryLost:
      ++stats_.ticks_odometry_lost;
      return descend(now_ns);
    case IndiFailsafeState::kMotorsStopped:
      break;
  }
  ++stats_.ticks_motors_stopped;
  return command(now_ns, {0.0, 0.0, 0.0, 0.0});  // on purpose, every tick
}

AllocationWall IndiControlLogic::allocation_wall(int64_t now_ns) const {
  AllocationWall wall;
  const int64_t max_age = tactile_common::from_seconds(params_.max_input_age_s);
  if (params_.use_wall_in_allocation && have_wall_ && wall_detected_ && now_ns - wall_ns_ <= max_age) {
    wall.present = true;
    wall.y = wall_distance_;
    wall.R = wall_frame_attitude(R_, wall_direction_);
  }
  return wall;
}

tactile_msgs::msg::ThrustCommand IndiControlLogic::command(int64_t now_ns, const std::array<double, 4>& f) {
  tactile_msgs::msg::ThrustCommand out;
  tactile_common::to_stamp(now_ns, out.header.stamp);
  out.header.frame_id = body_frame_;  // the odometry's body frame (cf1/base_link with a prefix)
  out.normalized = std::numeric_limits<double>::quiet_NaN();
  out.rotor_thrust.assign(f.begin(), f.end());
  out.total_thrust = f[0] + f[1] + f[2] + f[3];
  ++stats_.published;
  return out;
}

std::optional<tactile_msgs::msg::ThrustCommand> IndiControlLogic::nominal(int64_t now_ns) {
  if (ticks_ % outer_every_ == 0) {
    IndiFeedback fb;
    fb.position = pos_;
    fb.velocity = vel_;
    fb.R = R_;
    fb.specific_force = acc_;
    ctl_.outer(sp_, fb, outer_every_ / params_.rate_hz);  // 004 eq. 26, 30-34
  }
  ++ticks_;
  const Vec3 xb = R_.col(0);
  const auto f = ctl_.inner(gyro_, std::atan2(xb.y(), xb.x()), sp_.yaw, allocation_wall(now_ns));  // 004 eq. 35-36
  return command(now_ns, f);
}

tactile_msgs::msg::ThrustCommand IndiControlLogic::descend(int64_t now_ns) {
  // Velocity: the last odometry's plus the IMU's measured acceleration integrated since.
  const Vec3 v = vel_ + imu_dv_since_odom_;
  stats_.vertical_speed_estimate = v.z();
  stats_.height_estimate = pos_.z() + imu_dp_since_odom_.z();
  if (ticks_ % outer_every_ == 0) {
    // 004 eq. 26 velocity-only on every axis (K_d; no position): hold the horizontal velocity
    // at 0 (level unless a force such as the wall's pull must be held off, max_tilt) and
    // descend at failsafe_descent_speed; eq. 30-34 unchanged.
    IndiSetpoint sp;
    sp.position_control = {false, false, false};
    sp.velocity = Vec3(0.0, 0.0, -params_.failsafe_descent_speed);
    sp.yaw = yaw_hold_;
    IndiFeedback fb;
    fb.velocity = v;
    fb.R = R_;
    fb.specific_force = acc_ - stats_.accel_bias;
    ctl_.outer(sp, fb, outer_every_ / params_.rate_hz);
  }
  ++ticks_;
  // The floor probe (README): the collective thrust ramps down, the attitude loop runs on.
  double thrust = ctl_.last_outer().thrust;
  if (probe_since_ns_ >= 0)
    thrust = indi_guards::floor_probe_thrust(probe_start_thrust_, tactile_common::to_seconds(now_ns - probe_since_ns_));
  stats_.commanded_thrust = thrust;
  const Vec3 xb = R_.col(0);
  const auto f = ctl_.allocate(ctl_.angular_accel(gyro_, std::atan2(xb.y(), xb.x()), yaw_hold_), gyro_, thrust,
                               allocation_wall(now_ns));  // 004 eq. 35-36
  return command(now_ns, f);
}

std::optional<tactile_msgs::msg::FsmState> IndiControlLogic::state_message(int64_t now_ns) {
  const bool changed = stats_.transitions != published_transitions_;
  if (!changed && last_state_msg_ns_ >= 0 && now_ns - last_state_msg_ns_ < kStatePeriodNs) return std::nullopt;
  tactile_msgs::msg::FsmState s;
  tactile_common::to_stamp(now_ns, s.header.stamp);
  s.behaviour = "indi_failsafe";
  s.state = to_string(stats_.state);
  s.previous_state = stats_.transitions > 0 ? to_string(stats_.previous) : "";
  s.reason = stats_.reason;
  s.reason_code = static_cast<uint8_t>(stats_.reason_code);
  // Before the first transition: since the first tick (the node clock may not start at 0).
  if (first_tick_ns_ < 0) first_tick_ns_ = now_ns;
  s.time_in_state = tactile_common::to_seconds(now_ns - (stats_.transitions > 0 ? stats_.state_since_ns : first_tick_ns_));
  s.transitions = stats_.transitions;
  published_transitions_ = stats_.transitions;
  last_state_msg_ns_ = now_ns;
  ++stats_.state_messages;
  return s;
}

}  // namespace wall_effect_ekf
