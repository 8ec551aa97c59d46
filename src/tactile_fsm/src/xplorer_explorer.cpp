// XPLORER tactile behaviours (001 Sec. III-B, IV); see xplorer_explorer.hpp.
#include "tactile_fsm/xplorer_explorer.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace tactile_fsm {
namespace {

[[noreturn]] void bad(const std::string& s, const std::string& field, const std::string& why, double v) {
  std::ostringstream o;
  o << s << "." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(o.str());
}
XVec2 rot(double yaw, const XVec2& v) { return Eigen::Rotation2Dd(yaw) * v; }
double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

}  // namespace

// --- 001 eq. 8 -------------------------------------------------------------------
void AdmittanceParams::validate() const {
  if (!(virtual_mass > 0.0) || !std::isfinite(virtual_mass)) bad("AdmittanceParams", "virtual_mass", "must be > 0", virtual_mass);
  if (!(virtual_inertia > 0.0) || !std::isfinite(virtual_inertia))
    bad("AdmittanceParams", "virtual_inertia", "must be > 0", virtual_inertia);
  for (int i = 0; i < 4; ++i) {
    if (!(damping[i] >= 0.0) || !std::isfinite(damping[i]))
      bad("AdmittanceParams", "damping[" + std::to_string(i) + "]", "must be >= 0", damping[i]);
    if (!(stiffness[i] >= 0.0) || !std::isfinite(stiffness[i]))
      bad("AdmittanceParams", "stiffness[" + std::to_string(i) + "]", "must be >= 0", stiffness[i]);
  }
}

AdmittanceController::AdmittanceController(const AdmittanceParams& p) : p_((p.validate(), p)) {}

void AdmittanceController::reset(const XVec3& r, double yaw) {
  r_ = r;
  v_.setZero();
  yaw_ = yaw;
  yaw_rate_ = 0.0;
}

void AdmittanceController::reset_yaw(double yaw) {
  yaw_ = yaw;
  yaw_rate_ = 0.0;
}

const XVec3& AdmittanceController::update(const XVec3& force, const XVec3& force_des, const XVec3& r_star,
                                          double torque_z, double torque_des, double yaw_star, double dt) {
  for (int i = 0; i < 3; ++i) {
    if (p_.damping[i] == 0.0 && p_.stiffness[i] == 0.0) {  // axis not in admittance
      r_[i] = r_star[i];
      v_[i] = 0.0;
      continue;
    }
    // 001 eq. 8: m_v r'' + D r' + K (r - r*) = delta_f - delta_f_des
    const double acc = (force[i] - force_des[i] - p_.damping[i] * v_[i] - p_.stiffness[i] * (r_[i] - r_star[i])) /
                       p_.virtual_mass;
    v_[i] += acc * dt;
    r_[i] += v_[i] * dt;
  }
  // 001 eq. 8, yaw row: I_v psi'' + D psi' + K (psi - psi*) = tau_z - tau_des
  const double e = wrap(yaw_ - yaw_star);
  const double acc = (torque_z - torque_des - p_.damping[3] * yaw_rate_ - p_.stiffness[3] * e) / p_.virtual_inertia;
  yaw_rate_ += acc * dt;
  yaw_ = wrap(yaw_ + yaw_rate_ * dt);
  return r_;
}

// --- names ------------------------------------------------------------------------------
const char* to_string(XplorerMission m) {
  switch (m) {
    case XplorerMission::kExplore: return "explore";
    case XplorerMission::kStaticWrench: return "static_wrench";
    case XplorerMission::kRicochet: return "ricochet";
    case XplorerMission::kWaypoint: return "waypoint";
  }
  return "?";
}

XplorerMission mission_from_string(const std::string& s) {
  for (auto m : {XplorerMission::kExplore, XplorerMission::kStaticWrench, XplorerMission::kRicochet,
                 XplorerMission::kWaypoint}) {
    if (s == to_string(m)) return m;
  }
  throw std::invalid_argument("XplorerParams.mission: must be explore, static_wrench, ricochet or waypoint, got \"" + s + "\"");
}

const char* to_string(XplorerState s) {
  switch (s) {
    case XplorerState::kTakeoff: return "takeoff";
    case XplorerState::kExploration: return "exploration";
    case XplorerState::kTactileTurning: return "tactile_turning";
    case XplorerState::kTactileTraversal: return "tactile_traversal";
    case XplorerState::kRicocheting: return "ricocheting";
    case XplorerState::kStaticWrench: return "static_wrench";
    case XplorerState::kGoTo: return "goto";
    case XplorerState::kDone: return "done";
  }
  return "?";
}

const char* to_string(XplorerReason r) {
  switch (r) {
    case XplorerReason::kNone: return "none";
    case XplorerReason::kHoverHeightReached: return "hover_height_reached";
    case XplorerReason::kContact: return "contact";
    case XplorerReason::kContactSquareUp: return "contact_square_up";
    case XplorerReason::kNewContact: return "new_contact";
    case XplorerReason::kYawRatePeak: return "yaw_rate_peak";
    case XplorerReason::kContactLostTurn: return "contact_lost_turn";
    case XplorerReason::kContactLost: return "contact_lost";
    case XplorerReason::kContactLostSquaring: return "contact_lost_squaring";
    case XplorerReason::kReContact: return "re_contact";
    case XplorerReason::kTurnLimit: return "turn_limit";
    case XplorerReason::kLoopClosed: return "loop_closed";
    case XplorerReason::kCollisionRecovered: return "collision_recovered";
    case XplorerReason::kGoalPassed: return "goal_passed";
  }
  return "?";
}

