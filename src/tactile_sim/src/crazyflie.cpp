#include "tactile_sim/crazyflie.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tactile_sim {
namespace {

void require(bool ok, const char* field, const char* reason, double value) {
  if (ok) return;
  std::ostringstream os;
  os << "CrazyflieParams." << field << ": " << reason << ", got " << value;
  throw std::invalid_argument(os.str());
}

void positive(const char* field, double v) { require(std::isfinite(v) && v > 0.0, field, "must be > 0", v); }
void non_negative(const char* field, double v) {
  require(std::isfinite(v) && v >= 0.0, field, "must be >= 0", v);
}

Quat euler_zyx(double roll, double pitch, double yaw) {
  return Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
              Eigen::AngleAxisd(roll, Vec3::UnitX()));
}

}  // namespace

void CrazyflieParams::validate() const {
  positive("mass", mass);
  positive("max_thrust_per_motor", max_thrust_per_motor);
  require(max_thrust() > mass * kGravity, "max_thrust_per_motor",
          "4 motors must lift the mass", max_thrust_per_motor);
  positive("motor_tau", motor_tau);
  non_negative("drag_coeff", drag_coeff);
  positive("yaw_inertia", yaw_inertia);
  positive("guard_radius", guard_radius);
  non_negative("collision_debounce", collision_debounce);
  whisker.validate();
  non_negative("whisker_spacing", whisker_spacing);
  require(std::isfinite(whisker_base_x), "whisker_base_x", "must be finite", whisker_base_x);
  non_negative("thrust_base", thrust_base);
  non_negative("vel_kp", vel_kp);
  non_negative("vel_ki", vel_ki);
  require(std::isfinite(max_tilt) && max_tilt > 0.0 && max_tilt < M_PI / 3, "max_tilt",
          "must be in (0, pi/3)", max_tilt);
  non_negative("z_kp", z_kp);
  non_negative("z_ki", z_ki);
  positive("vz_max", vz_max);
  non_negative("vz_kp", vz_kp);
  non_negative("vz_ki", vz_ki);
  positive("max_yaw_rate", max_yaw_rate);
  positive("land_speed", land_speed);
  non_negative("land_cutoff_height", land_cutoff_height);
  positive("attitude_wn", attitude_wn);
  positive("attitude_zeta", attitude_zeta);
  positive("yaw_rate_tau", yaw_rate_tau);
  non_negative("yaw_kp", yaw_kp);
  non_negative("yaw_ki", yaw_ki);
  non_negative("mocap_position_noise", mocap_position_noise);
  non_negative("mocap_velocity_noise", mocap_velocity_noise);
  non_negative("mocap_yaw_noise", mocap_yaw_noise);
  flow_deck.validate();
  contact.validate();
}

WhiskerCrazyflie::WhiskerCrazyflie(const CrazyflieParams& params, const RigidBodyState& initial,
                                   uint64_t seed)
    : p_(params),
      rng_(stream_seed(seed, crazyflie_streams::kMocap)),
      flow_deck_(params.flow_deck, seed),
      guard_contact_(params.contact),
      state_(initial) {
  p_.validate();
  yaw_ = initial.yaw();
  yaw_sp_ = yaw_;
  state_.orientation = euler_zyx(0.0, 0.0, yaw_);
  state_.angular_velocity.setZero();
  estimate_ = state_;
  flow_deck_.reset(state_);
  collisions_.reserve(8);
}

void WhiskerCrazyflie::set_setpoint(const HoverSetpoint& sp) {
  setpoint_ = sp;
  if (!sp.land && sp.height > 0.0) landing_done_ = false;
}

std::vector<CollisionEvent> WhiskerCrazyflie::take_collisions() {
  std::vector<CollisionEvent> out;
  out.swap(collisions_);
  collisions_.reserve(8);
  return out;
}

