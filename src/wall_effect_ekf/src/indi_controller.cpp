// INDI controller of 004 (eq. 26-36); see indi_controller.hpp.
#include "wall_effect_ekf/indi_controller.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace wall_effect_ekf {
namespace {

[[noreturn]] void bad(const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << "IndiParams." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void non_negative(const std::string& f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(f, "must be finite and >= 0", v);
}
void positive(const std::string& f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(f, "must be finite and > 0", v);
}
void non_negative3(const char* f, const Vec3& v) {
  for (int i = 0; i < 3; ++i) non_negative(std::string(f) + "[" + std::to_string(i) + "]", v[i]);
}
double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

void IndiParams::validate() const {
  vehicle.validate();
  non_negative3("k_p", k_p);
  non_negative3("k_d", k_d);
  non_negative3("k_i", k_i);
  non_negative("integral_limit", integral_limit);
  positive("integral_zone", integral_zone);
  positive("max_accel_xy", max_accel_xy);
  non_negative("attitude_time_constant", attitude_time_constant);
  positive("max_rate_xy", max_rate_xy);
  // Below the fail-safe's crash tilt (60 deg, IndiControlLogic), so that no commanded tilt is taken for a crash.
  if (!(max_tilt > 0.0 && max_tilt < 1.0)) bad("max_tilt", "must be in (0, 1.0) rad", max_tilt);
  non_negative3("kappa_d", kappa_d);
  non_negative("kappa_p_yaw", kappa_p_yaw);
  positive("max_yaw_accel", max_yaw_accel);
}

IndiController::IndiController(const IndiParams& params) : p_(params) {
  p_.validate();
  reset();
}

void IndiController::reset() {
  integral_.setZero();
  thrust_prev_ = p_.vehicle.mass * kGravity;
  out_ = IndiOuterOutput{};
  out_.thrust = thrust_prev_;
}

IndiOuterOutput IndiController::outer(const IndiSetpoint& sp, const IndiFeedback& fb, double dt) {
  if (!(dt > 0.0)) throw std::invalid_argument("IndiController::outer: dt must be > 0");
  const double m = p_.vehicle.mass;
  IndiOuterOutput o;
  // 004 eq. 26 (errors written setpoint - state so that positive gains stabilise).
  const Vec3 e_p = sp.position - fb.position;
  const Vec3 e_v = sp.velocity - fb.velocity;
  Vec3 a_t = sp.acceleration + p_.k_d.cwiseProduct(e_v);
  for (int i = 0; i < 3; ++i) {
    if (!sp.position_control[static_cast<size_t>(i)]) {
      integral_[i] = 0.0;
      continue;
    }
    if (std::abs(e_p[i]) < p_.integral_zone)
      integral_[i] = std::clamp(integral_[i] + p_.k_i[i] * e_p[i] * dt, -p_.integral_limit, p_.integral_limit);
    a_t[i] += p_.k_p[i] * e_p[i] + integral_[i];
  }
  const double axy = a_t.head<2>().norm();
  if (axy > p_.max_accel_xy) a_t.head<2>() *= p_.max_accel_xy / axy;
  o.accel_target = a_t;
  // 004 eq. 30: measured acceleration from the accelerometer and attitude.
  const Vec3 a_meas = fb.R * fb.specific_force - kGravity * Vec3::UnitZ();
  const Vec3 e = a_t - a_meas;
  o.increment = m * e;
  const Vec3 x_b = fb.R.col(0), y_b = fb.R.col(1), z_b = fb.R.col(2);
  const double T_prev = std::max(thrust_prev_, 0.1 * m * kGravity);
  const double tau = p_.attitude_time_constant > 0.0 ? p_.attitude_time_constant : dt;
  o.rate_x = -m / (T_prev * tau) * y_b.dot(e);  // 004 eq. 32
  o.rate_y = m / (T_prev * tau) * x_b.dot(e);   // 004 eq. 33
  // No rate that tilts the vehicle beyond max_tilt (only rates that level it).
  const double tilt = std::acos(std::clamp(z_b.z(), -1.0, 1.0));
  if (tilt > p_.max_tilt) {
    // Tilt direction in the body frame: rotating about axis (e3_b x z) levels it.
    const Vec3 up_b = fb.R.transpose() * Vec3::UnitZ();
    const Vec3 level_axis = Vec3(0, 0, 1).cross(up_b);  // body rates about this axis reduce the tilt
    if (level_axis.head<2>().dot(Vec2(o.rate_x, o.rate_y)) < 0.0) {
      const Vec2 a = level_axis.head<2>().normalized();
      const Vec2 w(o.rate_x, o.rate_y);
      const Vec2 w_ok = w - a * a.dot(w);
      o.rate_x = w_ok.x();
      o.rate_y = w_ok.y();
    }
  }
  o.rate_x = std::clamp(o.rate_x, -p_.max_rate_xy, p_.max_rate_xy);
  o.rate_y = std::clamp(o.rate_y, -p_.max_rate_xy, p_.max_rate_xy);
  o.thrust = std::clamp(thrust_prev_ + m * z_b.dot(e), 0.0, 4.0 * p_.vehicle.max_rotor_thrust);  // 004 eq. 34
  thrust_prev_ = o.thrust;
  out_ = o;
  return o;
}

Vec3 IndiController::angular_accel(const Vec3& omega, double yaw, double yaw_setpoint) const {
  // 004 eq. 35.
  Vec3 wd(-p_.kappa_d.x() * (omega.x() - out_.rate_x), -p_.kappa_d.y() * (omega.y() - out_.rate_y),
          -p_.kappa_d.z() * omega.z() - p_.kappa_p_yaw * wrap(yaw - yaw_setpoint));
  wd.z() = std::clamp(wd.z(), -p_.max_yaw_accel, p_.max_yaw_accel);
  return wd;
}

std::array<double, 4> IndiController::allocate(const Vec3& angular_accel, const Vec3& omega,
                                               double total_thrust, const AllocationWall& wall) const {
  const VehicleParams& v = p_.vehicle;
  const Mat3 J = v.inertia_diag.asDiagonal();
  Mat4 M;
  M.topRows<3>() = torque_matrix(wall.y, wall.R, v, wall.present);  // B of 004 eq. 8
  M.row(3).setOnes();
  const Eigen::PartialPivLU<Mat4> lu(M);
  const Vec3 tau = J * angular_accel + omega.cross(J * omega);       // 004 eq. 36
  const double T = std::clamp(total_thrust, 0.0, 4.0 * v.max_rotor_thrust);
  const Vec4 f_t = lu.solve(Vec4(0.0, 0.0, 0.0, T));
  const Vec4 f_tau = lu.solve(Vec4(tau.x(), tau.y(), tau.z(), 0.0));
  // Largest s in [0, 1] with 0 <= f_t + s f_tau <= max for every rotor.
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (f_tau[i] > 0.0) s = std::min(s, std::max(0.0, (v.max_rotor_thrust - f_t[i]) / f_tau[i]));
    if (f_tau[i] < 0.0) s = std::min(s, std::max(0.0, -f_t[i] / f_tau[i]));
  }
  std::array<double, 4> out{};
  for (int i = 0; i < 4; ++i) out[static_cast<size_t>(i)] = std::clamp(f_t[i] + s * f_tau[i], 0.0, v.max_rotor_thrust);
  return out;
}

std::array<double, 4> IndiController::inner(const Vec3& omega, double yaw, double yaw_setpoint,
                                            const AllocationWall& wall) const {
  return allocate(angular_accel(omega, yaw, yaw_setpoint), omega, out_.thrust, wall);
}

}  // namespace wall_effect_ekf