XVec2 post_collision_velocity(const XVec2& v, const XVec2& n_in, double e) {
  const XVec2 n = n_in.normalized();
  const double vn = v.dot(n);
  return v - vn * n - e * vn * n;  // tangential kept, normal reversed and scaled
}

void XplorerParams::validate() const {
  auto pos = [](const char* f, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) bad("XplorerParams", f, "must be finite and > 0", v);
  };
  pos("hover_height", hover_height);
  pos("takeoff_tolerance", takeoff_tolerance);
  pos("explore_speed", explore_speed);
  pos("traverse_speed", traverse_speed);
  pos("position_gain", position_gain);
  if (force_average_samples < 1) bad("XplorerParams", "force_average_samples", "must be >= 1", force_average_samples);
  pos("delta_0", delta_0);
  pos("delta_psi0", delta_psi0);
  if (!(delta_psi0 > delta_0)) bad("XplorerParams", "delta_psi0", "must be > delta_0 (001 Sec. IV-A)", delta_psi0);
  pos("yaw_rate_trigger", yaw_rate_trigger);
  pos("yaw_rate_lowpass_hz", yaw_rate_lowpass_hz);
  pos("turn_rate", turn_rate);
  if (!(turn_limit > 0.0 && turn_limit <= M_PI)) bad("XplorerParams", "turn_limit", "must be in (0, pi] (001: 180 deg)", turn_limit);
  pos("turn_push", turn_push);
  pos("contact_reach", contact_reach);
  pos("turn_radius", turn_radius);
  if (!(turn_slide >= 0.0) || !std::isfinite(turn_slide)) bad("XplorerParams", "turn_slide", "must be finite and >= 0", turn_slide);
  if (!(turn_backoff >= 0.0) || !std::isfinite(turn_backoff)) bad("XplorerParams", "turn_backoff", "must be finite and >= 0", turn_backoff);
  pos("turn_backoff_tau", turn_backoff_tau);
  if (!(corner_lookback >= 0.0) || !std::isfinite(corner_lookback))
    bad("XplorerParams", "corner_lookback", "must be finite and >= 0", corner_lookback);
  pos("contact_force", contact_force);
  if (!(reshape_gain >= 0.0) || !std::isfinite(reshape_gain)) bad("XplorerParams", "reshape_gain", "must be >= 0", reshape_gain);
  pos("reshape_limit", reshape_limit);
  pos("release_force", release_force);
  pos("release_time", release_time);
  if (!(settle_time >= 0.0) || !std::isfinite(settle_time))
    bad("XplorerParams", "settle_time", "must be finite and >= 0", settle_time);
  pos("loop_closure_radius", loop_closure_radius);
  pos("loop_min_path", loop_min_path);
  if (!(contact_lost_turn_min_s >= 0.0) || !std::isfinite(contact_lost_turn_min_s))
    bad("XplorerParams", "contact_lost_turn_min_s", "must be finite and >= 0", contact_lost_turn_min_s);
  if (max_clockwise_turns_in_a_row < 0 || max_clockwise_turns_in_a_row > 1000)
    bad("XplorerParams", "max_clockwise_turns_in_a_row", "must be in [0, 1000]", max_clockwise_turns_in_a_row);
  if (!(loop_min_winding >= 0.0 && loop_min_winding <= 2.0 * M_PI))
    bad("XplorerParams", "loop_min_winding", "must be in [0, 2 pi] (one circuit turns the heading by 2 pi)", loop_min_winding);
  if (!(loop_turn_min_winding >= 0.0 && loop_turn_min_winding <= 2.0 * M_PI))
    bad("XplorerParams", "loop_turn_min_winding", "must be in [0, 2 pi] (0: off)", loop_turn_min_winding);
  if (!(contact_backoff_gain >= 0.0) || !std::isfinite(contact_backoff_gain))
    bad("XplorerParams", "contact_backoff_gain", "must be finite and >= 0", contact_backoff_gain);
  if (!(contact_backoff_max >= 0.0 && contact_backoff_max <= 0.5))
    bad("XplorerParams", "contact_backoff_max", "must be in [0, 0.5] m", contact_backoff_max);
  if (!(contact_backoff_time >= 0.0 && contact_backoff_time <= 2.0))
    bad("XplorerParams", "contact_backoff_time", "must be in [0, 2] s", contact_backoff_time);
  if (!(square_min_deflection >= 0.0 && square_min_deflection < 0.5 * M_PI))
    bad("XplorerParams", "square_min_deflection", "must be in [0, pi/2) (0: off)", square_min_deflection);
  pos("square_window", square_window);
  if (!(square_min_path >= 0.0) || !std::isfinite(square_min_path))
    bad("XplorerParams", "square_min_path", "must be finite and >= 0", square_min_path);
  if (!(square_hold >= 0.0 && square_hold <= 10.0)) bad("XplorerParams", "square_hold", "must be in [0, 10] s", square_hold);
  pos("static_force", static_force);
  if (!goal.allFinite()) bad("XplorerParams", "goal", "must be finite", goal.x());
  pos("ricochet_speed", ricochet_speed);
  pos("collision_force", collision_force);
  if (!(restitution >= 0.0 && restitution <= 1.0)) bad("XplorerParams", "restitution", "must be in [0, 1]", restitution);
  // Finite: an infinite gain would send the recovery setpoint to infinity.
  if (!(recovery_gain >= 0.0) || !std::isfinite(recovery_gain))
    bad("XplorerParams", "recovery_gain", "must be finite and >= 0", recovery_gain);
  if (!(recovery_time >= 0.0) || !std::isfinite(recovery_time))
    bad("XplorerParams", "recovery_time", "must be finite and >= 0", recovery_time);
  admittance.validate();
}

