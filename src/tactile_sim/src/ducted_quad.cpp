// Ducted quadrotor (004), the shared cascaded controller and rigid-body step;
// see ducted_quad.hpp and docs/physics.md.
#include "tactile_sim/ducted_quad.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace tactile_sim {
namespace {

[[noreturn]] void bad(const char* type, const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << type << "." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const char* t, const std::string& f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(t, f, "must be > 0", v);
}
void non_negative(const char* t, const std::string& f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(t, f, "must be >= 0", v);
}
void non_negative3(const char* t, const char* f, const Vec3& v) {
  for (int i = 0; i < 3; ++i) non_negative(t, std::string(f) + "[" + std::to_string(i) + "]", v[i]);
}
void positive3(const char* t, const char* f, const Vec3& v) {
  for (int i = 0; i < 3; ++i) positive(t, std::string(f) + "[" + std::to_string(i) + "]", v[i]);
}
double clampd(double v, double lim) { return std::clamp(v, -lim, lim); }

}  // namespace

// --- controller ----------------------------------------------------------------

void CascadedControllerParams::validate() const {
  const char* t = "CascadedControllerParams";
  non_negative3(t, "pos_p", pos_p);
  non_negative3(t, "vel_p", vel_p);
  non_negative3(t, "vel_i", vel_i);
  non_negative3(t, "vel_d", vel_d);
  non_negative(t, "vel_i_limit", vel_i_limit);
  positive(t, "max_speed_xy", max_speed_xy);
  positive(t, "max_speed_z", max_speed_z);
  if (!(max_tilt > 0.0 && max_tilt < 1.4)) bad(t, "max_tilt", "must be in (0, 1.4) rad", max_tilt);
  non_negative3(t, "att_p", att_p);
  non_negative3(t, "rate_p", rate_p);
  non_negative3(t, "rate_i", rate_i);
  non_negative3(t, "rate_d", rate_d);
  non_negative(t, "rate_i_limit", rate_i_limit);
  positive3(t, "max_rate", max_rate);
  if (desaturation != TorqueDesaturation::kScaleAll && desaturation != TorqueDesaturation::kYawFirst)
    bad(t, "desaturation", "must be kScaleAll or kYawFirst", static_cast<double>(desaturation));
}

CascadedController::CascadedController(const CascadedControllerParams& params, double mass,
                                       const Mat3& inertia)
    : p_(params), mass_(mass), inertia_(inertia) {
  p_.validate();
}

void CascadedController::reset() {
  vel_int_.setZero();
  rate_int_.setZero();
  prev_vel_err_.setZero();
  prev_rate_.setZero();
  first_ = true;
}

