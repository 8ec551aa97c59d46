#include "tactile_fsm/whisker_wall_follower.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace tactile_fsm {

const char* to_string(FsmState s) {
  switch (s) {
    case FsmState::kHoverInit: return "HOVER_INIT";
    case FsmState::kFlyForward: return "FLY_FORWARD";
    case FsmState::kWallFollowing: return "WALL_FOLLOWING";
    case FsmState::kResumeForward: return "RESUME_FORWARD";
    case FsmState::kLanding: return "LANDING";
    case FsmState::kLanded: return "LANDED";
    case FsmState::kFailsafeHover: return "FAILSAFE_HOVER";
    case FsmState::kFailsafeLand: return "FAILSAFE_LAND";
  }
  return "UNKNOWN";
}

const char* to_string(WallSubState s) {
  switch (s) {
    case WallSubState::kNone: return "NONE";
    case WallSubState::kFlySideways: return "FLY_SIDEWAYS";
    case WallSubState::kFlyForward: return "FLY_FORWARD";
    case WallSubState::kFlyBackward: return "FLY_BACKWARD";
    case WallSubState::kTurnLeft: return "TURN_LEFT";
    case WallSubState::kTurnRight: return "TURN_RIGHT";
  }
  return "UNKNOWN";
}

const char* to_string(Side s) { return s == Side::kLeft ? "left" : "right"; }

Side side_from_string(const char* s) {
  if (std::strcmp(s, "right") == 0) return Side::kRight;
  if (std::strcmp(s, "left") == 0) return Side::kLeft;
  throw std::invalid_argument(std::string("side must be \"right\" or \"left\", got \"") + s + "\"");
}

namespace {

// Tolerance of time comparisons: ticks are sums of 20 ms steps in floating point.
constexpr double kTimeEps = 1e-9;

void require(bool ok, const char* field, const std::string& reason, double value) {
  if (!ok) {
    throw std::invalid_argument(std::string("WallFollowerParams.") + field + ": " + reason + ", got " +
                                std::to_string(value));
  }
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }
bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

/// One whisker's S_c sum moving: the RMS of its changes >= level > 0.
bool moves(double change_rms, double level) { return level > 0.0 && std::isfinite(change_rms) && change_rms >= level; }

/// Either whisker's S_c sum moving: a touch TDORC has not flagged yet
/// (whisk_pause_rms, clear_yaw_release_rms).
bool sum_moves(const WallFollowerInput& in, double level) {
  return moves(in.input_change_rms_left, level) || moves(in.input_change_rms_right, level);
}

/// Gain of the yaw tracking of a moving reference (whisk, yaw offset): the realignment's, or
/// 1.5 1/s with the realignment off.
double tracking_gain(const WallFollowerParams& p) { return p.realign_gain > 0.0 ? p.realign_gain : 1.5; }

}  // namespace

void WallFollowerParams::validate() const {
  require(finite_positive(v_max), "v_max", "must be finite and > 0", v_max);
  require(finite_positive(omega_max), "omega_max", "must be finite and > 0", omega_max);
  require(finite_positive(t_min), "t_min", "must be finite and > 0", t_min);
  require(std::isfinite(t_max) && t_max > t_min, "t_max", "must be finite and > t_min", t_max);
  require(finite_positive(whisker_spacing), "whisker_spacing", "must be finite and > 0", whisker_spacing);
  require(finite_nonneg(hover_init_s), "hover_init_s", "must be finite and >= 0", hover_init_s);
  require(finite_positive(flight_height), "flight_height", "must be finite and > 0", flight_height);
  require(std::isfinite(align_enter) && align_enter > 0.0 && align_enter < M_PI / 2, "align_enter",
          "must be in (0, pi/2)", align_enter);
  require(std::isfinite(align_exit) && align_exit >= 0.0 && align_exit <= align_enter, "align_exit",
          "must be in [0, align_enter]", align_exit);
  require(finite_nonneg(depth_filter_tau_s), "depth_filter_tau_s", "must be finite and >= 0", depth_filter_tau_s);
  require(finite_nonneg(side_deadband), "side_deadband", "must be finite and >= 0", side_deadband);
  require(finite_nonneg(clear_confirm_s), "clear_confirm_s", "must be finite and >= 0", clear_confirm_s);
  require(finite_nonneg(clear_margin), "clear_margin", "must be finite and >= 0", clear_margin);
  require(finite_nonneg(realign_gain), "realign_gain", "must be finite and >= 0", realign_gain);
  require(std::isfinite(max_heading_offset) && max_heading_offset >= 0.0 && max_heading_offset <= M_PI,
          "max_heading_offset", "must be in [0, pi]", max_heading_offset);
  require(finite_nonneg(turn_anchor_tolerance) && turn_anchor_tolerance <= M_PI, "turn_anchor_tolerance",
          "must be in [0, pi] (0 = off)", turn_anchor_tolerance);
  require(std::isfinite(turn_anchor_theta) && turn_anchor_theta > 0.0 && turn_anchor_theta < M_PI / 2,
          "turn_anchor_theta", "must be in (0, pi/2)", turn_anchor_theta);
  require(finite_nonneg(turn_anchor_rate), "turn_anchor_rate", "must be finite and >= 0 (0 = fixed)", turn_anchor_rate);
  require(std::isfinite(wall_end_depth) && (wall_end_depth == 0.0 || wall_end_depth >= t_max), "wall_end_depth",
          "must be 0 (off) or finite and >= t_max", wall_end_depth);
  require(finite_nonneg(same_obstacle_distance), "same_obstacle_distance", "must be finite and >= 0",
          same_obstacle_distance);
  require(finite_nonneg(press_sum_pa), "press_sum_pa", "must be finite and >= 0 (0 = off)", press_sum_pa);
  require(finite_nonneg(press_hold_s), "press_hold_s", "must be finite and >= 0", press_hold_s);
  require(finite_positive(press_depth), "press_depth", "must be finite and > 0", press_depth);
  require(std::isfinite(whisker_base_x), "whisker_base_x", "must be finite", whisker_base_x);
  require(finite_nonneg(phantom_quiet_rms), "phantom_quiet_rms", "must be finite and >= 0 (0 = off)",
          phantom_quiet_rms);
  require(finite_nonneg(phantom_travel), "phantom_travel", "must be finite and >= 0", phantom_travel);
  require(finite_nonneg(phantom_resume_max), "phantom_resume_max", "must be finite and >= 0", phantom_resume_max);
  require(std::isfinite(whisk_rate_max) && whisk_rate_max > 0.0, "whisk_rate_max", "must be finite and > 0",
          whisk_rate_max);
  require(finite_nonneg(whisk_pause_rms), "whisk_pause_rms", "must be finite and >= 0 (0 = off)", whisk_pause_rms);
  require(finite_nonneg(clear_yaw_offset) && clear_yaw_offset <= M_PI / 4.0, "clear_yaw_offset",
          "must be in [0, pi/4] (0 = off)", clear_yaw_offset);
  require(finite_nonneg(clear_yaw_release_rms), "clear_yaw_release_rms", "must be finite and >= 0 (0 = off)",
          clear_yaw_release_rms);
  require(finite_nonneg(first_whisk_amplitude) && first_whisk_amplitude <= M_PI / 2.0, "first_whisk_amplitude",
          "must be in [0, pi/2] (0 = off)", first_whisk_amplitude);
  require(std::isfinite(first_scan_step) && first_scan_step >= 0.02, "first_scan_step",
          "must be finite and >= 0.02 m (the step ends 15 mm before its end)", first_scan_step);
  require(finite_positive(first_scan_rate) && first_scan_rate <= whisk_rate_max, "first_scan_rate",
          "must be finite, > 0 and <= whisk_rate_max", first_scan_rate);
  require(finite_nonneg(end_contact_lateral), "end_contact_lateral", "must be finite and >= 0 (0 = off)",
          end_contact_lateral);
  require(finite_positive(target_radius), "target_radius", "must be finite and > 0", target_radius);
  require(finite_nonneg(landing_duration_s), "landing_duration_s", "must be finite and >= 0", landing_duration_s);
  require(finite_positive(max_input_age_s), "max_input_age_s", "must be finite and > 0", max_input_age_s);
  require(finite_nonneg(failsafe_land_after_s), "failsafe_land_after_s", "must be finite and >= 0",
          failsafe_land_after_s);
}