// --- the state machine ---------------------------------------------------------------------
XplorerExplorer::XplorerExplorer(const XplorerParams& p) : p_((p.validate(), p)), adm_(p.admittance) {}

double XplorerExplorer::reshape(const XVec2& n, const XVec2& p, const XVec3& force, const XVec3& f_des, double dt) {
  // 001 Sec. III-B1: r* reshaped by the external wrench (integral of the force error along C_n).
  double rn = r_star_.dot(n) + p_.reshape_gain * (force - f_des).head<2>().dot(n) * dt;
  rn = std::clamp(rn, p.dot(n) - p_.reshape_limit, p.dot(n) + p_.reshape_limit);
  if (p_.reshape_follows_contact) {
    // Keep only the offset along C_n, with the tangential part at the vehicle: when C_n turns
    // with the yaw (a curved surface: pipe, bin), a stale tangential part projected onto the
    // new C_n would drive r* into the surface (and the force up) as the vehicle goes round.
    r_star_ = p + (rn - p.dot(n)) * n;
  } else {
    r_star_ = r_star_ + (rn - r_star_.dot(n)) * n;
  }
  return rn;
}

std::string XplorerExplorer::reason_text(XplorerReason why) const {
  switch (why) {
    case XplorerReason::kNone: return "";
    case XplorerReason::kHoverHeightReached: return "hover height reached";
    case XplorerReason::kContact: return std::string("contact ") + to_string(contact_);
    case XplorerReason::kContactSquareUp: {
      std::ostringstream r;
      r << "contact " << to_string(contact_) << " (square up "
        << std::lround(wrap(square_yaw_ - square_yaw0_) * 180.0 / M_PI) << " deg)";
      return r.str();
    }
    case XplorerReason::kNewContact: return std::string("new contact ") + to_string(contact_);
    case XplorerReason::kYawRatePeak: return "yaw rate peak";
    case XplorerReason::kContactLostTurn: return "contact lost: turn about the corner";
    case XplorerReason::kContactLost: return "contact lost";
    case XplorerReason::kContactLostSquaring: return "contact lost while squaring up";
    case XplorerReason::kReContact: return std::string("re-contact ") + to_string(contact_);
    case XplorerReason::kTurnLimit: return "turn limit without re-contact";
    case XplorerReason::kLoopClosed: return "loop closed";
    case XplorerReason::kCollisionRecovered: return "collision recovered";
    case XplorerReason::kGoalPassed: return "goal passed without collision";
  }
  return "?";
}

void XplorerExplorer::enter(XplorerState s, XplorerReason why, const XplorerInput& in, XplorerOutput& out) {
  const XplorerState from = state_;
  const XVec3 hold_before = hold_;  // the take-off's hover point (Ricocheting's first setpoint)
  const double hold_yaw_before = hold_yaw_;
  state_ = s;
  t_enter_ = in.t;
  ++transitions_;
  low_force_since_ = -1.0;
  hold_ = in.position;
  hold_yaw_ = in.yaw;
  yaw_enter_ = in.yaw;
  squaring_ = false;
  // Entry actions: the state's set-up and its setpoint on this tick (by default the vehicle's
  // position at hover height with the yaw held; never the output's default, the world origin
  // at z = 0).
  const XVec2 p2 = in.position.head<2>();
  out.position = XVec3(p2.x(), p2.y(), p_.hover_height);
  out.yaw = hold_yaw_;
  switch (s) {
    case XplorerState::kExploration: explore_history_.clear(); break;
    case XplorerState::kTactileTraversal:
    case XplorerState::kStaticWrench:
      // The admittance (001 eq. 8) starts at rest at the vehicle, r* there.
      adm_.reset(XVec3(in.position.x(), in.position.y(), p_.hover_height), in.yaw);
      r_star_ = p2;
      t_quiet_ = in.t;
      traverse_history_.clear();
      if (from == XplorerState::kExploration) {  // the first contact of this approach
        start_backoff(in);
        if (s == XplorerState::kTactileTraversal && plan_square(in)) {  // a face slid along: square up first
          square_t0_ = std::max(in.t, backoff_until_);
          why = XplorerReason::kContactSquareUp;
        }
      }
      // The contact back-off's setpoint (or, without one, the vehicle's position; the
      // admittance starts there next tick).
      if (in.t < backoff_until_) out.position = backoff_sp_;
      break;
    case XplorerState::kTactileTurning: out.position = turning_setpoint(in, &out.yaw); break;
    case XplorerState::kRicocheting:  // the take-off's hover setpoint once more; the line to the goal next tick
      out.position = XVec3(hold_before.x(), hold_before.y(), p_.hover_height);
      out.yaw = hold_yaw_before;
      break;
    case XplorerState::kGoTo: out.position = XVec3(p_.goal.x(), p_.goal.y(), p_.hover_height); break;
    case XplorerState::kTakeoff:
    case XplorerState::kDone: break;
  }
  reason_code_ = why;
  reason_ = reason_text(why);
  out.state = s;
  out.transitioned = true;
}