void WhiskerCrazyflie::control(double dt, double floor_z) {
  const bool want_flight = !landing_done_ && (setpoint_.land ? motors_on_ : setpoint_.height > 0.0);
  if (!want_flight) {
    motors_on_ = false;
    roll_cmd_ = pitch_cmd_ = thrust_cmd_ = 0.0;
    vx_int_ = vy_int_ = z_int_ = vz_int_ = 0.0;
    return;
  }
  if (!motors_on_) {
    motors_on_ = true;
    vx_int_ = vy_int_ = z_int_ = vz_int_ = 0.0;
  }
  const RigidBodyState& e = estimate_;
  const double yaw_e = e.yaw();
  const double c = std::cos(yaw_e), s = std::sin(yaw_e);
  // Velocity in the body-yaw frame (the hover setpoint's frame).
  const double vbx = c * e.velocity.x() + s * e.velocity.y();
  const double vby = -s * e.velocity.x() + c * e.velocity.y();
  const double height = e.position.z() - floor_z;

  // Horizontal velocity PID -> pitch/roll setpoints (firmware velocity PID, limited).
  const double ex = setpoint_.vx - vbx, ey = setpoint_.vy - vby;
  vx_int_ = std::clamp(vx_int_ + ex * dt, -p_.max_tilt / std::max(p_.vel_ki, 1e-9),
                       p_.max_tilt / std::max(p_.vel_ki, 1e-9));
  vy_int_ = std::clamp(vy_int_ + ey * dt, -p_.max_tilt / std::max(p_.vel_ki, 1e-9),
                       p_.max_tilt / std::max(p_.vel_ki, 1e-9));
  // Positive pitch (nose down, FLU) accelerates forward; positive roll accelerates to -y.
  pitch_cmd_ = std::clamp(p_.vel_kp * ex + p_.vel_ki * vx_int_, -p_.max_tilt, p_.max_tilt);
  roll_cmd_ = -std::clamp(p_.vel_kp * ey + p_.vel_ki * vy_int_, -p_.max_tilt, p_.max_tilt);

  // Height PID -> vz setpoint (limited) -> vz PID -> thrust.
  double vz_sp;
  if (setpoint_.land) {
    vz_sp = -p_.land_speed;
    if (height < p_.land_cutoff_height) {
      landing_done_ = true;
      motors_on_ = false;
      roll_cmd_ = pitch_cmd_ = thrust_cmd_ = 0.0;
      return;
    }
  } else {
    const double ez = setpoint_.height - height;
    z_int_ = std::clamp(z_int_ + ez * dt, -p_.vz_max / std::max(p_.z_ki, 1e-9),
                        p_.vz_max / std::max(p_.z_ki, 1e-9));
    vz_sp = std::clamp(p_.z_kp * ez + p_.z_ki * z_int_, -p_.vz_max, p_.vz_max);
  }
  const double evz = vz_sp - e.velocity.z();
  const double a_lim = p_.max_thrust() / p_.mass;
  vz_int_ = std::clamp(vz_int_ + evz * dt, -a_lim / std::max(p_.vz_ki, 1e-9),
                       a_lim / std::max(p_.vz_ki, 1e-9));
  thrust_cmd_ = std::clamp(p_.thrust_base + p_.mass * (p_.vz_kp * evz + p_.vz_ki * vz_int_), 0.0,
                           p_.max_thrust());
}

