// XPLORER (001): compliant arms, cascaded control, arm IMUs; see xplorer.hpp
// and docs/physics.md.
#include "tactile_sim/xplorer.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tactile_sim {
namespace {

[[noreturn]] void bad(const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << "XplorerParams." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const std::string& f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(f, "must be > 0", v);
}
void non_negative(const std::string& f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(f, "must be >= 0", v);
}
Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

}  // namespace

CascadedControllerParams XplorerParams::default_controller() {
  CascadedControllerParams c;
  c.pos_p = Vec3(1.5, 1.5, 2.0);
  c.vel_p = Vec3(4.0, 4.0, 5.0);
  c.vel_i = Vec3(1.0, 1.0, 2.0);
  c.att_p = Vec3(8.0, 8.0, 4.0);
  c.rate_p = Vec3(20.0, 20.0, 10.0);
  c.rate_i = Vec3(5.0, 5.0, 3.0);
  c.rate_d = Vec3(0.2, 0.2, 0.0);
  // Roll/pitch before yaw in the allocation (PX4's mixer order; 001 flies a
  // PIXHAWK; our choice): the arms' springs pass contact yaw torques (up to 0.68 N m per
  // arm at the 30 deg stop) that the rotors cannot match (~0.18 N m at
  // hover); scaling every axis alike gave up the attitude with the yaw and
  // the vehicle sank in contact (docs/tuning/tactile_fsm.md, "Height lost in contact").
  c.desaturation = TorqueDesaturation::kYawFirst;
  return c;
}

void XplorerParams::validate() const {
  positive("mass", mass);
  for (int i = 0; i < 3; ++i) positive("inertia_diag[" + std::to_string(i) + "]", inertia_diag[i]);
  non_negative("hinge_offset", hinge_offset);
  positive("arm_length", arm_length);
  positive("arm_inertia", arm_inertia);
  non_negative("arm_damping", arm_damping);
  positive("arm_stiffness", arm_stiffness);
  if (!(arm_max_deflection > 0.0 && arm_max_deflection < M_PI / 2))
    bad("arm_max_deflection", "must be in (0, pi/2)", arm_max_deflection);
  non_negative("end_stop_stiffness", end_stop_stiffness);
  non_negative("end_stop_damping", end_stop_damping);
  positive("guard_radius", guard_radius);
  positive("body_radius", body_radius);
  positive("thrust_scale", thrust_scale);
  if (thrust_scale <= mass * kGravity) bad("thrust_scale", "cannot carry the weight", thrust_scale);
  if (!(thrust_curve_factor >= 0.0 && thrust_curve_factor <= 1.0))
    bad("thrust_curve_factor", "must be in [0, 1]", thrust_curve_factor);
  non_negative("torque_coefficient", torque_coefficient);
  positive("motor_time_constant", motor_time_constant);
  non_negative("linear_drag", linear_drag);
  non_negative("arm_imu_position", arm_imu_position);
  if (arm_imu_position > arm_length) bad("arm_imu_position", "must be <= arm_length", arm_imu_position);
  positive("arm_imu_rate_hz", arm_imu_rate_hz);
  controller.validate();
  contact.validate();
}

Xplorer::Xplorer(const XplorerParams& params, const RigidBodyState& initial)
    : p_((params.validate(), params)),
      inertia_(params.inertia_diag.asDiagonal()),
      controller_(params.controller, params.mass, inertia_),
      state_(initial),
      arm_contacts_{CircleContact(params.contact), CircleContact(params.contact),
                    CircleContact(params.contact), CircleContact(params.contact)},
      body_contact_(params.contact) {
  arm_dir_ = kArmDirections;
  nominal_.spin_sign = {1.0, -1.0, 1.0, -1.0};
  nominal_.torque_coefficient = p_.torque_coefficient;
  for (int i = 0; i < 4; ++i) nominal_.position_body[i] = arm_point_body(i, p_.arm_length);
  // Thrust curve through the hover point: 4 T_max ((1 - f) u_h + f u_h^2) = m g, u_h = m g / thrust_scale.
  const double u_h = p_.mass * kGravity / p_.thrust_scale, f = p_.thrust_curve_factor;
  rotor_max_ = 0.25 * p_.mass * kGravity / ((1.0 - f) * u_h + f * u_h * u_h);
  setpoint_.position = initial.position;
  setpoint_.yaw = initial.yaw();
  collisions_.reserve(16);
}

void Xplorer::set_setpoint(const PositionSetpoint& sp) { setpoint_ = sp; }