void XplorerExplorer::plan_turn(double sign, double face_yaw, const XVec2& face_p, const XplorerInput& in) {
  // The face as it was before the release: its yaw, its normal C_n and the pivot on it in
  // front of the vehicle, abreast of it along lambda.
  turn_sign_ = sign;
  ++turns_;
  face_yaw_ = face_yaw;
  face_n_ = rot(face_yaw, unit(contact_));
  face_t_ = rot(face_yaw, unit(move_));
  const XVec2 p2 = in.position.head<2>();
  pivot_ = face_p + p_.contact_reach * face_n_ + (p2 - face_p).dot(face_t_) * face_t_;
  phi0_ = std::clamp(turn_sign_ * wrap(in.yaw - face_yaw_), 0.0, p_.turn_limit);
}

void XplorerExplorer::hold_backoff(const XplorerInput& in, XplorerOutput& out) {
  out.position = backoff_sp_;
  out.yaw = hold_yaw_;
  adm_.reset(XVec3(in.position.x(), in.position.y(), p_.hover_height), in.yaw);
  r_star_ = in.position.head<2>();
  t_quiet_ = in.t;
  low_force_since_ = -1.0;
  traverse_history_.clear();
}

void XplorerExplorer::start_backoff(const XplorerInput& in) {
  // 001 Sec. III-B3 collision recovery at the contact that ends Exploration: a setpoint
  // away from the obstacle along the measured force, proportional to its magnitude.
  backoff_sp_ = XVec3(in.position.x(), in.position.y(), p_.hover_height);
  if (!(p_.contact_backoff_time > 0.0)) return;
  const XVec2 f = in.force.head<2>();
  const double fn = f.norm();
  // The fused force points out of the obstacle; a vanishing one (the average crossed delta_0
  // on older samples) falls back on -C_n.
  const XVec2 dir = fn > 1e-6 ? XVec2(f / fn) : XVec2(-rot(in.yaw, unit(contact_)));
  backoff_sp_.head<2>() += std::min(p_.contact_backoff_gain * fn, p_.contact_backoff_max) * dir;
  backoff_until_ = in.t + p_.contact_backoff_time;
  ++backoffs_;
}

void XplorerExplorer::push_window(std::deque<PoseSample>& h, const PoseSample& s, double window) {
  h.push_back(s);
  while (h.size() > 1 && s.t - h[1].t >= window) h.pop_front();
}

bool XplorerExplorer::plan_square(const XplorerInput& in) {
  // Issue 17, class B (our choice; docs/tuning/tactile_fsm.md "Oblique first face"): the path of the last
  // square_window s of Exploration, deflected from the Exploration direction, runs along the
  // face the vehicle slid on; the face's normal is perpendicular to it, on the side the force
  // comes from (the fused force points out of the obstacle).
  if (!(p_.square_min_deflection > 0.0) || p_.mission != XplorerMission::kExplore || explore_history_.empty())
    return false;
  const XVec2 d = in.position.head<2>() - explore_history_.front().p;
  if (d.norm() < p_.square_min_path || d.norm() < 1e-9) return false;
  const XVec2 t = d.normalized();
  const double cos_defl = std::clamp(t.dot(explore_dir_), -1.0, 1.0);
  // Deflected by at least square_min_deflection, but still forward (at most 80 deg: a rebound
  // from a square hit runs back along the force, not along a face).
  if (std::acos(cos_defl) < p_.square_min_deflection || cos_defl < std::cos(80.0 * M_PI / 180.0)) return false;
  const XVec2 fw = rot(in.yaw, f_body_avg_);
  if (!(fw.norm() > 1e-6) || std::abs(t.dot(fw.normalized())) > std::cos(M_PI / 4.0)) return false;  // slid across the force
  XVec2 n(-t.y(), t.x());
  if (n.dot(fw) > 0.0) n = -n;                    // into the obstacle
  if (n.dot(explore_dir_) <= 0.0) return false;  // the face lies ahead of the approach
  // C_n: body +X (square_to_x) or the body axis nearest to the normal; the yaw that puts it on
  // the normal (|.| < 90 / <= 45 deg).
  const XVec2 nb = rot(-in.yaw, n);
  const BodyDirection c = p_.square_to_x ? BodyDirection::kPlusX
                : std::abs(nb.x()) >= std::abs(nb.y()) ? (nb.x() > 0 ? BodyDirection::kPlusX : BodyDirection::kMinusX)
                                                      : (nb.y() > 0 ? BodyDirection::kPlusY : BodyDirection::kMinusY);
  const XVec2 cw = rot(in.yaw, unit(c));
  contact_ = c;
  move_ = right_hand(c);  // 001 Sec. IV-A: right-hand traversal
  square_yaw0_ = in.yaw;
  square_yaw_ = wrap(in.yaw + std::atan2(cw.x() * n.y() - cw.y() * n.x(), cw.dot(n)));
  squaring_ = true;
  ++squarings_;
  return true;
}