WallSubState wall_sub_state(double d_l, bool l_valid, double d_r, bool r_valid, Side side, bool both_touched,
                            WallSubState current, const WallFollowerParams& p, double theta_in) {
  l_valid = l_valid && std::isfinite(d_l);
  r_valid = r_valid && std::isfinite(d_r);
  if (!l_valid && !r_valid) return WallSubState::kFlySideways;
  if (l_valid != r_valid) {
    const bool leading_lost = (side == Side::kRight) ? !r_valid : !l_valid;
    if (both_touched && p.wall_end_depth > 0.0 && (l_valid ? d_l : d_r) > p.wall_end_depth) {
      // One whisker lost after both touched, the other beyond wall_end_depth:
      // the wall ends here (a whisker held past the end), not a wall ahead;
      // keep passing the edge instead of flying forward into the end (issue
      // 17, docs/tuning/tactile_fsm.md "Round 7"; our choice).
      return WallSubState::kFlySideways;
    }
    if (both_touched && leading_lost) {
      // The leading whisker ran off the wall's end: keep passing the edge.
      const double remaining = l_valid ? d_l : d_r;
      return remaining < p.t_min ? WallSubState::kFlyBackward : WallSubState::kFlySideways;
    }
    if (both_touched && p.hold_heading_trailing_lost) {
      // The trailing whisker lost the wall the leading one is still on: at a
      // straight baffle it cannot have run off an end, so hold the heading and
      // keep the remaining depth in the band (issue 17; docs/whisker_fsm.md "Trailing whisker lost").
      const double remaining = l_valid ? d_l : d_r;
      if (remaining < p.t_min) return WallSubState::kFlyBackward;
      if (remaining > p.t_max) return WallSubState::kFlyForward;
      return WallSubState::kFlySideways;
    }
    // Approach (or trailing whisker lost): the missing depth is beyond the
    // whisker's reach, hence beyond T_max.
    const double far = p.t_max + p.whisker_spacing;
    if (!l_valid) d_l = far;
    if (!r_valid) d_r = far;
  }
  // Wall angle in the body frame, 000 eq. 21: theta = atan((d_l - d_r) / s).
  // theta > 0: the wall is nearer on the right; the heading perpendicular to
  // the wall is yaw - theta, i.e. turn right (clockwise).
  const double theta = (l_valid && r_valid && std::isfinite(theta_in)) ? theta_in
                                                                      : std::atan((d_l - d_r) / p.whisker_spacing);
  const WallSubState turn = theta > 0.0 ? WallSubState::kTurnRight : WallSubState::kTurnLeft;
  const bool turning = current == WallSubState::kTurnLeft || current == WallSubState::kTurnRight;
  const int band_l = d_l < p.t_min ? -1 : (d_l > p.t_max ? 1 : 0);
  const int band_r = d_r < p.t_min ? -1 : (d_r > p.t_max ? 1 : 0);
  if (band_l == -1 && band_r == -1) return WallSubState::kFlyBackward;  // both too close
  if (band_l == 1 && band_r == 1) return WallSubState::kFlyForward;     // both too far
  if (band_l != band_r) {
    // Different intervals: the heading is off (000 Fig. S4e turn conditions).
    if (std::fabs(theta) > p.align_exit) return turn;
    // Aligned but straddling a band edge: translate back into the band.
    return (band_l == -1 || band_r == -1) ? WallSubState::kFlyBackward : WallSubState::kFlyForward;
  }
  // Both inside [T_min, T_max]: align (hysteresis), then fly along the wall.
  if (std::fabs(theta) > p.align_enter || (turning && std::fabs(theta) > p.align_exit)) return turn;
  return WallSubState::kFlySideways;
}

void WallFollowing::motion(const WallFollowerParams& p, Setpoint* sp) const {
  switch (sub_) {  // 000 Fig. S4e: V_sideway = V_max, V_forward = V_backward = V_max/2, omega_max
    case WallSubState::kFlySideways: sp->vy = side_ == Side::kLeft ? p.v_max : -p.v_max; break;  // vy > 0: left
    case WallSubState::kFlyForward: sp->vx = 0.5 * p.v_max; break;
    case WallSubState::kFlyBackward: sp->vx = -0.5 * p.v_max; break;
    case WallSubState::kTurnLeft: sp->yaw_rate = p.omega_max; break;
    case WallSubState::kTurnRight: sp->yaw_rate = -p.omega_max; break;
    case WallSubState::kNone: break;
  }
}