Vec3 Xplorer::arm_point_body(int i, double s) const {
  const double a = arm_dir_[i];
  const double b = a + theta_[i];
  return Vec3(p_.hinge_offset * std::cos(a) + s * std::cos(b),
              p_.hinge_offset * std::sin(a) + s * std::sin(b), 0.0);
}

RotorGeometry Xplorer::geometry() const {
  RotorGeometry g = nominal_;
  for (int i = 0; i < 4; ++i) g.position_body[i] = arm_point_body(i, p_.arm_length);
  return g;
}

double Xplorer::rotor_static_thrust(double u) const {
  const double f = p_.thrust_curve_factor, c = std::clamp(u, 0.0, 1.0);
  return rotor_max_ * ((1.0 - f) * c + f * c * c);
}

double Xplorer::collective_thrust() const { return thrust_[0] + thrust_[1] + thrust_[2] + thrust_[3]; }

std::vector<CollisionEvent> Xplorer::take_collisions() {
  std::vector<CollisionEvent> out;
  out.swap(collisions_);
  collisions_.reserve(16);
  return out;
}

ArmImuTruth Xplorer::arm_imu(int i) const {
  if (i < 0 || i > 3) throw std::out_of_range("Xplorer::arm_imu: arm index must be 0..3");
  ArmImuTruth t;
  t.angle = theta_[i];
  t.rate = theta_dot_[i];
  const Mat3 Rz = rot_z(arm_dir_[i] + theta_[i]);  // arm frame -> body frame
  const Mat3 R = state_.orientation.toRotationMatrix();
  t.orientation = state_.orientation * Quat(Rz);
  const Vec3& w = state_.angular_velocity;
  t.gyro = Rz.transpose() * (w + theta_dot_[i] * Vec3::UnitZ());
  // Acceleration of a point on a hinged arm (body frame components):
  // a = a_cm + w_dot x r + w x (w x r) + 2 w x v_rel + a_rel,
  // v_rel = theta_d e3 x rho, a_rel = theta_dd e3 x rho - theta_d^2 rho.
  const Vec3 r = arm_point_body(i, p_.arm_imu_position);
  const double a0 = arm_dir_[i];
  const Vec3 rho = r - Vec3(p_.hinge_offset * std::cos(a0), p_.hinge_offset * std::sin(a0), 0.0);
  const Vec3 v_rel = theta_dot_[i] * Vec3::UnitZ().cross(rho);
  const Vec3 a_rel = theta_ddot_[i] * Vec3::UnitZ().cross(rho) - theta_dot_[i] * theta_dot_[i] * rho;
  const Vec3 a_b = R.transpose() * accel_world_ + ang_accel_body_.cross(r) + w.cross(w.cross(r)) +
                   2.0 * w.cross(v_rel) + a_rel;
  t.accel = Rz.transpose() * (a_b + R.transpose() * (kGravity * Vec3::UnitZ()));  // specific force
  return t;
}