void WhiskerCrazyflie::sense_whiskers(const Arena& arena) {
  const Vec2 fwd(std::cos(yaw_), std::sin(yaw_));
  const Vec2 left(-fwd.y(), fwd.x());
  const Vec2 p(state_.position.x(), state_.position.y());
  const Vec2 v(state_.velocity.x(), state_.velocity.y());
  external_yaw_moment_ = 0.0;
  Vec2 force = Vec2::Zero();
  for (int i = 0; i < 2; ++i) {
    const double side = (i == 0 ? 0.5 : -0.5) * p_.whisker_spacing;
    const Vec2 r = p_.whisker_base_x * fwd + side * left;  // base relative to the CoM
    const Vec2 base = p + r;
    WhiskerContact& wc = whisker_detail_[i];
    if (p_.whiskers_enabled) {
      const Vec2 tip = base + p_.whisker.horizontal_reach() * fwd;
      const Hit h = arena.first_hit(base, tip);
      const double mu = h.hit ? arena.material(h.material).friction : 0.0;
      const Vec2 v_base = v + yaw_rate_ * Vec2(-r.y(), r.x());
      wc = whisker_contact(p_.whisker, base, fwd, v_base, h.hit, h.distance, h.point, h.normal, mu,
                           h.obstacle_id);
    } else {
      wc = WhiskerContact{};
      wc.base = base;
      wc.tip = wc.contact_point = base;
    }
    Whisker& w = whiskers_[i];
    w.contact = wc.contact;
    w.base = wc.base;
    w.tip = wc.tip;
    w.contact_point = wc.contact_point;
    w.depth = wc.depth;
    w.normal_force = wc.normal_force;
    w.friction_force = wc.friction_force;
    w.base_moment = wc.base_moment;
    w.obstacle_id = wc.obstacle_id;
    if (wc.contact) {
      force += wc.force_on_body;
      // Yaw moment of the reaction about the CoM, applied at the contact point.
      const Vec2 arm = wc.contact_point - p;
      external_yaw_moment_ += arm.x() * wc.force_on_body.y() - arm.y() * wc.force_on_body.x();
    }
  }
  external_force_ = Vec3(force.x(), force.y(), 0.0);
}

void WhiskerCrazyflie::update_estimate(double dt, const Vec3& accel_world, double floor_z) {
  if (p_.estimate_mode != StateEstimateMode::kMocap) {
    flow_deck_.step(dt, state_, accel_world, floor_z);
    estimate_ = flow_deck_.estimate();
    return;
  }
  estimate_ = state_;
  for (int i = 0; i < 3; ++i) {
    estimate_.position[i] += p_.mocap_position_noise * n01_(rng_);
    estimate_.velocity[i] += p_.mocap_velocity_noise * n01_(rng_);
  }
  const double dyaw = p_.mocap_yaw_noise * n01_(rng_);
  estimate_.orientation =
      (Quat(Eigen::AngleAxisd(dyaw, Vec3::UnitZ())) * state_.orientation).normalized();
}