Setpoint saturate(const Setpoint& s, const WallFollowerParams& p) {
  Setpoint o = s;
  if (!std::isfinite(o.vx)) o.vx = 0.0;
  if (!std::isfinite(o.vy)) o.vy = 0.0;
  if (!std::isfinite(o.yaw_rate)) o.yaw_rate = 0.0;
  if (!std::isfinite(o.height)) o.height = 0.0;
  const double speed = std::hypot(o.vx, o.vy);
  if (speed > p.v_max) {
    const double k = p.v_max / speed;
    o.vx *= k;
    o.vy *= k;
  }
  o.yaw_rate = std::clamp(o.yaw_rate, -p.omega_max, p.omega_max);
  return o;
}

const char* to_string(WhiskerReason r) {
  switch (r) {
    case WhiskerReason::kNone: return "none";
    case WhiskerReason::kHoverDone: return "hover_done";
    case WhiskerReason::kContact: return "contact";
    case WhiskerReason::kContactSameObstacle: return "contact_same_obstacle";
    case WhiskerReason::kContactBaffleEnd: return "contact_at_baffle_end";
    case WhiskerReason::kContactWhileClearing: return "contact_while_clearing";
    case WhiskerReason::kObstacleCleared: return "obstacle_cleared";
    case WhiskerReason::kClearedByMargin: return "cleared_by_margin";
    case WhiskerReason::kTargetReached: return "target_reached";
    case WhiskerReason::kLandingDone: return "landing_done";
    case WhiskerReason::kSubStateRule: return "sub_state_rule";
    case WhiskerReason::kHeadingLimit: return HeadingLimitRule::kName;
    case WhiskerReason::kTurnAnchor: return TurnAnchorRule::kName;
    case WhiskerReason::kStepAndScan: return StepAndScanRule::kName;
    case WhiskerReason::kYawOffset: return YawOffsetRule::kName;
  }
  return "unknown";
}

// --- Whisker ----------------------------------------------------------------

void Whisker::reset() {
  filtered_ = NAN;
  pressed_t_ = -INFINITY;
  live_x_ = live_y_ = NAN;
  phantom_ = false;
  reading_ = WhiskerReading{};
}

const WhiskerReading& Whisker::update(const WhiskerSample& s, double t, double dt, bool pose_ok, double x,
                                      double y) {
  WhiskerReading r;
  r.valid = s.depth_fresh && s.valid && std::isfinite(s.depth);
  bool tdorc = s.tdorc_contact;
  r.held_raw = r.valid || tdorc;  // contact as reported, before the phantom gate

  // Phantom hold gated by odometry (issue 17, docs/tuning/tactile_fsm.md "Round 4"): a held
  // contact whose S_c sum (000 eq. 5) stays quiet while the drone travels
  // more than phantom_travel is the gel-hysteresis offset (000 eq. 1, N_h) of
  // a whisker that left the wall, not a wall: ignore it.
  if (p_.phantom_quiet_rms > 0.0 && pose_ok) {
    // Free, unknown or moving: the contact (if any) is live here.
    // phantom_latch: once taken for a phantom, a whisker stays one until its
    // contact ends or its sum moves clearly (RMS >= twice the quiet level, a
    // new touch); without it the free whisker's noise, which crosses the
    // quiet level itself, lets the phantom back in for a moment.
    const double rms = s.input_change_rms;
    const double live_rms = (p_.phantom_latch && phantom_) ? 2.0 * p_.phantom_quiet_rms : p_.phantom_quiet_rms;
    if (!r.held_raw || !std::isfinite(rms) || rms >= live_rms || !std::isfinite(live_x_)) {
      live_x_ = x;
      live_y_ = y;
      phantom_ = false;
    } else {
      phantom_ = (p_.phantom_latch && phantom_) || std::hypot(x - live_x_, y - live_y_) > p_.phantom_travel;
      if (phantom_) {
        r.valid = false;
        tdorc = false;
      }
    }
  } else {
    phantom_ = false;
  }
  r.phantom = phantom_;
  r.contact = r.valid || tdorc;
  r.depth = r.valid ? s.depth : NAN;

  // First-order low-pass of the depth for the sub-state rule (our choice;
  // restarts when the whisker loses the wall).
  const double a = p_.depth_filter_tau_s > 0.0 ? dt / (p_.depth_filter_tau_s + dt) : 1.0;
  filtered_ = !r.valid ? NAN : (std::isfinite(filtered_) ? filtered_ + a * (s.depth - filtered_) : s.depth);
  r.filtered = filtered_;
  r.rule_depth = filtered_;

  // Pressed past the depth model (issue 17, docs/whisker_fsm.md "Pressed whisker"): the
  // whisker's S_c sum bounds its depth by press_depth whatever depth is read.
  if (p_.press_sum_pa > 0.0) {
    if (r.valid && s.input_sum >= p_.press_sum_pa) pressed_t_ = t;
    if (!r.valid) pressed_t_ = -INFINITY;
    if (r.valid && t - pressed_t_ <= p_.press_hold_s + kTimeEps) {
      r.pressed = true;
      r.rule_depth = std::fmin(r.rule_depth, p_.press_depth);
    }
  }
  reading_ = r;
  return reading_;
}

// --- Guards -------------------------------------------------------------------

