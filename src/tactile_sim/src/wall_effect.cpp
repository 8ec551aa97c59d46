// Ducted-rotor wall effect (004 eq. 3-7); see wall_effect.hpp.
#include "tactile_sim/wall_effect.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tactile_sim {
namespace {

[[noreturn]] void bad(const char* field, const char* why, double v) {
  std::ostringstream s;
  s << "WallEffectParams." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}

double clamp_d(double d_bar) { return d_bar < 0.0 ? 0.0 : d_bar; }

}  // namespace

void WallEffectParams::validate() const {
  if (!(rotor_radius > 0.0) || !std::isfinite(rotor_radius)) bad("rotor_radius", "must be > 0", rotor_radius);
  if (!(a1 > 0.0) || !std::isfinite(a1)) bad("a1", "must be > 0 (004 eq. 4)", a1);
  if (!(a2 > 0.0) || !std::isfinite(a2)) bad("a2", "must be > 0 (004 eq. 4)", a2);
  if (!(b1 > 0.0 && b1 < 1.0)) bad("b1", "must be in (0, 1) (004 eq. 4)", b1);
  if (!(b2 > 0.0 && b2 < 1.0)) bad("b2", "must be in (0, 1) (004 eq. 4)", b2);
  if (!(cutoff_normalized > 0.0) || !std::isfinite(cutoff_normalized))
    bad("cutoff_normalized", "must be > 0", cutoff_normalized);
}

double gamma_h(double d_bar, const WallEffectParams& p) {
  d_bar = clamp_d(d_bar);
  if (d_bar > p.cutoff_normalized) return 0.0;
  return p.a1 * std::pow(p.b1, d_bar);  // 004 eq. 4
}

double gamma_v(double d_bar, const WallEffectParams& p) {
  d_bar = clamp_d(d_bar);
  if (d_bar > p.cutoff_normalized) return 1.0;
  return 1.0 + p.a2 * std::pow(p.b2, d_bar);  // 004 eq. 4
}

Mat3 gamma_matrix(double distance, const Vec3& n_world, const WallEffectParams& p) {
  const double d_bar = distance / p.rotor_radius;  // 004: d_bar = d / R
  const double gh = gamma_h(d_bar, p);
  const double gv = gamma_v(d_bar, p);
  // 004 eq. 5 with y_W replaced by the wall normal n (horizontal, unit):
  // column 3 of Gamma maps the vertical thrust component to -gamma_h n + gamma_v e3.
  Mat3 G = Mat3::Identity();
  G(2, 2) = gv;
  G.col(2) += -gh * Vec3(n_world.x(), n_world.y(), 0.0);
  return G;
}

Vec3 rotor_force_world(double nominal_thrust, const Mat3& R_wb, const RotorWall& wall,
                       const WallEffectParams& p) {
  const Vec3 z_b = R_wb.col(2);  // R e3
  if (!wall.present) return nominal_thrust * z_b;
  return nominal_thrust * (gamma_matrix(wall.distance, wall.normal_world, p) * z_b);  // 004 eq. 5
}

Vec3 rotor_force_body(double nominal_thrust, const Mat3& R_wb, const RotorWall& wall,
                      const WallEffectParams& p) {
  return R_wb.transpose() * rotor_force_world(nominal_thrust, R_wb, wall, p);
}

RotorWrench rotor_wrench(const std::array<double, 4>& nominal_thrust, const Mat3& R_wb,
                         const RotorGeometry& g, const std::array<RotorWall, 4>& walls,
                         const WallEffectParams& p) {
  RotorWrench w;
  for (int i = 0; i < 4; ++i) {
    const Vec3 f_w = rotor_force_world(nominal_thrust[i], R_wb, walls[i], p);  // 004 eq. 5
    w.rotor_force_world[i] = f_w;
    w.force_world += f_w;                                                   // 004 eq. 6
    const Vec3 f_b = R_wb.transpose() * f_w;
    // 004 eq. 7: ([r_i]x + (-1)^(i+1) c_tau I) R^T T_W,i
    w.torque_body += g.position_body[i].cross(f_b) + g.spin_sign[i] * g.torque_coefficient * f_b;
  }
  return w;
}

}  // namespace tactile_sim