void WhiskerCrazyflie::step(double dt, const Arena& arena) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("WhiskerCrazyflie::step: dt must be > 0");
  const double floor_z = arena.floor_z();
  control(dt, floor_z);

  // Closed-loop attitude: second-order lag of roll/pitch to their setpoints.
  const double wn2 = p_.attitude_wn * p_.attitude_wn, zw2 = 2.0 * p_.attitude_zeta * p_.attitude_wn;
  const double roll_cmd = motors_on_ ? roll_cmd_ : 0.0, pitch_cmd = motors_on_ ? pitch_cmd_ : 0.0;
  roll_rate_ += (wn2 * (roll_cmd - roll_) - zw2 * roll_rate_) * dt;
  pitch_rate_ += (wn2 * (pitch_cmd - pitch_) - zw2 * pitch_rate_) * dt;
  roll_ += roll_rate_ * dt;
  pitch_ += pitch_rate_ * dt;

  // Contact forces (whiskers, then the guard circle).
  sense_whiskers(arena);
  const Vec2 p2(state_.position.x(), state_.position.y());
  const Vec2 v2(state_.velocity.x(), state_.velocity.y());
  const ContactResult gc = guard_contact_.step(arena, p2, p_.guard_radius, v2);
  if (gc.contact) external_force_ += Vec3(gc.force.x(), gc.force.y(), 0.0);
  const bool guard_touching = gc.contact || guard_contact_.in_episode();
  // Bounces of one impact (the velocity controller pushes the guard back
  // against the wall) merge into one event: a new one needs collision_debounce
  // seconds without contact.
  if (gc.began && time_ - last_guard_contact_time_ > p_.collision_debounce) {
    CollisionEvent ev;
    ev.time_s = time_ + dt;
    ev.part = "guard";
    ev.point = gc.point;
    ev.normal = gc.normal;
    ev.impact_speed = gc.impact_speed;
    ev.obstacle_id = gc.obstacle_id;
    collisions_.push_back(ev);
  }
  if (guard_touching) last_guard_contact_time_ = time_ + dt;

  // Yaw. As in the Crazyflie firmware's PID controller in hover mode, the
  // yaw-rate setpoint is integrated into a yaw-angle setpoint that the
  // attitude PI loop holds (so the whisker friction's yaw moment, 000 Fig. 2a
  // M_yaw, leaves no lasting heading error); the closed inner rate loop is a
  // first-order lag disturbed by that moment.
  const double yaw_rate_cmd =
      motors_on_ ? std::clamp(setpoint_.yaw_rate, -p_.max_yaw_rate, p_.max_yaw_rate) : 0.0;
  const bool airborne = motors_on_ || state_.position.z() > floor_z + 1e-6;
  if (airborne) {
    yaw_sp_ += yaw_rate_cmd * dt;
    const double yaw_err = std::remainder(yaw_sp_ - yaw_, 2.0 * M_PI);
    yaw_int_ += yaw_err * dt;
    const double rate_cmd = std::clamp(yaw_rate_cmd + p_.yaw_kp * yaw_err + p_.yaw_ki * yaw_int_,
                                       -p_.max_yaw_rate, p_.max_yaw_rate);
    yaw_rate_ += ((rate_cmd - yaw_rate_) / p_.yaw_rate_tau + external_yaw_moment_ / p_.yaw_inertia) * dt;
  } else {
    yaw_rate_ = 0.0;
    yaw_sp_ = yaw_;
    yaw_int_ = 0.0;
  }
  yaw_ += yaw_rate_ * dt;

  // Motor thrust lag.
  thrust_ += (thrust_cmd_ - thrust_) * dt / p_.motor_tau;
  thrust_ = std::clamp(thrust_, 0.0, p_.max_thrust());

  // Translational dynamics: m a = R e3 T - m g e3 - c v + F_ext.
  const Quat q = euler_zyx(roll_, pitch_, yaw_);
  const Vec3 thrust_world = q * Vec3(0.0, 0.0, thrust_);
  Vec3 force = thrust_world - p_.drag_coeff * state_.velocity + external_force_;
  force.z() -= p_.mass * kGravity;
  Vec3 acc = force / p_.mass;
  Vec3 v = state_.velocity + acc * dt;
  Vec3 pos = state_.position + v * dt;
  bool attitude_reset = false;
  // Floor: no penetration; resting on it stops all motion.
  if (pos.z() <= floor_z) {
    pos.z() = floor_z;
    if (v.z() < 0.0) v.z() = 0.0;
    if (thrust_world.z() < p_.mass * kGravity) {
      v.setZero();
      roll_ = pitch_ = roll_rate_ = pitch_rate_ = 0.0;
      attitude_reset = true;
    }
    acc = (v - state_.velocity) / dt;
  }
  state_.position = pos;
  state_.velocity = v;
  // q unless the floor zeroed roll and pitch: the same angles give the same quaternion, and
  // its three sincos were 1.9 % of a whisker flight's CPU (issue 18).
  state_.orientation = attitude_reset ? euler_zyx(roll_, pitch_, yaw_) : q;
  // Body rates from ZYX Euler rates.
  const double sr = std::sin(roll_), cr = std::cos(roll_), sp = std::sin(pitch_),
               cp = std::cos(pitch_);
  state_.angular_velocity = Vec3(roll_rate_ - yaw_rate_ * sp, pitch_rate_ * cr + yaw_rate_ * sr * cp,
                                 -pitch_rate_ * sr + yaw_rate_ * cr * cp);
  specific_force_body_ = state_.orientation.conjugate() * (acc + Vec3(0.0, 0.0, kGravity));
  time_ += dt;
  update_estimate(dt, acc, floor_z);
}

}  // namespace tactile_sim