namespace guards {

bool hover_done(const TickSnapshot& s, const WallFollowerParams& p) {
  return s.in.t - s.entered >= p.hover_init_s - kTimeEps;
}

bool contact(const TickSnapshot& s, const WallFollowerParams&) { return s.left.contact || s.right.contact; }

bool contact_while_clearing(const TickSnapshot& s, const WallFollowerParams& p) {
  // Contact again while side-stepping past the edge: the same obstacle's end
  // (the contact flags dropped early). Kept side, passing the edge (rule 2),
  // not a new approach, which would turn toward the touching whisker and wrap the tip.
  return contact(s, p);
}

bool contact_same_obstacle(const TickSnapshot& s, const WallFollowerParams& p) {
  // Contact right after a clearing: the same obstacle (its contact flags
  // dropped mid-wall). Keep the side instead of re-choosing it, which went
  // back along the baffle (issue 17; docs/whisker_fsm.md "Same obstacle").
  return contact(s, p) && s.after_clear &&
         std::cos(s.course_yaw) * (s.in.x - s.resume_x) + std::sin(s.course_yaw) * (s.in.y - s.resume_y) <
             p.same_obstacle_distance;
}

double end_contact_offset(const TickSnapshot& s, const WallFollowerParams& p) {
  // Lateral offset (left > 0) of the touching whisker's contact point from the
  // course axis through the drone: the point (whisker_base_x + d, +-s/2) of the
  // body frame turned by the yaw off the course heading. Exactly one whisker,
  // with its depth.
  if (s.left.contact == s.right.contact || !s.origin_set || !std::isfinite(s.in.yaw)) return 0.0;
  const WhiskerReading& w = s.left.contact ? s.left : s.right;
  if (!w.valid) return 0.0;
  const double side = s.left.contact ? 1.0 : -1.0;
  const double rel = std::remainder(s.in.yaw - s.course_yaw, 2.0 * M_PI);
  const double lat = std::sin(rel) * (p.whisker_base_x + w.depth) + std::cos(rel) * side * 0.5 * p.whisker_spacing;
  // Only on that whisker's side (the end lies where its baffle is).
  return lat * side > 0.0 ? lat : 0.0;
}

bool contact_at_baffle_end(const TickSnapshot& s, const WallFollowerParams& p) {
  // A baffle's end met by one whisker beside the axis (docs/tuning/tactile_fsm.md "Round 10").
  return contact(s, p) && p.end_contact_lateral > 0.0 && std::fabs(end_contact_offset(s, p)) > p.end_contact_lateral;
}

bool cleared_by_margin(const TickSnapshot& s, const WallFollowerParams& p) {
  // A whisker still held as a phantom: TDORC has not released it yet, and its
  // window learns what follows the release (a new contact would go unseen);
  // keep side-stepping, up to phantom_resume_max.
  const double moved = std::hypot(s.in.x - s.clear_x, s.in.y - s.clear_y);
  return moved >= p.clear_margin && (!(s.left.held_raw || s.right.held_raw) || moved >= p.phantom_resume_max);
}

bool obstacle_cleared(const TickSnapshot& s, const WallFollowerParams& p) {
  return !contact(s, p) && s.in.t - s.last_contact_t >= p.clear_confirm_s - kTimeEps;
}

bool target_reached(const TickSnapshot& s, const WallFollowerParams& p) {
  const WallFollowerInput& in = s.in;
  if (!in.has_target) return false;
  const double ex = in.x - in.target_x, ey = in.y - in.target_y;
  if (std::hypot(ex, ey) <= p.target_radius) return true;
  if (!p.land_past_target) return false;
  // Past the target along the course direction (course start -> target).
  const double cx = in.target_x - s.origin_x, cy = in.target_y - s.origin_y;
  const double n = std::hypot(cx, cy);
  if (n < 1e-6) return false;
  return (ex * cx + ey * cy) / n >= 0.0;
}

bool landing_done(const TickSnapshot& s, const WallFollowerParams& p) {
  return s.in.t - s.entered >= p.landing_duration_s - kTimeEps;
}

}  // namespace guards

// --- Transition tables ----------------------------------------------------------

namespace {

#define TACTILE_GUARD(g) #g, &guards::g
constexpr Transition kHoverInitTable[] = {
    {TACTILE_GUARD(hover_done), FsmState::kFlyForward, WhiskerReason::kHoverDone, "hover initialisation done"},
};
constexpr Transition kFlyForwardTable[] = {
    {TACTILE_GUARD(target_reached), FsmState::kLanding, WhiskerReason::kTargetReached, "target reached"},
    {TACTILE_GUARD(contact_same_obstacle), FsmState::kWallFollowing, WhiskerReason::kContactSameObstacle,
     "whisker contact, same obstacle (just cleared)"},
    {TACTILE_GUARD(contact_at_baffle_end), FsmState::kWallFollowing, WhiskerReason::kContactBaffleEnd,
     "whisker contact at a baffle's end beside the axis"},
    {TACTILE_GUARD(contact), FsmState::kWallFollowing, WhiskerReason::kContact, "whisker contact"},
};
constexpr Transition kWallFollowingTable[] = {
    {TACTILE_GUARD(target_reached), FsmState::kLanding, WhiskerReason::kTargetReached, "target reached"},
    {TACTILE_GUARD(obstacle_cleared), FsmState::kResumeForward, WhiskerReason::kObstacleCleared,
     "obstacle cleared (both whiskers off the wall)"},
};
constexpr Transition kResumeForwardTable[] = {
    {TACTILE_GUARD(target_reached), FsmState::kLanding, WhiskerReason::kTargetReached, "target reached"},
    {TACTILE_GUARD(contact_while_clearing), FsmState::kWallFollowing, WhiskerReason::kContactWhileClearing,
     "whisker contact while clearing"},
    {TACTILE_GUARD(cleared_by_margin), FsmState::kFlyForward, WhiskerReason::kClearedByMargin,
     "cleared the obstacle by the margin"},
};
constexpr Transition kLandingTable[] = {
    {TACTILE_GUARD(landing_done), FsmState::kLanded, WhiskerReason::kLandingDone, "landing complete"},
};
#undef TACTILE_GUARD

template <std::size_t N>
TransitionTable table_of(const Transition (&rows)[N]) {
  return TransitionTable{rows, N};
}

bool flying(FsmState s) {
  return s == FsmState::kFlyForward || s == FsmState::kWallFollowing || s == FsmState::kResumeForward;
}

WhiskerSample sample_of(const WallFollowerInput& in, bool depth_fresh, bool left) {
  WhiskerSample w;
  w.depth_fresh = depth_fresh;
  w.valid = left ? in.left_valid : in.right_valid;
  w.depth = left ? in.depth_left : in.depth_right;
  w.tdorc_contact = left ? in.tdorc_contact_left : in.tdorc_contact_right;
  w.input_sum = left ? in.input_sum_left : in.input_sum_right;
  w.input_change_rms = left ? in.input_change_rms_left : in.input_change_rms_right;
  return w;
}

SafetyParams safety_params(const WallFollowerParams& p) {
  SafetyParams s;
  s.max_input_age_s = p.max_input_age_s;
  s.failsafe_land_after_s = p.failsafe_land_after_s;
  // No time limit: the follower lands at the target (time_limit_s infinite).
  return s;
}

const WallFollowerParams& validated(const WallFollowerParams& p) {
  p.validate();  // before the members built from it (the SafetyRunner validates its own copy)
  return p;
}

uint8_t code_of(WhiskerReason r) { return static_cast<uint8_t>(r); }

WhiskerReason reason_of(OverrideRule r) {
  switch (r) {
    case OverrideRule::kHeadingLimit: return WhiskerReason::kHeadingLimit;
    case OverrideRule::kTurnAnchor: return WhiskerReason::kTurnAnchor;
    case OverrideRule::kStepAndScan: return WhiskerReason::kStepAndScan;
    case OverrideRule::kYawOffset: return WhiskerReason::kYawOffset;
  }
  return WhiskerReason::kNone;
}

}  // namespace