XVec3 XplorerExplorer::turning_setpoint(const XplorerInput& in, double* yaw) const {
  const XVec2 p2 = in.position.head<2>();
  if (p_.turn_pivot) {
    // Orbit the pivot: yaw and position setpoints turn together at psi_c (001 Sec.
    // V-C: 0.26 rad/s), from the angle the vehicle has already turned, limited to 180 deg.
    const double phi = std::min(phi0_ + p_.turn_rate * (in.t - t_enter_), p_.turn_limit);
    *yaw = wrap(face_yaw_ + turn_sign_ * phi);
    const double radius = p_.turn_radius + p_.turn_backoff * std::exp(-(in.t - t_enter_) / p_.turn_backoff_tau);
    // The pivot is abreast of the vehicle along lambda at the trigger; from there it
    // moves on along lambda at traverse_speed to turn_slide past the pivot.
    const double slide = std::min(p_.turn_slide, p_.traverse_speed * (in.t - t_enter_));
    const XVec2 sp = pivot_ + rot(turn_sign_ * phi, slide * face_t_ - radius * face_n_);
    return XVec3(sp.x(), sp.y(), p_.hover_height);
  }
  const double turned = std::min(p_.turn_rate * (in.t - t_enter_), p_.turn_limit);  // 001: limited to 180 deg
  *yaw = wrap(yaw_enter_ + turn_sign_ * turned);
  const XVec2 n = rot(in.yaw, unit(contact_)), t = rot(in.yaw, unit(move_));
  XVec3 out(p2.x(), p2.y(), p_.hover_height);
  out.head<2>() += p_.turn_push * n + (p_.traverse_speed / p_.position_gain) * t;
  return out;
}

// --- Named guards (public, tested alone) -------------------------------------

bool XplorerExplorer::at_hover_height(const XplorerInput& in) const {
  return std::abs(in.position.z() - p_.hover_height) < p_.takeoff_tolerance;
}

BodyDirection XplorerExplorer::contact_detected() const { return contact_direction(f_body_avg_, p_.delta_0); }

bool XplorerExplorer::yaw_rate_peak(double t) const {
  return t - t_quiet_ > p_.settle_time && std::abs(yaw_rate_f_) > p_.yaw_rate_trigger;
}

bool XplorerExplorer::peak_against_the_traversal() const {
  return yaw_rate_f_ < 0.0 && clockwise_in_a_row_ >= p_.max_clockwise_turns_in_a_row;
}

bool XplorerExplorer::released(double t) const {
  return low_force_since_ >= 0.0 && t - low_force_since_ > p_.release_time;
}

bool XplorerExplorer::turns_about_the_faces_end(double t) const {
  return released(t) && p_.turn_on_contact_lost && p_.turn_pivot && t - t_enter_ >= p_.contact_lost_turn_min_s;
}

bool XplorerExplorer::re_contact(double t) const {
  return t - t_enter_ > p_.settle_time &&
         (std::abs(f_body_avg_.x()) > p_.delta_psi0 || std::abs(f_body_avg_.y()) > p_.delta_psi0);
}

bool XplorerExplorer::turn_limit_passed(double t) const { return t - t_enter_ > p_.turn_limit / p_.turn_rate + 3.0; }

bool XplorerExplorer::recovered(double t) const { return collision_peak_ > 0.0 && t - t_quiet_ > p_.recovery_time; }

bool XplorerExplorer::goal_passed(const XVec2& p2) const {
  const XVec2 dir = (p_.goal - hold_.head<2>()).normalized();
  return (p2 - hold_.head<2>()).dot(dir) > (p_.goal - hold_.head<2>()).norm() + 0.3;
}

bool XplorerExplorer::loop_closes(const XVec2& p2) const {
  const bool closure_state =
      state_ == XplorerState::kTactileTraversal ||
      (state_ == XplorerState::kTactileTurning && p_.loop_turn_min_winding > 0.0 &&
       winding_ >= p_.loop_turn_min_winding);
  return started_path_ && !loop_closed_ && closure_state && path_ > p_.loop_min_path &&
         winding_ >= p_.loop_min_winding && (p2 - first_contact_p_).norm() < p_.loop_closure_radius;
}

XplorerOutput XplorerExplorer::for_test_enter(XplorerState s, const XplorerInput& in, BodyDirection contact) {
  initialised_ = true;
  hold_ = in.position;
  hold_yaw_ = yaw_enter_ = last_yaw_ = in.yaw;
  last_p_ = in.position.head<2>();
  t_enter_ = in.t;
  state_ = XplorerState::kExploration;  // the state the contact states are entered from
  explore_dir_ = rot(in.yaw, XVec2(1, 0));
  contact_ = contact;
  move_ = right_hand(contact);
  if (s == XplorerState::kTactileTurning) plan_turn(1.0, in.yaw, in.position.head<2>(), in);
  XplorerOutput out;
  enter(s, XplorerReason::kNone, in, out);
  return out;
}