void Xplorer::step(double dt, const Arena& arena) {
  if (!(dt > 0.0)) throw std::invalid_argument("Xplorer::step: dt must be > 0");
  time_ += dt;
  const double max_rotor = p_.thrust_scale / 4.0;
  // Cascaded P-PID (001 Sec. II) with the nominal (undeflected) allocation:
  // the paper relies on the controller's robustness to the small geometry change.
  const CascadedController::Output u = controller_.update(state_, setpoint_, dt, landed_);
  command_ = allocate_rotors(nominal_, u.thrust, u.torque, max_rotor, p_.controller.desaturation);
  thrust_command_ = (command_[0] + command_[1] + command_[2] + command_[3]) / p_.thrust_scale;  // 001 V-A3
  const double km = 1.0 - std::exp(-dt / p_.motor_time_constant);
  for (int i = 0; i < 4; ++i) {
    // 001 Sec. V-A3: the firmware's normalised command; the rotor's static thrust curve (see thrust_curve_factor).
    thrust_[i] += (rotor_static_thrust(command_[i] / max_rotor) - thrust_[i]) * km;
  }

  const Mat3 R = state_.orientation.toRotationMatrix();
  const Vec3& p = state_.position;
  const Vec3& w = state_.angular_velocity;
  // Rotor thrusts at the deflected motor positions (004 eq. 7 form, no wall effect).
  const std::array<RotorWall, 4> no_walls{};
  const RotorWrench rw = rotor_wrench(thrust_, R, geometry(), no_walls);

  contact_force_.setZero();
  Vec3 torque_body = rw.torque_body;
  Vec3 tip_force_world = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    const double a0 = arm_dir_[i];
    const Vec3 hinge(p_.hinge_offset * std::cos(a0), p_.hinge_offset * std::sin(a0), 0.0);
    const Vec3 tip = arm_point_body(i, p_.arm_length);
    const Vec3 rho = tip - hinge;
    const Vec3 tip_w = p + R * tip;
    const Vec3 v_tip = state_.velocity + R * (w.cross(tip) + theta_dot_[i] * Vec3::UnitZ().cross(rho));
    const ContactResult c = arm_contacts_[i].step(arena, tip_w.head<2>(), p_.guard_radius, v_tip.head<2>());
    arm_force_[i] = Vec3(c.force.x(), c.force.y(), 0.0);
    double tau_hinge = arm_ext_torque_[i];
    if (!arm_tip_force_[i].isZero()) {  // test/fault push at the motor location
      tau_hinge += rho.cross(arm_tip_force_[i]).z();
      torque_body += hinge.cross(arm_tip_force_[i]);
      tip_force_world += R * arm_tip_force_[i];
    }
    if (c.contact) {
      const Vec3 f_b = R.transpose() * arm_force_[i];
      // 001 eq. 2: the contact force acts at the motor location (001 Sec. III-A1);
      // its moment about the hinge drives the arm, the force itself reaches the body at the hinge.
      tau_hinge += rho.cross(f_b).z();
      torque_body += hinge.cross(f_b);
      contact_force_ += arm_force_[i];
      if (c.began) {
        collisions_.push_back(CollisionEvent{time_, "arm" + std::to_string(i), c.point, c.normal,
                                             c.impact_speed, c.obstacle_id});
      }
    }
    if (p_.rigid_arms) {  // 001 Sec. V-C4: rigid chassis, the hinge moment goes to the body
      torque_body += rho.cross(c.contact ? Vec3(R.transpose() * arm_force_[i]) : Vec3::Zero()) +
                     rho.cross(arm_tip_force_[i]) + arm_ext_torque_[i] * Vec3::UnitZ();
      theta_[i] = theta_dot_[i] = theta_ddot_[i] = 0.0;
      continue;
    }
    // 001 eq. 2: J_zz theta_dd + b theta_d + k theta = tau, plus end stops at +-30 deg.
    double tau_spring = -p_.arm_stiffness * theta_[i] - p_.arm_damping * theta_dot_[i];
    const double over = std::abs(theta_[i]) - p_.arm_max_deflection;
    if (over > 0.0) {
      const double sgn = theta_[i] > 0.0 ? 1.0 : -1.0;
      tau_spring -= sgn * p_.end_stop_stiffness * over;
      if (sgn * theta_dot_[i] > 0.0) tau_spring -= p_.end_stop_damping * theta_dot_[i];
    }
    theta_ddot_[i] = (tau_hinge + tau_spring) / p_.arm_inertia;
    theta_dot_[i] += theta_ddot_[i] * dt;
    theta_[i] += theta_dot_[i] * dt;
    torque_body.z() -= tau_spring;  // reaction of the hinge spring/damper on the body
  }
  const ContactResult cb = body_contact_.step(arena, p.head<2>(), p_.body_radius, state_.velocity.head<2>());
  if (cb.contact) {
    const Vec3 f(cb.force.x(), cb.force.y(), 0.0);
    contact_force_ += f;
    torque_body += R.transpose() * (Vec3(cb.point.x(), cb.point.y(), p.z()) - p).cross(f);
    if (cb.began)
      collisions_.push_back(CollisionEvent{time_, "body", cb.point, cb.normal, cb.impact_speed, cb.obstacle_id});
  }

  // 001 eq. 1a/1b (ENU: thrust along +z_B, gravity -z).
  const Vec3 f_world = rw.force_world + contact_force_ + tip_force_world - p_.linear_drag * state_.velocity -
                       p_.mass * kGravity * Vec3::UnitZ();
  const Vec3 v_old = state_.velocity, w_old = state_.angular_velocity;
  detail::integrate_rigid_body(state_, p_.mass, inertia_, f_world, torque_body, dt, arena.floor_z());
  landed_ = state_.position.z() <= arena.floor_z();
  accel_world_ = (state_.velocity - v_old) / dt;
  ang_accel_body_ = (state_.angular_velocity - w_old) / dt;
  specific_force_body_ = state_.orientation.conjugate() * Vec3(accel_world_ + kGravity * Vec3::UnitZ());
}

}  // namespace tactile_sim