TransitionTable transition_table(FsmState s) {
  switch (s) {
    case FsmState::kHoverInit: return table_of(kHoverInitTable);
    case FsmState::kFlyForward: return table_of(kFlyForwardTable);
    case FsmState::kWallFollowing: return table_of(kWallFollowingTable);
    case FsmState::kResumeForward: return table_of(kResumeForwardTable);
    case FsmState::kLanding: return table_of(kLandingTable);
    case FsmState::kLanded:
    case FsmState::kFailsafeHover:
    case FsmState::kFailsafeLand:
      break;
  }
  return TransitionTable{};
}

// --- The follower ------------------------------------------------------------

WhiskerWallFollower::WhiskerWallFollower(const WallFollowerParams& params)
    : p_(validated(params)),
      left_(params),
      right_(params),
      safety_(safety_params(params), {SafetyInput::kDepth, SafetyInput::kOdometry}),
      heading_limit_(params),
      turn_anchor_(params),
      step_and_scan_(params),
      yaw_offset_(params) {
  reset();
}

void WhiskerWallFollower::reset() {
  state_ = previous_ = FsmState::kHoverInit;
  reason_ = "start";
  reason_code_ = code_of(WhiskerReason::kNone);
  reason_composed_ = false;
  started_ = false;
  entered_ = last_t_ = 0.0;
  transitions_ = 0;
  wall_.begin(p_.follow_side);
  last_contact_t_ = 0.0;
  left_.reset();
  right_.reset();
  safety_.reset();
  wall_heading_ = theta_ = NAN;
  origin_set_ = false;
  origin_x_ = origin_y_ = clear_x_ = clear_y_ = 0.0;
  after_clear_ = false;
  resume_x_ = resume_y_ = 0.0;
  contacted_ = false;
  course_yaw_ = 0.0;
  heading_limit_.reset();
  turn_anchor_.reset();
  step_and_scan_.reset();
  yaw_offset_.reset();
  override_count_.fill(0);
  override_active_.fill(false);
  override_started_ = false;
}

void WhiskerWallFollower::enter(FsmState s, const char* reason, uint8_t code, double t) {
  previous_ = state_;
  state_ = s;
  reason_ = reason;
  reason_code_ = code;
  reason_composed_ = false;
  entered_ = t;
  ++transitions_;
  wall_.set_sub_state(WallSubState::kNone);
}

void WhiskerWallFollower::set_origin(const WallFollowerInput& in) {
  origin_set_ = true;
  origin_x_ = in.x;
  origin_y_ = in.y;
  course_yaw_ = std::isfinite(in.yaw) ? in.yaw : 0.0;
}

void WhiskerWallFollower::fill_snapshot(TickSnapshot& snap) const {
  snap.state = state_;
  snap.current = wall_.sub_state();
  snap.side = wall_.side();
  snap.left = left_.reading();
  snap.right = right_.reading();
  snap.l_valid = snap.left.valid;
  snap.r_valid = snap.right.valid;
  snap.d_left = snap.left.rule_depth;
  snap.d_right = snap.right.rule_depth;
  snap.theta = theta_;
  snap.wall_heading = wall_heading_;
  snap.origin_set = origin_set_;
  snap.origin_x = origin_x_;
  snap.origin_y = origin_y_;
  snap.course_yaw = course_yaw_;
  snap.after_clear = after_clear_;
  snap.contacted = contacted_;
  snap.entered = entered_;
  snap.last_contact_t = last_contact_t_;
  snap.clear_x = clear_x_;
  snap.clear_y = clear_y_;
  snap.resume_x = resume_x_;
  snap.resume_y = resume_y_;
}

void WhiskerWallFollower::on_entry(FsmState s, const TickSnapshot& snap, uint8_t code) {
  const WallFollowerInput& in = snap.in;
  switch (s) {
    case FsmState::kFlyForward:
      // The course (heading and start) is set when the flight first goes
      // forward: at the end of HOVER_INIT, or on resuming from a fail-safe
      // hover that began there.
      if (!origin_set_) set_origin(in);
      if (code == code_of(WhiskerReason::kClearedByMargin)) {
        after_clear_ = true;
        resume_x_ = in.x;
        resume_y_ = in.y;
      }
      break;
    case FsmState::kWallFollowing:
      last_contact_t_ = in.t;
      if (code == code_of(WhiskerReason::kContactWhileClearing)) {
        wall_.begin(wall_.side(), true);  // the same obstacle's end: passing the edge (rule 2)
      } else if (code == code_of(WhiskerReason::kContactSameObstacle)) {
        wall_.begin(wall_.side());  // the side kept
      } else if (code == code_of(WhiskerReason::kContactBaffleEnd)) {
        // Pass the end on the other side, as an edge (rule 2).
        wall_.begin(guards::end_contact_offset(snap, p_) > 0.0 ? Side::kRight : Side::kLeft, true);
      } else {
        // A new obstacle. Side: toward the target's lateral offset in the body
        // frame when it is clear, else the configured side.
        Side side = p_.follow_side;
        if (p_.side_toward_target && in.has_target) {
          const double lateral = -std::sin(in.yaw) * (in.target_x - in.x) + std::cos(in.yaw) * (in.target_y - in.y);
          if (lateral > p_.side_deadband) side = Side::kLeft;
          if (lateral < -p_.side_deadband) side = Side::kRight;
        }
        wall_.begin(side);
      }
      break;
    case FsmState::kResumeForward:
      clear_x_ = in.x;
      clear_y_ = in.y;
      break;
    case FsmState::kHoverInit:
    case FsmState::kLanding:
    case FsmState::kLanded:
    case FsmState::kFailsafeHover:
    case FsmState::kFailsafeLand:
      break;
  }
}

void WhiskerWallFollower::on_tick(const TickSnapshot& snap) {
  if (state_ != FsmState::kWallFollowing) return;
  if (guards::contact(snap, p_)) last_contact_t_ = snap.in.t;
  wall_.touched(snap.left.valid, snap.right.valid);
}