XplorerOutput XplorerExplorer::update(const XplorerInput& in, double dt) {
  // Body force (001 Sec. IV-A: b_delta = w_R_b^T delta) and its 50-sample moving average (Sec. V-C).
  const XVec2 fb = rot(-in.yaw, in.force.head<2>());
  forces_.push_back(fb);
  f_sum_ += fb;
  while (static_cast<int>(forces_.size()) > p_.force_average_samples) {
    f_sum_ -= forces_.front();
    forces_.pop_front();
  }
  f_body_avg_ = f_sum_ / static_cast<double>(forces_.size());
  // Low-passed yaw rate (001 Sec. V-C).
  const double a = 1.0 - std::exp(-2.0 * M_PI * p_.yaw_rate_lowpass_hz * dt);
  yaw_rate_f_ = have_rate_ ? yaw_rate_f_ + a * (in.yaw_rate - yaw_rate_f_) : in.yaw_rate;
  have_rate_ = true;

  const XVec2 p2 = in.position.head<2>();
  if (started_path_ && state_ != XplorerState::kDone) {
    path_ += (p2 - last_p_).norm();
    winding_ += wrap(in.yaw - last_yaw_);  // counter-clockwise positive: the right-hand sense
  }
  last_p_ = p2;
  last_yaw_ = in.yaw;

  if (!initialised_) {  // take off where the vehicle stands
    initialised_ = true;
    hold_ = in.position;
    hold_yaw_ = yaw_enter_ = in.yaw;
    t_enter_ = in.t;
  }
  XplorerOutput out;
  out.state = state_;
  // Loop closure (001 Sec. V-C2): back at the first contact point after going round,
  // traversing its face (001: "continues traversing all the edges until it returns to
  // the initial contact position"), not while a turn swings past it.
  // Once round the object: the heading has wound by ~2 pi counter-clockwise (right-hand
  // traversal); wobbling round one corner back to the first contact point has not.
  // Optionally also inside a turn, once (nearly) round (loop_turn_min_winding).
  if (loop_closes(p2)) {
    loop_closed_ = true;
    loop_closure_t_ = in.t;
    enter(XplorerState::kDone, XplorerReason::kLoopClosed, in, out);
    return out;
  }
  switch (state_) {
    case XplorerState::kTakeoff: tick_takeoff(in, out); break;
    case XplorerState::kExploration: tick_exploration(in, out); break;
    case XplorerState::kTactileTraversal: tick_traversal(in, dt, out); break;
    case XplorerState::kTactileTurning: tick_turning(in, out); break;
    case XplorerState::kStaticWrench: tick_static_wrench(in, dt, out); break;
    case XplorerState::kRicocheting: tick_ricochet(in, out); break;
    case XplorerState::kGoTo:
      out.position = XVec3(p_.goal.x(), p_.goal.y(), p_.hover_height);
      out.yaw = hold_yaw_;
      break;
    case XplorerState::kDone:
      out.position = hold_;
      out.yaw = hold_yaw_;
      break;
  }
  return out;
}

void XplorerExplorer::tick_takeoff(const XplorerInput& in, XplorerOutput& out) {
  out.position = XVec3(hold_.x(), hold_.y(), p_.hover_height);
  out.yaw = hold_yaw_;
  if (!at_hover_height(in)) return;
  switch (p_.mission) {
    case XplorerMission::kExplore:
    case XplorerMission::kStaticWrench:
      explore_dir_ = rot(in.yaw, XVec2(1, 0));  // 001 Sec. V-C: move along body +x
      enter(XplorerState::kExploration, XplorerReason::kHoverHeightReached, in, out);
      break;
    case XplorerMission::kRicochet: enter(XplorerState::kRicocheting, XplorerReason::kHoverHeightReached, in, out); break;
    case XplorerMission::kWaypoint: enter(XplorerState::kGoTo, XplorerReason::kHoverHeightReached, in, out); break;
  }
}

void XplorerExplorer::tick_exploration(const XplorerInput& in, XplorerOutput& out) {
  const XVec2 p2 = in.position.head<2>();
  const BodyDirection c = contact_detected();
  if (c != BodyDirection::kNone) {  // 001 Sec. IV-A: contact
    contact_ = c;
    if (p_.mission == XplorerMission::kStaticWrench) {
      enter(XplorerState::kStaticWrench, XplorerReason::kContact, in, out);
      return;
    }
    move_ = right_hand(c);  // 001 Sec. IV-A: right-hand traversal
    if (first_contact_t_ < 0) {
      first_contact_t_ = in.t;
      first_contact_p_ = p2;
      started_path_ = true;
    }
    enter(XplorerState::kTactileTraversal, XplorerReason::kContact, in, out);
    return;
  }
  out.position = XVec3(p2.x(), p2.y(), p_.hover_height);
  out.position.head<2>() += (p_.explore_speed / p_.position_gain) * explore_dir_;
  out.yaw = hold_yaw_;
  if (p_.square_min_deflection > 0.0) {  // the path for squaring up (square_window)
    push_window(explore_history_, {in.t, p2, in.yaw}, p_.square_window);
  }
}