CascadedController::Output CascadedController::update(const RigidBodyState& s,
                                                      const PositionSetpoint& sp, double dt,
                                                      bool landed) {
  Output out;
  // Position P -> velocity setpoint (limited).
  Vec3 v_sp = p_.pos_p.cwiseProduct(sp.position - s.position) + sp.velocity_ff;
  const double vxy = v_sp.head<2>().norm();
  if (vxy > p_.max_speed_xy) v_sp.head<2>() *= p_.max_speed_xy / vxy;
  v_sp.z() = clampd(v_sp.z(), p_.max_speed_z);
  // Velocity PID -> acceleration.
  const Vec3 e_v = v_sp - s.velocity;
  vel_int_ += p_.vel_i.cwiseProduct(e_v) * dt;
  for (int i = 0; i < 3; ++i) vel_int_[i] = clampd(vel_int_[i], p_.vel_i_limit);
  const Vec3 d_v = first_ ? Vec3::Zero() : Vec3((e_v - prev_vel_err_) / dt);
  prev_vel_err_ = e_v;
  if (landed) vel_int_.head<2>().setZero();
  Vec3 a = p_.vel_p.cwiseProduct(e_v) + vel_int_ + p_.vel_d.cwiseProduct(d_v);
  if (landed) a.head<2>().setZero();
  a.z() += kGravity;  // thrust must carry the weight (ENU, z up)
  // Tilt limit: keep a minimum upward component and |a_xy| <= tan(max_tilt) a_z.
  a.z() = std::max(a.z(), 0.2 * kGravity);
  const double axy = a.head<2>().norm(), axy_max = std::tan(p_.max_tilt) * a.z();
  if (axy > axy_max) a.head<2>() *= axy_max / axy;
  out.accel_world = a;

  const Mat3 R = s.orientation.toRotationMatrix();
  out.thrust = std::max(0.0, mass_ * a.dot(R.col(2)));  // collective along the current z_B

  // Desired attitude: z_B along a, heading sp.yaw.
  const Vec3 z_d = a.normalized();
  const Vec3 x_c(std::cos(sp.yaw), std::sin(sp.yaw), 0.0);
  Vec3 y_d = z_d.cross(x_c);
  if (y_d.norm() < 1e-6) y_d = z_d.cross(Vec3::UnitX());
  y_d.normalize();
  Mat3 R_d;
  R_d.col(0) = y_d.cross(z_d);
  R_d.col(1) = y_d;
  R_d.col(2) = z_d;
  Quat q_e = s.orientation.conjugate() * Quat(R_d);  // attitude error in the body frame
  if (q_e.w() < 0.0) q_e.coeffs() *= -1.0;
  // Attitude P (quaternion error) -> body-rate setpoint.
  Vec3 w_sp = 2.0 * p_.att_p.cwiseProduct(q_e.vec());
  for (int i = 0; i < 3; ++i) w_sp[i] = clampd(w_sp[i], p_.max_rate[i]);
  out.rate_setpoint = w_sp;
  // Rate PID -> angular acceleration -> torque (J alpha + w x J w).
  const Vec3& w = s.angular_velocity;
  const Vec3 e_w = w_sp - w;
  rate_int_ += p_.rate_i.cwiseProduct(e_w) * dt;
  if (landed) rate_int_.setZero();
  for (int i = 0; i < 3; ++i) rate_int_[i] = clampd(rate_int_[i], p_.rate_i_limit);
  const Vec3 dw = first_ ? Vec3::Zero() : Vec3((w - prev_rate_) / dt);
  prev_rate_ = w;
  first_ = false;
  const Vec3 alpha = p_.rate_p.cwiseProduct(e_w) + rate_int_ - p_.rate_d.cwiseProduct(dw);
  out.torque = inertia_ * alpha + w.cross(inertia_ * w);
  return out;
}

namespace {

/// Largest s in [0, 1] with 0 <= base + s d <= max for every rotor.
double feasible_scale(const Eigen::Vector4d& base, const Eigen::Vector4d& d, double max_thrust) {
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (d[i] > 0.0) s = std::min(s, std::max(0.0, (max_thrust - base[i]) / d[i]));
    if (d[i] < 0.0) s = std::min(s, std::max(0.0, -base[i] / d[i]));
  }
  return s;
}

}  // namespace

std::array<double, 4> allocate_rotors(const RotorGeometry& g, double thrust, const Vec3& torque,
                                      double max_thrust, TorqueDesaturation mode) {
  // Rows: T = sum f_i; tau = sum (r_i x f_i e3 + s_i c_tau f_i e3) (004 eq. 7, no wall).
  Eigen::Matrix4d M;
  for (int i = 0; i < 4; ++i) {
    const Vec3& r = g.position_body[i];
    M(0, i) = 1.0;
    M(1, i) = r.y();
    M(2, i) = -r.x();
    M(3, i) = g.spin_sign[i] * g.torque_coefficient;
  }
  const Eigen::Matrix4d Minv = M.inverse();
  thrust = std::clamp(thrust, 0.0, 4.0 * max_thrust);
  const Eigen::Vector4d f_t = Minv * Eigen::Vector4d(thrust, 0.0, 0.0, 0.0);
  std::array<double, 4> out{};
  if (mode == TorqueDesaturation::kYawFirst) {
    // Roll/pitch within what the rotors can give at this thrust, then yaw in what is left.
    const Eigen::Vector4d f_rp = Minv * Eigen::Vector4d(0.0, torque.x(), torque.y(), 0.0);
    const Eigen::Vector4d f_yaw = Minv * Eigen::Vector4d(0.0, 0.0, 0.0, torque.z());
    const Eigen::Vector4d base = f_t + feasible_scale(f_t, f_rp, max_thrust) * f_rp;
    const double s_yaw = feasible_scale(base, f_yaw, max_thrust);
    for (int i = 0; i < 4; ++i) out[i] = std::clamp(base[i] + s_yaw * f_yaw[i], 0.0, max_thrust);
    return out;
  }
  const Eigen::Vector4d f_tau = Minv * Eigen::Vector4d(0.0, torque.x(), torque.y(), torque.z());
  const double s = feasible_scale(f_t, f_tau, max_thrust);
  for (int i = 0; i < 4; ++i) out[i] = std::clamp(f_t[i] + s * f_tau[i], 0.0, max_thrust);
  return out;
}