void WhiskerWallFollower::for_test_enter(FsmState s, const WallFollowerInput& in, WhiskerReason code) {
  if (s == FsmState::kFailsafeHover || s == FsmState::kFailsafeLand) {
    throw std::invalid_argument(std::string("WhiskerWallFollower::for_test_enter: ") + to_string(s) +
                                " is the SafetyRunner's state, entered by a stale input");
  }
  if (!started_) {
    started_ = true;
    last_t_ = in.t;
  }
  if (!origin_set_) set_origin(in);
  TickSnapshot snap;
  snap.in = in;
  fill_snapshot(snap);
  enter(s, "test", code_of(code), in.t);
  on_entry(s, snap, code_of(code));
}

WallFollowerOutput WhiskerWallFollower::step(const WallFollowerInput& in) {
  const double t = in.t;
  const FsmState state_before = state_;
  const WallSubState sub_before = wall_.sub_state();
  if (!started_) {
    started_ = true;
    entered_ = t;
    last_t_ = t;
  }
  const double dt = std::max(0.0, t - last_t_);
  last_t_ = t;

  // 1. Input gates: each Whisker's reading (validity, phantom gate, low-pass,
  // pressed cap), then the wall angle from the two.
  const bool depth_fresh = input_is_fresh(t, in.depth_stamp, p_.max_input_age_s);
  const bool pose_ok =
      input_is_fresh(t, in.odom_stamp, p_.max_input_age_s) && std::isfinite(in.x) && std::isfinite(in.y);
  const WhiskerReading& wl = left_.update(sample_of(in, depth_fresh, true), t, dt, pose_ok, in.x, in.y);
  const WhiskerReading& wr = right_.update(sample_of(in, depth_fresh, false), t, dt, pose_ok, in.x, in.y);
  // Wall angle, 000 eq. 21: theta = atan((d_l - d_r) / s), filtered as the
  // world-frame heading of the wall normal yaw - theta (our choice: a straight
  // wall keeps it constant while the drone turns, so the filter adds no lag
  // to the turn and the turn stops on time).
  if (wl.valid && wr.valid && std::isfinite(in.yaw)) {
    const double a = p_.depth_filter_tau_s > 0.0 ? dt / (p_.depth_filter_tau_s + dt) : 1.0;
    const double w = in.yaw - std::atan((wl.depth - wr.depth) / p_.whisker_spacing);
    wall_heading_ = std::isfinite(wall_heading_) ? wall_heading_ + a * std::remainder(w - wall_heading_, 2.0 * M_PI) : w;
    theta_ = std::remainder(in.yaw - wall_heading_, 2.0 * M_PI);
  } else {
    wall_heading_ = theta_ = NAN;
  }

  // 2. The state switch: the shared fail-safe first (a flying state, or the
  // end of HOVER_INIT, with stale depth or odometry), then the state's tick
  // and its transition table.
  TickSnapshot snap;
  snap.in = in;
  snap.dt = dt;
  fill_snapshot(snap);
  const bool guarded = flying(state_) || (state_ == FsmState::kHoverInit && guards::hover_done(snap, p_));
  const SafetyVerdict v = safety_.step(t, {in.depth_stamp, in.odom_stamp}, guarded);
  const uint8_t safety_code = static_cast<uint8_t>(v.reason);
  if (v.entered) {
    switch (v.state) {
      case SafetyState::kFailsafeHover: {
        const bool depth = safety_.stale_input() == SafetyInput::kDepth;
        const char* text = state_ != FsmState::kHoverInit ? v.text
                           : depth                         ? "tactile depth stale at end of hover"
                                                           : "odometry stale at end of hover";
        enter(FsmState::kFailsafeHover, text, safety_code, t);
        break;
      }
      case SafetyState::kNominal:  // inputs fresh again: forward
        enter(FsmState::kFlyForward, v.text, safety_code, t);
        on_entry(FsmState::kFlyForward, snap, safety_code);
        break;
      case SafetyState::kFailsafeLand:
      case SafetyState::kTimeLimitLand:  // not reached: no time limit (safety_params)
        enter(FsmState::kFailsafeLand, v.text, safety_code, t);
        break;
    }
  } else if (v.nominal()) {
    on_tick(snap);
    snap.last_contact_t = last_contact_t_;
    for (const Transition& row : transition_table(state_)) {
      if (!row.guard(snap, p_)) continue;
      enter(row.next, row.text, code_of(row.code), t);
      on_entry(row.next, snap, code_of(row.code));
      break;
    }
  }

  // 3. The sub-state rule (000 Fig. S4e) and the override rules (issue 33;
  // docs/whisker_fsm.md "Override rules"), in order: first on the sub-state
  // rule's result, then on the state's setpoint.
  const bool top = state_ != state_before;
  override_started_ = false;
  fill_snapshot(snap);
  snap.sub_state = state_ == FsmState::kWallFollowing
                       ? wall_.rule(snap.d_left, snap.l_valid, snap.d_right, snap.r_valid, p_, theta_)
                       : WallSubState::kNone;
  const WallSubState rule_sub = snap.sub_state;
  const char* sub_reason = nullptr;
  WhiskerReason sub_code = WhiskerReason::kSubStateRule;
  run_rule(heading_limit_, OverrideRule::kHeadingLimit, snap, top);
  if (snap.sub_state != rule_sub) {
    sub_reason = HeadingLimitRule::kReason;
    sub_code = WhiskerReason::kHeadingLimit;
  }
  const WallSubState limited_sub = snap.sub_state;
  run_rule(turn_anchor_, OverrideRule::kTurnAnchor, snap, top);
  if (snap.sub_state != limited_sub) {
    sub_reason = TurnAnchorRule::kReason;
    sub_code = WhiskerReason::kTurnAnchor;
  }
  if (snap.sub_state != wall_.sub_state() && !top) {
    // A sub-state change: the Fig. S4e rule's, or the override's that made it.
    if (sub_reason == nullptr) {
      reason_ = "sub-state rule (000 Fig. S4e)";
      reason_code_ = code_of(sub_code);
      reason_composed_ = false;
    } else if (!override_started_) {
      reason_ = sub_reason;  // else run_rule named it
      reason_code_ = code_of(sub_code);
      reason_composed_ = false;
    }
  }
  wall_.set_sub_state(snap.sub_state);

  // 4. The state's setpoint and the setpoint rules.
  WallFollowerOutput out;
  out.state = state_;
  out.sub_state = wall_.sub_state();
  out.transitioned = state_ != state_before || wall_.sub_state() != sub_before;
  if (state_ == FsmState::kWallFollowing) contacted_ = true;
  snap.contacted = contacted_;
  snap.setpoint = saturate(command(in), p_);
  run_rule(step_and_scan_, OverrideRule::kStepAndScan, snap, top);
  run_rule(yaw_offset_, OverrideRule::kYawOffset, snap, top);
  out.setpoint = snap.setpoint;
  out.override_started = override_started_;
  return out;
}