bool XplorerExplorer::tick_squaring(const XplorerInput& in, double dt, XplorerOutput& out) {
  // Squaring up to the face slid along (square_*, our choice): the yaw setpoint ramps at
  // turn_rate (001 Sec. V-C) to put C_n on the face normal, then holds square_hold s; the
  // contact is held along the normal (eq. 8 with r* reshaped along it), no lead along
  // the face; no turn trigger, concave-corner update or face lookback meanwhile.
  const XVec2 p2 = in.position.head<2>();
  const double dpsi = wrap(square_yaw_ - square_yaw0_);
  const double ramp_s = std::abs(dpsi) / p_.turn_rate, el = in.t - square_t0_;
  const XVec2 n = rot(square_yaw_, unit(contact_));
  if (f_body_avg_.norm() < p_.release_force) {
    if (low_force_since_ < 0) low_force_since_ = in.t;
    if (released(in.t)) {  // the face went: Exploration towards it
      explore_dir_ = n;
      enter(XplorerState::kExploration, XplorerReason::kContactLostSquaring, in, out);
      return true;
    }
  } else {
    low_force_since_ = -1.0;
  }
  if (el < ramp_s + p_.square_hold) {
    const XVec3 f_des(-p_.contact_force * n.x(), -p_.contact_force * n.y(), 0.0);
    const double rn = reshape(n, p2, in.force, f_des, dt);
    const XVec2 rs = p2 + (rn - p2.dot(n)) * n;
    adm_.update(in.force, f_des, XVec3(rs.x(), rs.y(), p_.hover_height), in.torque_z, 0.0, in.yaw, dt);
    out.position = adm_.position();
    out.yaw = wrap(square_yaw0_ + std::copysign(std::min(p_.turn_rate * std::max(el, 0.0), std::abs(dpsi)), dpsi));
    t_quiet_ = in.t;
    return true;
  }
  squaring_ = false;  // squared: the traversal of 001 from here
  // The yaw row ran on under the ramp (yaw* = the measured yaw): restarted at rest from
  // the squared heading, or its lag and rate would carry the setpoint ~8 deg past it.
  adm_.reset_yaw(in.yaw);
  t_quiet_ = in.t;
  low_force_since_ = -1.0;
  traverse_history_.clear();
  return false;
}

void XplorerExplorer::tick_traversal(const XplorerInput& in, double dt, XplorerOutput& out) {
  // Tactile-traversal runs in phases: the contact back-off (after a contact from
  // Exploration), squaring up (after a face slid along), then the traversal of 001.
  if (in.t < backoff_until_) {
    // Contact back-off: hold its setpoint; the traversal starts afterwards from where the
    // vehicle is (no turn trigger, release timer or reshaped r* from the back-off).
    hold_backoff(in, out);
    return;
  }
  if (squaring_ && tick_squaring(in, dt, out)) return;
  const XVec2 p2 = in.position.head<2>();
  // 001 Sec. IV-A: a yaw-rate peak (release at a corner) starts Tactile-turning.
  push_window(traverse_history_, {in.t, p2, in.yaw}, p_.corner_lookback);
  // A convex corner of the right-hand traversal turns counter-clockwise (yaw rate > 0).
  // A clockwise peak may turn once (re-aligning after an oblique contact); a second
  // clockwise turn before a counter-clockwise one would cycle round one corner point,
  // so that peak leaves the traversal going on (C_n follows the yaw).
  const bool against = peak_against_the_traversal();
  const bool peak = yaw_rate_peak(in.t);
  if (peak && against) {
    if (!peak_against_) ++turns_against_;
    peak_against_ = true;
  } else if (std::abs(yaw_rate_f_) <= p_.yaw_rate_trigger) {
    peak_against_ = false;
  }
  if (peak && !against) {
    const double sign = yaw_rate_f_ > 0 ? 1.0 : -1.0;
    clockwise_in_a_row_ = sign > 0 ? 0 : clockwise_in_a_row_ + 1;
    // The face as it was before the release (the yaw has already turned by the time the
    // low-passed rate crosses the trigger): corner_lookback s ago.
    const PoseSample& f = traverse_history_.front();
    plan_turn(sign, f.yaw, f.p, in);
    enter(XplorerState::kTactileTurning, XplorerReason::kYawRatePeak, in, out);
    return;
  }
  // A new contact in the move direction (concave corner): C_n <- latest contact.
  const BodyDirection c = contact_direction(f_body_avg_, p_.delta_0);
  if (c != BodyDirection::kNone && c == move_ && in.t - t_quiet_ > p_.settle_time) {
    contact_ = c;
    move_ = right_hand(c);
    t_quiet_ = in.t;
    reason_code_ = XplorerReason::kNewContact;
    reason_ = reason_text(reason_code_);
    traverse_history_.clear();  // the face ahead is the new one
  }
  if (f_body_avg_.norm() < p_.release_force) {
    if (low_force_since_ < 0) {
      low_force_since_ = in.t;
      lost_p_ = p2;  // the face as it was when the force went
      lost_yaw_ = in.yaw;
    }
    if (turns_about_the_faces_end(in.t)) {
      // The face ended without a yaw-rate peak (an obtuse convex corner the yaw followed
      // slowly): right-hand traversal round a convex object goes on round the corner,
      // so turn counter-clockwise about it instead of flying off along the lost C_n.
      clockwise_in_a_row_ = 0;
      plan_turn(1.0, lost_yaw_, lost_p_, in);
      enter(XplorerState::kTactileTurning, XplorerReason::kContactLostTurn, in, out);
      return;
    }
    if (released(in.t)) {
      explore_dir_ = rot(in.yaw, unit(contact_));
      enter(XplorerState::kExploration, XplorerReason::kContactLost, in, out);
      return;
    }
  } else {
    low_force_since_ = -1.0;
  }
  const XVec2 n = rot(in.yaw, unit(contact_)), t = rot(in.yaw, unit(move_));
  const XVec3 f_des(-p_.contact_force * n.x(), -p_.contact_force * n.y(), 0.0);
  // r*: along lambda a lead ahead of the vehicle, along C_n reshaped by the force error.
  const double lead_t = p_.traverse_speed / p_.position_gain;
  const double rn = reshape(n, p2, in.force, f_des, dt);
  const XVec2 rs = p2 + (rn - p2.dot(n)) * n + lead_t * t;
  adm_.update(in.force, f_des, XVec3(rs.x(), rs.y(), p_.hover_height), in.torque_z, 0.0, in.yaw, dt);  // 001 eq. 8
  out.position = adm_.position();
  out.yaw = adm_.yaw();
}

