#include "tactile_sim/whisker_mechanics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

namespace tactile_sim {
namespace {

void require(bool ok, const char* field, const char* reason, double value) {
  if (ok) return;
  std::ostringstream os;
  os << "WhiskerParams." << field << ": " << reason << ", got " << value;
  throw std::invalid_argument(os.str());
}

// 000 eq. S8 coefficients (valid for 0.5 < n < 10).
constexpr double kA0 = 2.654855;
constexpr double kA1 = 0.509896e-1;
constexpr double kA2 = 0.126749e-1;
constexpr double kA3 = 0.142039e-2;
constexpr double kA4 = 0.584525e-4;

}  // namespace

void WhiskerParams::validate() const {
  require(std::isfinite(length) && length > 0.0, "length", "must be > 0", length);
  require(std::isfinite(diameter) && diameter > 0.0 && diameter < length, "diameter",
          "must be > 0 and < length", diameter);
  require(std::isfinite(youngs_modulus) && youngs_modulus > 0.0, "youngs_modulus",
          "must be > 0", youngs_modulus);
  require(std::isfinite(placement_angle) && placement_angle > 0.0 &&
              placement_angle < M_PI / 2.0,
          "placement_angle", "must be in (0, pi/2) rad", placement_angle);
  require(std::isfinite(friction_speed_eps) && friction_speed_eps > 0.0, "friction_speed_eps",
          "must be > 0", friction_speed_eps);
  require(std::isfinite(stick_slip_gain) && stick_slip_gain >= 0.0, "stick_slip_gain", "must be >= 0",
          stick_slip_gain);
  require(std::isfinite(stick_slip_length) && stick_slip_length > 0.0, "stick_slip_length", "must be > 0",
          stick_slip_length);
}

PrbmState prbm_contact(const WhiskerParams& p, double d) {
  PrbmState s;
  const double alpha = p.placement_angle;
  const double lo = p.length;
  d = std::clamp(d, 0.0, p.horizontal_reach());
  s.d = d;
  // 000 eq. S3: static contact point in the sensor frame {S}.
  s.px = lo - d * std::cos(alpha);
  s.py = d * std::sin(alpha);
  // 000 eq. S6: pseudo-rigid-body angle.
  s.theta = std::atan2(s.py, s.px);
  // 000 eq. S2: beta ~ 3/2 theta; n = tan(beta) (000 eq. S1).
  s.beta = 1.5 * s.theta;
  s.n = std::tan(s.beta);
  const double n = s.n;
  // 000 eq. S7: characteristic radius factor.
  s.gamma = 0.841655 - 0.0067807 * n + 0.000438 * n * n;
  // 000 eq. S8: stiffness coefficient polynomial.
  s.k_theta = kA0 - kA1 * n + kA2 * n * n - kA3 * n * n * n + kA4 * n * n * n * n;
  // 000 eq. S4-S5: flexural beam length so that the force acts at its free end.
  s.lr = std::hypot(s.px, s.py) / s.gamma;
  // 000 eq. S8: torsion spring constant.
  s.spring_k = s.gamma * p.bending_stiffness() * s.k_theta / s.lr;
  if (d <= 0.0) return s;  // no deflection, no force
  // 000 eq. S1 (equivalently S9 with the constant E I): transverse force at P_c.
  s.force_f =
      s.spring_k * s.theta / (s.gamma * s.lr * (std::cos(s.theta) + n * std::sin(s.theta)));
  // 000 eq. S10: normal force on the wall.
  s.normal_force = s.force_f / std::sin(s.beta + alpha);
  // Base bending moment: the wall's horizontal normal force acting at the static
  // contact point, l_o sin(alpha) above the base (lever of P_c^S about O).
  s.base_moment = s.normal_force * p.contact_height();
  return s;
}

double stick_slip_profile(double u, double length, uint64_t seed, int obstacle_id) {
  if (!std::isfinite(u) || !(length > 0.0)) return 0.0;
  const double x = u / length;
  const double cycle = std::floor(x);
  const double f = x - cycle;  // phase in the cycle, [0, 1)
  // splitmix64 of (seed, obstacle, cycle): the amplitude of this asperity.
  uint64_t z = seed ^ (static_cast<uint64_t>(static_cast<int64_t>(cycle)) * 0x9E3779B97F4A7C15ULL) ^
               (static_cast<uint64_t>(obstacle_id + 1) * 0xD1B54A32D192ED03ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  const double a = 0.5 + 0.5 * static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);  // [0.5, 1)
  // Sawtooth: load builds while the tip sticks (f: 0 -> 1), drops at the slip.
  return a * (2.0 * f - 1.0);
}

WhiskerContact whisker_contact(const WhiskerParams& p, const Vec2& base, const Vec2& forward,
                               const Vec2& base_velocity, bool hit, double hit_distance,
                               const Vec2& hit_point, const Vec2& hit_normal, double friction,
                               int obstacle_id) {
  WhiskerContact c;
  const double reach = p.horizontal_reach();
  c.base = base;
  c.tip = base + reach * forward;
  c.contact_point = c.tip;
  if (!hit || !(hit_distance <= reach)) return c;
  c.contact = true;
  c.depth = std::max(hit_distance, 0.0);
  c.contact_point = hit_point;
  c.normal = hit_normal;
  c.obstacle_id = obstacle_id;
  // Incidence: cos(phi) between the shaft direction and the wall's inward normal.
  const double cos_phi = std::clamp(-forward.dot(hit_normal), 0.0, 1.0);
  c.deflection = (reach - c.depth) * cos_phi;
  c.prbm = prbm_contact(p, c.deflection);
  c.normal_force = c.prbm.normal_force;
  c.base_moment = c.prbm.base_moment;
  // Coulomb friction of the (static-on-the-wall) contact point sliding along the
  // wall as the base moves tangentially; regularised below friction_speed_eps.
  const Vec2 tangent(-hit_normal.y(), hit_normal.x());
  const double v_t = base_velocity.dot(tangent);
  const double slip = std::clamp(v_t / p.friction_speed_eps, -1.0, 1.0);
  const double f_t = -friction * c.normal_force * slip;
  c.friction_force = std::abs(f_t);
  // Stick-slip of the sliding tip (docs/whisker_signal_model.md, "Stick-slip while sliding"): a
  // zero-mean fluctuation of the bending moment the barometers feel, scaled by
  // the friction moment mu N l_o sin(alpha) and by how fully the tip slides;
  // its frequency is the sliding speed over the cycle length. The force on the
  // body keeps the mean (PRBM) normal force.
  if (p.stick_slip_gain > 0.0 && friction > 0.0) {
    const double u = hit_point.dot(tangent);
    c.stick_slip_moment = p.stick_slip_gain * friction * c.normal_force * p.contact_height() * std::abs(slip) *
                          stick_slip_profile(u, p.stick_slip_length, p.stick_slip_seed, obstacle_id);
    c.base_moment = std::max(c.base_moment + c.stick_slip_moment, 0.0);
  }
  // Reaction transmitted through the shaft to the drone: the wall pushes along
  // its normal and drags against the sliding direction.
  c.force_on_body = c.normal_force * hit_normal + f_t * tangent;
  return c;
}

}  // namespace tactile_sim