Setpoint WhiskerWallFollower::command(const WallFollowerInput& in) const {
  Setpoint s;
  s.height = p_.flight_height;
  const double sideways = wall_.side() == Side::kLeft ? p_.v_max : -p_.v_max;  // vy > 0 is left
  switch (state_) {
    case FsmState::kHoverInit:
    case FsmState::kFailsafeHover:
      break;
    case FsmState::kFlyForward:
      s.vx = p_.v_max;  // 000 Methods "Flying Forward" at V_max
      s.yaw_rate = realign(in);
      break;
    case FsmState::kResumeForward:
      s.vy = sideways;  // side-step past the edge, then FLY_FORWARD
      s.yaw_rate = realign(in);
      break;
    case FsmState::kWallFollowing:
      wall_.motion(p_, &s);  // the shared wall following's (000 Fig. S4e)
      break;
    case FsmState::kLanding:
    case FsmState::kLanded:
    case FsmState::kFailsafeLand:
      s.height = 0.0;
      s.land = true;
      break;
  }
  return s;
}

// --- Override rules ---------------------------------------------------------

const char* to_string(OverrideRule r) {
  switch (r) {
    case OverrideRule::kHeadingLimit: return HeadingLimitRule::kName;
    case OverrideRule::kTurnAnchor: return TurnAnchorRule::kName;
    case OverrideRule::kStepAndScan: return StepAndScanRule::kName;
    case OverrideRule::kYawOffset: return YawOffsetRule::kName;
  }
  return "unknown";
}

WallSubState translation_instead_of_turn(const TickSnapshot& s, const WallFollowerParams& p) {
  const double lo = std::fmin(s.l_valid ? s.d_left : INFINITY, s.r_valid ? s.d_right : INFINITY);
  const double hi = std::fmax(s.l_valid ? s.d_left : -INFINITY, s.r_valid ? s.d_right : -INFINITY);
  return (s.l_valid || s.r_valid) && lo < p.t_min   ? WallSubState::kFlyBackward
         : (s.l_valid || s.r_valid) && hi > p.t_max ? WallSubState::kFlyForward
                                                    : WallSubState::kFlySideways;
}

bool turns_beyond(const TickSnapshot& s, double ref, double limit) {
  const double off = std::remainder(s.in.yaw - ref, 2.0 * M_PI);
  return (s.sub_state == WallSubState::kTurnLeft && off >= limit) ||
         (s.sub_state == WallSubState::kTurnRight && off <= -limit);
}

bool HeadingLimitRule::applies(const TickSnapshot& s) const {
  return s.state == FsmState::kWallFollowing && p_.max_heading_offset > 0.0 && s.origin_set &&
         std::isfinite(s.in.yaw) && turns_beyond(s, s.course_yaw, p_.max_heading_offset);
}

bool TurnAnchorRule::tracks(const TickSnapshot& s) const {
  return s.state == FsmState::kWallFollowing && p_.turn_anchor_tolerance > 0.0 && s.l_valid && s.r_valid &&
         std::isfinite(s.wall_heading) && std::isfinite(s.theta);
}

void TurnAnchorRule::observe(const TickSnapshot& s) {
  if (s.state != FsmState::kWallFollowing) {
    anchor_ = NAN;  // a new wall following reads its own anchor
    return;
  }
  if (!tracks(s)) return;
  // Readings in a turn never move the anchor: a tip dragged round by the yaw
  // reads an angle toward the turn.
  const bool clear_angle = std::fabs(s.theta) >= p_.turn_anchor_theta;
  const bool turning = s.current == WallSubState::kTurnLeft || s.current == WallSubState::kTurnRight;
  if (!std::isfinite(anchor_) || (clear_angle && !turning)) {
    anchor_ = s.wall_heading;
  } else if (p_.turn_anchor_rate > 0.0 && !turning) {
    // Not turning: the anchor follows the wall heading read, at most
    // turn_anchor_rate (a wall that turns away slowly).
    const double step = p_.turn_anchor_rate * s.dt;
    anchor_ += std::clamp(std::remainder(s.wall_heading - anchor_, 2.0 * M_PI), -step, step);
  }
}

bool TurnAnchorRule::applies(const TickSnapshot& s) const {
  return tracks(s) && std::fabs(s.theta) < p_.turn_anchor_theta && std::isfinite(s.in.yaw) &&
         turns_beyond(s, anchor_, p_.turn_anchor_tolerance);
}

bool StepAndScanRule::applies(const TickSnapshot& s) const {
  // No clearing yet: the first baffle's end may lie in the blind band on either side.
  return p_.first_whisk_amplitude > 0.0 && s.state == FsmState::kFlyForward && !s.contacted && !s.after_clear &&
         s.origin_set && std::isfinite(s.in.yaw) && std::isfinite(s.in.x) && std::isfinite(s.in.y);
}

void StepAndScanRule::begin_scan(int leg) {
  scanning_ = true;
  ref_ = 0.0;
  leg_ = leg;
  hold_s_ = settle_s_ = 0.0;
}