void XplorerExplorer::tick_turning(const XplorerInput& in, XplorerOutput& out) {
  // Re-contact (|b_delta_f_x| or |b_delta_f_y| > delta_psi0), once the moving
  // average no longer holds the force of the face just left.
  if (re_contact(in.t)) {
    contact_ = contact_direction(f_body_avg_, p_.delta_psi0);
    move_ = right_hand(contact_);
    enter(XplorerState::kTactileTraversal, XplorerReason::kReContact, in, out);
    return;
  }
  if (turn_limit_passed(in.t)) {
    explore_dir_ = rot(in.yaw, unit(contact_));
    enter(XplorerState::kExploration, XplorerReason::kTurnLimit, in, out);
    return;
  }
  out.position = turning_setpoint(in, &out.yaw);
}

void XplorerExplorer::tick_static_wrench(const XplorerInput& in, double dt, XplorerOutput& out) {
  if (in.t < backoff_until_) {
    hold_backoff(in, out);
    return;
  }
  // 001 Sec. V-B: delta_f_ref = 1 N onto the surface, r* = current position
  // (the setpoint is reshaped by the force error only).
  const XVec2 p2 = in.position.head<2>();
  const XVec2 n = rot(in.yaw, unit(contact_));
  const XVec3 f_des(-p_.static_force * n.x(), -p_.static_force * n.y(), 0.0);
  const double rn = reshape(n, p2, in.force, f_des, dt);
  const XVec2 h = hold_.head<2>();
  const XVec2 rs = h + (rn - h.dot(n)) * n;  // tangentially at the contact point
  adm_.update(in.force, f_des, XVec3(rs.x(), rs.y(), p_.hover_height), in.torque_z, 0.0, in.yaw, dt);
  out.position = adm_.position();
  out.yaw = adm_.yaw();
}

void XplorerExplorer::tick_ricochet(const XplorerInput& in, XplorerOutput& out) {
  // 001 Sec. IV-C: fly at the maximum speed along the line to the goal (beyond
  // it), collide, recover (setpoint away from the collision, proportional to
  // its intensity), then regulate at the goal.
  const XVec2 p2 = in.position.head<2>();
  const XVec2 dir = (p_.goal - hold_.head<2>()).normalized();
  const double fmag = in.force.head<2>().norm();
  if (collision_peak_ == 0.0 && fmag > p_.collision_force) {
    ++collisions_;
    collision_normal_ = in.force.head<2>().normalized();  // out of the obstacle
    collision_peak_ = fmag;
    t_quiet_ = in.t;
  }
  if (collision_peak_ > 0.0) {
    collision_peak_ = std::max(collision_peak_, fmag);
    recovery_sp_ = XVec3(p2.x(), p2.y(), p_.hover_height);
    recovery_sp_.head<2>() += p_.recovery_gain * collision_peak_ * collision_normal_;
    if (recovered(in.t)) {
      enter(XplorerState::kGoTo, XplorerReason::kCollisionRecovered, in, out);
      return;
    }
    out.position = recovery_sp_;
  } else {
    // Well past the goal without a collision (no wall there): regulate at the goal.
    if (goal_passed(p2)) {
      enter(XplorerState::kGoTo, XplorerReason::kGoalPassed, in, out);
      return;
    }
    out.position = XVec3(p2.x(), p2.y(), p_.hover_height);
    out.position.head<2>() += (p_.ricochet_speed / p_.position_gain + 1.0) * dir;  // saturates the vehicle's speed
  }
  out.yaw = yaw_enter_;
}

}  // namespace tactile_fsm