namespace detail {

Quat yaw_only(const Quat& q) {
  const Vec3 x = q * Vec3::UnitX();
  return Quat(Eigen::AngleAxisd(std::atan2(x.y(), x.x()), Vec3::UnitZ()));
}

void integrate_rigid_body(RigidBodyState& s, double mass, const Mat3& inertia, const Vec3& f_world,
                          const Vec3& tau_body, double dt, double floor_z) {
  // Translational (004 eq. 6 / 001 eq. 1a in ENU): m p_dd = f_world (gravity included).
  s.velocity += f_world / mass * dt;
  s.position += s.velocity * dt;
  // Rotational (004 eq. 8 / 001 eq. 1b): J w_dot + w x J w = tau.
  const Vec3& w = s.angular_velocity;
  s.angular_velocity += inertia.inverse() * (tau_body - w.cross(inertia * w)) * dt;
  const Vec3 dphi = s.angular_velocity * dt;
  const double a = dphi.norm();
  if (a > 0.0) s.orientation = s.orientation * Quat(Eigen::AngleAxisd(a, dphi / a));
  s.orientation.normalize();
  // Flat floor: resting contact, the vehicle sits level until it lifts off.
  if (s.position.z() < floor_z) {
    s.position.z() = floor_z;
    s.velocity.setZero();
    s.angular_velocity.setZero();
    s.orientation = yaw_only(s.orientation);
  }
}

}  // namespace detail

// --- ducted quadrotor ------------------------------------------------------------

void DuctedQuadParams::validate() const {
  const char* t = "DuctedQuadParams";
  positive(t, "mass", mass);
  positive3(t, "inertia_diag", inertia_diag);
  positive(t, "rotor_offset", rotor_offset);
  non_negative(t, "torque_coefficient", torque_coefficient);
  positive(t, "max_rotor_thrust", max_rotor_thrust);
  if (4.0 * max_rotor_thrust <= mass * kGravity)
    bad(t, "max_rotor_thrust", "four rotors cannot carry the weight", max_rotor_thrust);
  positive(t, "motor_time_constant", motor_time_constant);
  non_negative(t, "linear_drag", linear_drag);
  positive(t, "guard_radius", guard_radius);
  positive(t, "wall_truth_range", wall_truth_range);
  wall_effect.validate();
  controller.validate();
  contact.validate();
}

DuctedQuad::DuctedQuad(const DuctedQuadParams& params, const RigidBodyState& initial)
    : p_((params.validate(), params)),
      inertia_(params.inertia_diag.asDiagonal()),
      controller_(params.controller, params.mass, inertia_),
      state_(initial),
      guards_{CircleContact(params.contact), CircleContact(params.contact),
              CircleContact(params.contact), CircleContact(params.contact)} {
  const double L = p_.rotor_offset;
  // Counter-clockwise from front-right; spins (-1)^(i+1) of 004 eq. 7.
  geometry_.position_body = {Vec3(L, -L, 0), Vec3(L, L, 0), Vec3(-L, L, 0), Vec3(-L, -L, 0)};
  geometry_.spin_sign = {1.0, -1.0, 1.0, -1.0};
  geometry_.torque_coefficient = p_.torque_coefficient;
  setpoint_.position = initial.position;
  setpoint_.yaw = initial.yaw();
  wall_truth_.distance = std::numeric_limits<double>::infinity();
  wall_truth_.height = initial.position.z();
  collisions_.reserve(16);
}

void DuctedQuad::set_rotor_thrusts(const std::array<double, 4>& thrust) {
  for (int i = 0; i < 4; ++i)
    command_[i] = std::isfinite(thrust[i]) ? std::clamp(thrust[i], 0.0, p_.max_rotor_thrust) : 0.0;
  external_ = true;
}

void DuctedQuad::set_position_setpoint(const PositionSetpoint& sp) {
  if (external_) controller_.reset();
  setpoint_ = sp;
  external_ = false;
}

double DuctedQuad::collective_thrust() const {
  return thrust_[0] + thrust_[1] + thrust_[2] + thrust_[3];
}

std::vector<CollisionEvent> DuctedQuad::take_collisions() {
  std::vector<CollisionEvent> out;
  out.swap(collisions_);
  collisions_.reserve(16);
  return out;
}

