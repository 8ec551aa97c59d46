// Near-wall model of the ducted quadrotor (004 eq. 3-10); see wall_effect_model.hpp.
#include "wall_effect_ekf/wall_effect_model.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace wall_effect_ekf {
namespace {

[[noreturn]] void bad(const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const std::string& f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(f, "must be finite and > 0", v);
}

}  // namespace

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Mat3 so3_exp(const Vec3& phi) {
  const double a = phi.norm();
  const Mat3 K = skew(phi);
  if (a < 1e-8) return Mat3::Identity() + K + 0.5 * K * K;
  return Mat3::Identity() + std::sin(a) / a * K + (1.0 - std::cos(a)) / (a * a) * K * K;
}

void ProximityParams::validate() const {
  positive("ProximityParams.rotor_radius", rotor_radius);
  positive("ProximityParams.a1", a1);
  positive("ProximityParams.a2", a2);
  if (!(b1 > 0.0 && b1 < 1.0)) bad("ProximityParams.b1", "must be in (0, 1) (004 eq. 4)", b1);
  if (!(b2 > 0.0 && b2 < 1.0)) bad("ProximityParams.b2", "must be in (0, 1) (004 eq. 4)", b2);
}

Proximity proximity(double y_i, const ProximityParams& p) {
  Proximity g;
  const bool touching = !(y_i > 0.0);
  const double d_bar = touching ? 0.0 : y_i / p.rotor_radius;  // 004: d_bar = d / R
  const double eh = p.a1 * std::pow(p.b1, d_bar);               // 004 eq. 4
  const double ev = p.a2 * std::pow(p.b2, d_bar);
  g.gh = eh;
  g.gv = 1.0 + ev;
  if (!touching) {
    g.dgh = eh * std::log(p.b1) / p.rotor_radius;
    g.dgv = ev * std::log(p.b2) / p.rotor_radius;
  }
  return g;
}

Mat3 gamma_matrix(double y_i, const ProximityParams& p) {
  const Proximity g = proximity(y_i, p);
  Mat3 G = Mat3::Identity();  // 004 eq. 5
  G(1, 2) = -g.gh;
  G(2, 2) = g.gv;
  return G;
}

void VehicleParams::validate() const {
  positive("VehicleParams.mass", mass);
  for (int i = 0; i < 3; ++i) positive("VehicleParams.inertia_diag[" + std::to_string(i) + "]", inertia_diag[i]);
  positive("VehicleParams.rotor_offset", rotor_offset);
  if (!(torque_coefficient >= 0.0) || !std::isfinite(torque_coefficient))
    bad("VehicleParams.torque_coefficient", "must be finite and >= 0", torque_coefficient);
  if (!(linear_drag >= 0.0) || !std::isfinite(linear_drag))
    bad("VehicleParams.linear_drag", "must be finite and >= 0", linear_drag);
  positive("VehicleParams.max_rotor_thrust", max_rotor_thrust);
  if (4.0 * max_rotor_thrust <= mass * kGravity)
    bad("VehicleParams.max_rotor_thrust", "four rotors cannot carry the weight", max_rotor_thrust);
  proximity.validate();
}

std::array<Vec3, 4> VehicleParams::rotor_positions() const {
  const double L = rotor_offset;
  return {Vec3(L, -L, 0), Vec3(L, L, 0), Vec3(-L, L, 0), Vec3(-L, -L, 0)};
}

double rotor_wall_distance(double y, const Mat3& R, const Vec3& r_i, const ProximityParams& p) {
  return y + R.row(1).dot(r_i) - p.rotor_radius;  // 004: y_i = y + e2^T R r_i - R
}

Wrench rotor_wrench(const Vec4& thrust, double y, const Mat3& R, const VehicleParams& v,
                    bool wall_present) {
  Wrench w;
  const auto r = v.rotor_positions();
  const Vec3 z_b = R.col(2);
  for (int i = 0; i < 4; ++i) {
    Vec3 f = thrust[i] * z_b;  // T0,i R e3
    if (wall_present) f = thrust[i] * (gamma_matrix(rotor_wall_distance(y, R, r[i], v.proximity), v.proximity) * z_b);  // 004 eq. 5
    w.force_wall += f;                                                        // 004 eq. 6
    const Vec3 fb = R.transpose() * f;
    w.torque_body += r[i].cross(fb) + VehicleParams::kSpin[i] * v.torque_coefficient * fb;  // 004 eq. 7
  }
  w.force_body = R.transpose() * w.force_wall;
  return w;
}

Mat34 torque_matrix(double y, const Mat3& R, const VehicleParams& v, bool wall_present) {
  Mat34 B;
  for (int i = 0; i < 4; ++i) {
    Vec4 e = Vec4::Zero();
    e[i] = 1.0;
    B.col(i) = rotor_wrench(e, y, R, v, wall_present).torque_body;  // 004 eq. 7-8: tau = B T0
  }
  return B;
}

Vec2 optical_flow(const Vec3& velocity, const Mat3& R, const Vec3& omega, double height) {
  const Vec3 vb = R.transpose() * velocity;
  return Vec2(vb.x() / height - omega.y(),   // 004 eq. 9
              vb.y() / height + omega.x());  // 004 eq. 10
}

}  // namespace wall_effect_ekf