void StepAndScanRule::apply(TickSnapshot& snap) {
  // Along the course the drone flies to the step's end, v = (goal - progress)
  // / kApproachTau (at most V_max), and holds it there while it scans; the
  // velocity is the course direction in the world frame, expressed in the
  // body-yaw frame.
  constexpr double kApproachTau = 0.3;  // [s], our choice: the vehicle's velocity lag is ~0.23 s
  constexpr double kAtGoal = 0.015;     // [m] the step is done this near its end
  constexpr double kSettled = 0.05;     // [rad] back on the course: the next step starts
  constexpr double kMaxHold = 1.0;      // [s] per scan: a moving sum no flag follows holds no longer
  constexpr double kMaxSettle = 2.0;    // [s] back toward the course at most this long, then step
  const WallFollowerInput& in = snap.in;
  const double dt = snap.dt;
  const double c = std::cos(snap.course_yaw), sn = std::sin(snap.course_yaw);
  const double progress = c * (in.x - snap.origin_x) + sn * (in.y - snap.origin_y);
  const double off = std::remainder(in.yaw - snap.course_yaw, 2.0 * M_PI);
  if (!std::isfinite(goal_)) {
    // (Re)entering the first approach, e.g. after a fail-safe hover in a
    // scan: off the course, settle first rather than step at a yawed heading.
    if (std::fabs(off) >= kSettled) {
      goal_ = progress;
      begin_scan(3);
    } else {
      goal_ = progress + p_.first_scan_step;
      scanning_ = false;
      ref_ = 0.0;  // a scan cut short (e.g. by a fail-safe hover) leaves no yaw offset
    }
  }
  const double a = p_.first_whisk_amplitude;
  const double r = p_.first_scan_rate;
  double ff = 0.0;
  if (!scanning_ && goal_ - progress < kAtGoal) begin_scan(0);
  // A whisker's sum moving: a touch TDORC has not flagged yet; hold the yaw
  // (up to kMaxHold per scan, so that a brush no flag follows cannot stop the
  // approach for good).
  const bool held = scanning_ && sum_moves(in, p_.whisk_pause_rms) && hold_s_ < kMaxHold;
  if (held) hold_s_ += dt;
  if (scanning_) {
    if (!held) {
      switch (leg_) {
        case 0: ref_ = std::fmin(a, ref_ + r * dt); ff = r; if (ref_ >= a) leg_ = 1; break;
        case 1: ref_ = std::fmax(-a, ref_ - r * dt); ff = -r; if (ref_ <= -a) leg_ = 2; break;
        case 2: ref_ = std::fmin(0.0, ref_ + r * dt); ff = r; if (ref_ >= 0.0) leg_ = 3; break;
        default: settle_s_ += dt; break;
      }
    }
    if (leg_ == 3 && (std::fabs(off) < kSettled || settle_s_ >= kMaxSettle)) {
      scanning_ = false;
      goal_ += p_.first_scan_step;
    }
  }
  Setpoint& o = snap.setpoint;
  if (held) {
    o.yaw_rate = 0.0;
  } else {
    o.yaw_rate = std::clamp(ff + tracking_gain(p_) * std::remainder(snap.course_yaw + ref_ - in.yaw, 2.0 * M_PI),
                            -p_.whisk_rate_max, p_.whisk_rate_max);
  }
  const double v = std::clamp((goal_ - progress) / kApproachTau, -p_.v_max, p_.v_max);
  o.vx = v * std::cos(off);
  o.vy = -v * std::sin(off);
}

bool YawOffsetRule::applies(const TickSnapshot& s) const {
  return p_.clear_yaw_offset > 0.0 && s.origin_set && std::isfinite(s.in.yaw) && s.state == FsmState::kFlyForward &&
         s.after_clear;
}

void YawOffsetRule::apply(TickSnapshot& snap) {
  // track_yaw_ is the heading the drone flies without the rule: it starts at
  // the yaw on entering the FLY_FORWARD after the clearing and realigns to the
  // course as the realignment does (omega_max at most). The body is held
  // clear_yaw_offset beyond it away from the side-step side; the body-frame
  // velocity of the setpoint, meant for that heading, is rotated into the
  // body's frame, so the track stays the same.
  const WallFollowerInput& in = snap.in;
  const double sign = snap.side == Side::kLeft ? -1.0 : 1.0;  // away from the side-step (yaw > 0 is left)
  if (!std::isfinite(track_yaw_)) track_yaw_ = in.yaw;
  const double track_rate =
      std::clamp(p_.realign_gain * std::remainder(snap.course_yaw - track_yaw_, 2.0 * M_PI), -p_.omega_max,
                 p_.omega_max);
  track_yaw_ = std::remainder(track_yaw_ + track_rate * snap.dt, 2.0 * M_PI);
  // A whisker's sum moving: a touch TDORC has not flagged yet; back to the
  // track's heading (latched until the next clearing), so that the wall
  // following starts as without the offset.
  if (sum_moves(in, p_.clear_yaw_release_rms)) released_ = true;
  const double ref = track_yaw_ + (released_ ? 0.0 : sign * p_.clear_yaw_offset);
  const Setpoint s = snap.setpoint;
  Setpoint& o = snap.setpoint;
  o.yaw_rate = std::clamp(track_rate + tracking_gain(p_) * std::remainder(ref - in.yaw, 2.0 * M_PI), -p_.omega_max,
                          p_.omega_max);
  const double rel = std::remainder(track_yaw_ - in.yaw, 2.0 * M_PI);
  o.vx = std::cos(rel) * s.vx - std::sin(rel) * s.vy;
  o.vy = std::sin(rel) * s.vx + std::cos(rel) * s.vy;
}

template <typename Rule>
void WhiskerWallFollower::run_rule(Rule& rule, OverrideRule id, TickSnapshot& s, bool top_transition) {
  const auto k = static_cast<std::size_t>(id);
  rule.observe(s);
  if (!rule.applies(s)) {
    rule.idle();
    override_active_[k] = false;
    return;
  }
  rule.apply(s);
  ++override_count_[k];
  if (!override_active_[k]) {
    override_active_[k] = true;
    override_started_ = true;
    note_rule(Rule::kReason, reason_of(id), top_transition);
  }
}

void WhiskerWallFollower::note_rule(const char* rule_reason, WhiskerReason code, bool top_transition) {
  if (!top_transition) {
    reason_ = rule_reason;
    reason_code_ = code_of(code);
    reason_composed_ = false;
    return;
  }
  // A rule that begins on a transition's tick: both, the transition first
  // (a second rule beginning on that tick appends to the first's); the code
  // stays the transition's.
  // Truncated at the buffer's size (the reasons are short static texts).
  std::array<char, 192> text{};
  std::size_t n = 0;
  const auto append = [&](const char* part) {
    for (; *part != '\0' && n + 1 < text.size(); ++part) text[n++] = *part;
  };
  append(reason());
  append("; ");
  append(rule_reason);
  text[n] = '\0';
  reason_buf_ = text;
  reason_composed_ = true;
}


double WhiskerWallFollower::realign(const WallFollowerInput& in) const {
  // Back to the course heading after a (tilted) obstacle; saturate() limits it to omega_max.
  if (!origin_set_ || !std::isfinite(in.yaw)) return 0.0;
  return realign_rate(in.yaw);
}

double WhiskerWallFollower::realign_rate(double yaw) const {
  return p_.realign_gain * std::remainder(course_yaw_ - yaw, 2.0 * M_PI);
}

}  // namespace tactile_fsm