void DuctedQuad::step(double dt, const Arena& arena) {
  if (!(dt > 0.0)) throw std::invalid_argument("DuctedQuad::step: dt must be > 0");
  time_ += dt;
  if (!external_) {
    const CascadedController::Output u = controller_.update(state_, setpoint_, dt, landed_);
    command_ = allocate_rotors(geometry_, u.thrust, u.torque, p_.max_rotor_thrust);
  }
  // First-order motors (exact discretisation).
  const double k = 1.0 - std::exp(-dt / p_.motor_time_constant);
  for (int i = 0; i < 4; ++i) thrust_[i] += (command_[i] - thrust_[i]) * k;

  const Mat3 R = state_.orientation.toRotationMatrix();
  const Vec3& p = state_.position;
  // Per-rotor wall: y_i = distance of the rotor centre to the wall minus R (004, before eq. 5).
  const double Rr = p_.wall_effect.rotor_radius;
  const double query = Rr * (1.0 + p_.wall_effect.cutoff_normalized);
  std::array<Vec3, 4> rotor_world;
  for (int i = 0; i < 4; ++i) {
    rotor_world[i] = p + R * geometry_.position_body[i];
    rotor_walls_[i] = RotorWall{};
    if (!p_.wall_effect_enabled) continue;
    const Hit h = arena.closest(rotor_world[i].head<2>(), query);
    if (h.hit) {
      rotor_walls_[i].present = true;
      rotor_walls_[i].distance = h.distance - Rr;
      rotor_walls_[i].normal_world = Vec3(h.normal.x(), h.normal.y(), 0.0);
    }
  }
  const RotorWrench w = rotor_wrench(thrust_, R, geometry_, rotor_walls_, p_.wall_effect);  // 004 eq. 5-7
  wall_force_ = w.force_world - collective_thrust() * R.col(2);

  // Duct guards: penalty contact per duct; one impact event per guard episode.
  bool guard_was_in_contact = false;
  for (const CircleContact& g : guards_) guard_was_in_contact |= g.in_episode();
  bool logged = false;
  contact_force_.setZero();
  Vec3 contact_torque_world = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    const Vec3 v_i = state_.velocity + R * state_.angular_velocity.cross(geometry_.position_body[i]);
    const ContactResult c =
        guards_[i].step(arena, rotor_world[i].head<2>(), p_.guard_radius, v_i.head<2>());
    if (!c.contact) continue;
    const Vec3 f(c.force.x(), c.force.y(), 0.0);
    const Vec3 at(c.point.x(), c.point.y(), rotor_world[i].z());
    contact_force_ += f;
    contact_torque_world += (at - p).cross(f);
    if (c.began && !guard_was_in_contact && !logged) {
      collisions_.push_back(
          CollisionEvent{time_, "guard", c.point, c.normal, c.impact_speed, c.obstacle_id});
      logged = true;
    }
  }

  const Vec3 f_world = w.force_world + contact_force_ - p_.linear_drag * state_.velocity -
                       p_.mass * kGravity * Vec3::UnitZ();
  const Vec3 tau_body = w.torque_body + R.transpose() * contact_torque_world;  // 004 eq. 8
  const Vec3 v_old = state_.velocity;
  detail::integrate_rigid_body(state_, p_.mass, inertia_, f_world, tau_body, dt, arena.floor_z());
  landed_ = state_.position.z() <= arena.floor_z();
  specific_force_body_ = state_.orientation.conjugate() *
                         Vec3((state_.velocity - v_old) / dt + kGravity * Vec3::UnitZ());

  // Wall ground truth from the new state.
  wall_truth_ = WallTruth{};
  wall_truth_.distance = std::numeric_limits<double>::infinity();
  wall_truth_.height = state_.position.z() - arena.floor_z();
  const Hit h = arena.closest(state_.position.head<2>(), p_.wall_truth_range);
  if (h.hit) {
    wall_truth_.present = true;
    wall_truth_.distance = h.distance;
    const Vec3 to_wall(-h.normal.x(), -h.normal.y(), 0.0);
    wall_truth_.direction_body = state_.orientation.conjugate() * to_wall;
    wall_truth_.direction = std::atan2(wall_truth_.direction_body.y(), wall_truth_.direction_body.x());
    wall_truth_.obstacle_id = h.obstacle_id;
  }
}

}  // namespace tactile_sim
