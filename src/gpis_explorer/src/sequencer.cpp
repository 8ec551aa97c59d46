// Exploration sequencing (000 Methods, Extended Data Fig. 1d). See sequencer.hpp.
#include "gpis_explorer/sequencer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace gpis_explorer {
namespace {

[[noreturn]] void fail(const char* field, const std::string& reason) {
  throw std::invalid_argument(std::string("SequencerParams.") + field + ": " + reason);
}
void positive(const char* field, double v) {
  if (!(std::isfinite(v) && v > 0.0)) fail(field, "must be > 0, got " + std::to_string(v));
}
double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

/// The tick's touched points, left then right: each whisker in contact whose
/// contact point is known (the one contact collection of every phase).
template <class F>
void each_touched_point(const SequencerInput& in, F&& f) {
  if (in.contact_left && in.point_left.allFinite()) f(in.point_left);
  if (in.contact_right && in.point_right.allFinite()) f(in.point_right);
}

constexpr std::size_t kMaxContacts = 200000;     ///< bound on the stored contact history
constexpr std::size_t kMaxTrajectory = 200000;

}  // namespace

const char* to_string(Phase p) {
  switch (p) {
    case Phase::kHoverInit: return "HOVER_INIT";
    case Phase::kTurn: return "TURN";
    case Phase::kProbe: return "PROBE";
    case Phase::kReturn: return "RETURN";
    case Phase::kFollowWall: return "FOLLOW_WALL";
    case Phase::kRetreat: return "RETREAT";
    case Phase::kGoToStaging: return "GO_TO_STAGING";
    case Phase::kGoToTarget: return "GO_TO_TARGET";
    case Phase::kExitThrough: return "EXIT_THROUGH";
    case Phase::kCheckAhead: return "CHECK_AHEAD";
    case Phase::kRefit: return "REFIT";
    case Phase::kFailsafeHover: return "FAILSAFE_HOVER";
    case Phase::kLanding: return "LANDING";
    case Phase::kDone: return "DONE";
  }
  return "UNKNOWN";
}

const char* to_string(Round r) {
  switch (r) {
    case Round::kProbes: return "probes";
    case Round::kTargets: return "targets";
  }
  return "unknown";
}

const char* to_string(ProbeSet s) {
  switch (s) {
    case ProbeSet::kOrthogonal: return "orthogonal";
    case ProbeSet::kDiagonal: return "diagonal";
  }
  return "unknown";
}

const char* to_string(CheckStage s) {
  switch (s) {
    case CheckStage::kWhiskBack: return "whisk_back";
    case CheckStage::kDwell: return "dwell";
  }
  return "unknown";
}

const char* to_string(ReturnLeg l) {
  switch (l) {
    case ReturnLeg::kToProbeLine: return "to_probe_line";
    case ReturnLeg::kAlongProbeLine: return "along_probe_line";
  }
  return "unknown";
}

const char* to_string(ReturnFor r) {
  switch (r) {
    case ReturnFor::kNextProbe: return "next_probe";
    case ReturnFor::kOpenProbeExit: return "open_probe_exit";
  }
  return "unknown";
}

const char* to_string(RetreatKind k) {
  switch (k) {
    case RetreatKind::kAfterFollow: return "after_follow";
    case RetreatKind::kBackOff: return "back_off";
  }
  return "unknown";
}

const char* to_string(ExitKind k) {
  switch (k) {
    case ExitKind::kAlongOpenProbe: return "along_open_probe";
    case ExitKind::kBeyondTarget: return "beyond_target";
  }
  return "unknown";
}

const char* to_string(SequencerReason r) {
  switch (r) {
    case SequencerReason::kNone: return "none";
    case SequencerReason::kFailsafeDepthStale: return "failsafe_depth_stale";
    case SequencerReason::kFailsafeOdometryStale: return "failsafe_odometry_stale";
    case SequencerReason::kFailsafeInputsFresh: return "failsafe_inputs_fresh";
    case SequencerReason::kFailsafeStaleTooLong: return "failsafe_stale_too_long";
    case SequencerReason::kHoverDone: return "hover_done";
    case SequencerReason::kAligned: return "aligned";
    case SequencerReason::kProbeFoundNoWall: return "probe_found_no_wall";
    case SequencerReason::kWhiskContact: return "whisk_contact";
    case SequencerReason::kContact: return "contact";
    case SequencerReason::kBesideCorridor: return "beside_corridor";
    case SequencerReason::kTooNearTheGuard: return "too_near_the_guard";
    case SequencerReason::kCornerAhead: return "corner_ahead";
    case SequencerReason::kWallFollowed: return "wall_followed";
    case SequencerReason::kSurfaceBeside: return "surface_beside";
    case SequencerReason::kRetreatedNextProbe: return "retreated_next_probe";
    case SequencerReason::kNextProbe: return "next_probe";
    case SequencerReason::kProbesDone: return "probes_done";
    case SequencerReason::kRetreatedRefit: return "retreated_refit";
    case SequencerReason::kOpenProbeReturn: return "open_probe_return";
    case SequencerReason::kOpenProbeExit: return "open_probe_exit";
    case SequencerReason::kTargetViaStaging: return "target_via_staging";
    case SequencerReason::kTargetChosen: return "target_chosen";
    case SequencerReason::kAtStaging: return "at_staging";
    case SequencerReason::kTargetReached: return "target_reached";
    case SequencerReason::kUpdateLimit: return "update_limit";
    case SequencerReason::kNoTarget: return "no_target";
    case SequencerReason::kOpenSpace: return "open_space";
    case SequencerReason::kExitFlownThrough: return "exit_flown_through";
    case SequencerReason::kTimeLimit: return "time_limit";
    case SequencerReason::kLanded: return "landed";
  }
  return "unknown";
}

const char* reason_text(SequencerReason r, Phase from) {
  switch (r) {
    case SequencerReason::kNone: return "start";
    case SequencerReason::kFailsafeDepthStale:
      return from == Phase::kHoverInit ? "tactile depth stale at end of hover" : "tactile depth stale";
    case SequencerReason::kFailsafeOdometryStale:
      return from == Phase::kHoverInit ? "odometry stale at end of hover" : "odometry stale";
    case SequencerReason::kFailsafeInputsFresh: return "inputs fresh again";
    case SequencerReason::kFailsafeStaleTooLong: return "inputs stale for failsafe_land_after_s";
    case SequencerReason::kHoverDone: return "hover done: first probe";
    case SequencerReason::kAligned: return "aligned";
    case SequencerReason::kProbeFoundNoWall: return "probe found no wall";
    case SequencerReason::kWhiskContact: return "whisk contact";
    case SequencerReason::kContact: return "contact";
    case SequencerReason::kBesideCorridor: return "whisk contact beside the corridor: leg goes on";
    case SequencerReason::kTooNearTheGuard: return "touched too near the guard: back off";
    case SequencerReason::kCornerAhead: return "approaching a penalised corner";
    case SequencerReason::kWallFollowed: return "wall followed";
    case SequencerReason::kSurfaceBeside: return "known surface beside: end of wall follow";
    case SequencerReason::kRetreatedNextProbe: return "retreated: next probe";
    case SequencerReason::kNextProbe: return "next probe";
    case SequencerReason::kProbesDone: return "probes done";
    case SequencerReason::kRetreatedRefit: return "retreated: refit";
    case SequencerReason::kOpenProbeReturn: return "a probe found the opening: back to the start";
    case SequencerReason::kOpenProbeExit: return "a probe found the opening";
    case SequencerReason::kTargetViaStaging: return "target chosen: to its staging point";
    case SequencerReason::kTargetChosen: return "target chosen";
    case SequencerReason::kAtStaging: return "at the staging point: face the wall";
    case SequencerReason::kTargetReached: return "target reached without contact";
    case SequencerReason::kUpdateLimit: return "GPIS update limit";
    case SequencerReason::kNoTarget: return "no reachable target";
    case SequencerReason::kOpenSpace: return "no contact in any probe direction";
    case SequencerReason::kExitFlownThrough: return "flew through the opening";
    case SequencerReason::kTimeLimit: return "time limit";
    case SequencerReason::kLanded: return "landed";
  }
  return "unknown";
}

const char* to_string(CheckDecision d) {
  switch (d) {
    case CheckDecision::kFollowUnknown: return "follow_unknown";
    case CheckDecision::kLegGoesOn: return "leg_goes_on";
    case CheckDecision::kFollowWall: return "follow_wall";
    case CheckDecision::kBackOff: return "back_off";
  }
  return "unknown";
}

CheckDecision check_ahead_decision(const std::vector<Eigen::Vector2d>& touched, const Eigen::Vector2d& pos,
                                   double heading, const PathRules& rules, double follow_min_forward) {
  if (touched.empty()) return CheckDecision::kFollowUnknown;
  const Eigen::Vector2d h(std::cos(heading), std::sin(heading));
  double nearest = std::numeric_limits<double>::infinity();
  for (const auto& q : touched) {
    if (rules.in_corridor(q, pos, heading)) nearest = std::min(nearest, (q - pos).dot(h));
  }
  if (!std::isfinite(nearest)) return CheckDecision::kLegGoesOn;
  return nearest >= follow_min_forward ? CheckDecision::kFollowWall : CheckDecision::kBackOff;
}

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::kRunning: return "running";
    case Outcome::kExitFound: return "exit_found";
    case Outcome::kOpenSpace: return "open_space";
    case Outcome::kNoTarget: return "no_target";
    case Outcome::kUpdateLimit: return "update_limit";
    case Outcome::kTimeLimit: return "time_limit";
    case Outcome::kInputsStale: return "inputs_stale";
  }
  return "unknown";
}

void SequencerParams::validate() const {
  explorer.validate();
  wall.validate();
  if (probe_directions < 1 || probe_directions > 16) {
    fail("probe_directions", "must be in [1, 16], got " + std::to_string(probe_directions));
  }
  positive("follow_time_s", follow_time_s);
  positive("retreat_time_s", retreat_time_s);
  if (surface_points_per_follow < 1) fail("surface_points_per_follow", "must be >= 1");
  if (interior_points_per_retreat < 0 || interior_points_per_retreat > 1) {
    fail("interior_points_per_retreat", "must be 0 or 1 (the retreat's end point)");
  }
  positive("retreat_speed", retreat_speed);
  positive("probe_max_distance", probe_max_distance);
  positive("yaw_gain", yaw_gain);
  positive("yaw_tolerance", yaw_tolerance);
  positive("target_radius", target_radius);
  positive("exit_confirm_distance", exit_confirm_distance);
  if (!(std::isfinite(exit_beyond) && exit_beyond >= 0.0)) fail("exit_beyond", "must be >= 0");
  if (!(std::isfinite(min_target_distance) && min_target_distance >= 0.0)) fail("min_target_distance", "must be >= 0");
  if (!(std::isfinite(side_clearance) && side_clearance >= 0.0)) fail("side_clearance", "must be >= 0");
  if (!(std::isfinite(wall_extension) && wall_extension >= 0.0)) fail("wall_extension", "must be >= 0");
  if (!(std::isfinite(corner_confirm_radius) && corner_confirm_radius >= 0.0)) {
    fail("corner_confirm_radius", "must be >= 0");
  }
  if (!(std::isfinite(approach_standoff) && approach_standoff >= 0.0)) fail("approach_standoff", "must be >= 0");
  if (!(std::isfinite(path_clearance) && path_clearance >= 0.0)) fail("path_clearance", "must be >= 0");
  if (!(std::isfinite(approach_clearance) && approach_clearance >= 0.0)) fail("approach_clearance", "must be >= 0");
  if (!(std::isfinite(slow_distance) && slow_distance >= 0.0)) fail("slow_distance", "must be >= 0");
  if (!(std::isfinite(slow_fraction) && slow_fraction > 0.0 && slow_fraction <= 1.0)) {
    fail("slow_fraction", "must be in (0, 1], got " + std::to_string(slow_fraction));
  }
  if (max_updates < 1) fail("max_updates", "must be >= 1");
  if (!(std::isfinite(line_gain) && line_gain >= 0.0)) fail("line_gain", "must be >= 0");
  if (!(std::isfinite(visited_radius) && visited_radius >= 0.0)) fail("visited_radius", "must be >= 0");
  if (!(std::isfinite(whisk_amplitude) && whisk_amplitude >= 0.0 && whisk_amplitude < 0.5 * M_PI)) {
    fail("whisk_amplitude", "must be in [0, pi/2), got " + std::to_string(whisk_amplitude));
  }
  positive("whisk_rate", whisk_rate);
  if (!(std::isfinite(turn_rate) && turn_rate >= 0.0 && turn_rate <= whisk_rate)) {
    fail("turn_rate", "must be in [0, whisk_rate], got " + std::to_string(turn_rate));
  }
  positive("whisk_speed", whisk_speed);
  positive("check_dwell_s", check_dwell_s);
  positive("corridor_half_width", corridor_half_width);
  if (!(std::isfinite(retreat_clearance) && retreat_clearance >= 0.0)) fail("retreat_clearance", "must be >= 0");
  if (!(std::isfinite(check_sample_s) && check_sample_s >= 0.0)) fail("check_sample_s", "must be >= 0");
  if (!(std::isfinite(follow_min_forward) && follow_min_forward >= 0.0)) fail("follow_min_forward", "must be >= 0");
  positive("max_time_s", max_time_s);
  positive("landing_duration_s", landing_duration_s);
}

namespace {
tactile_fsm::SafetyParams safety_params(const tactile_fsm::WallFollowerParams& w) {
  tactile_fsm::SafetyParams s;
  s.max_input_age_s = w.max_input_age_s;
  s.failsafe_land_after_s = w.failsafe_land_after_s;
  return s;  // no time limit: max_time_s is the sequencer's own (an outcome, see step())
}
}  // namespace

ExplorationSequencer::ExplorationSequencer(const SequencerParams& params)
    : p_(params),
      explorer_((params.validate(), params.explorer)),
      safety_(safety_params(params.wall), {tactile_fsm::SafetyInput::kDepth, tactile_fsm::SafetyInput::kOdometry}) {}

std::string ExplorationSequencer::sub_state() const {
  switch (phase_) {
    case Phase::kCheckAhead: return to_string(check_stage_);
    case Phase::kReturn: return to_string(return_leg_);
    case Phase::kRetreat: return to_string(retreat_kind_);
    case Phase::kExitThrough: return to_string(exit_kind_);
    case Phase::kFollowWall: return tactile_fsm::to_string(wall_.sub_state());
    case Phase::kTurn: return to_string(after_turn_);
    default: return "";
  }
}

void ExplorationSequencer::enter(Phase p, SequencerReason why, double t) {
  if (p == Phase::kRetreat) {
    retreat_held_ = false;
    retreat_kind_ = phase_ == Phase::kFollowWall ? RetreatKind::kAfterFollow : RetreatKind::kBackOff;
  }
  previous_ = phase_;
  phase_ = p;
  reason_code_ = why;
  entered_ = t;
  ++transitions_;
}

bool ExplorationSequencer::apply_safety(const SequencerInput& in, SequencerOutput* out) {
  // HOVER_INIT only hovers: guarded from its end, as the wall follower's.
  const bool guarded = phase_ != Phase::kHoverInit || in.t - entered_ >= p_.wall.hover_init_s;
  const double stale = std::numeric_limits<double>::quiet_NaN();
  const tactile_fsm::SafetyVerdict v =
      safety_.step(in.t, {in.depth_valid ? in.t : stale, in.pose_valid ? in.t : stale}, guarded);
  const auto why = static_cast<SequencerReason>(v.reason);  // same values (static_asserts in the node logic)
  switch (v.state) {
    case tactile_fsm::SafetyState::kFailsafeHover:
      if (v.entered) {
        failsafe_from_ = phase_;
        failsafe_from_entered_ = entered_;
        enter(Phase::kFailsafeHover, why, in.t);
      } else {
        hold_tick(in);
      }
      return true;
    case tactile_fsm::SafetyState::kFailsafeLand:
    case tactile_fsm::SafetyState::kTimeLimitLand:  // not reached: no time limit (safety_params)
      hold_tick(in);
      finish(Outcome::kInputsStale, why, in.t);
      out->setpoint.height = 0.0;  // landing from this tick (as the wall follower's FAILSAFE_LAND)
      out->setpoint.land = true;
      return true;
    case tactile_fsm::SafetyState::kNominal:
      break;
  }
  if (v.resumed) {
    // Back to the interrupted phase as it was, its clocks moved on by the time
    // held: a 2 s wall follow still follows for 2 s of fresh input, a check
    // dwells its full time. Not enter(): the phase is resumed, not re-entered.
    // Moved while held (drift under a zero-velocity setpoint): not a
    // contact-free part of the leg.
    if (have_last_pose_) leg_blind_ += (Eigen::Vector2d(in.x, in.y) - last_pose_).norm();
    const double held = in.t - entered_;
    previous_ = phase_;
    phase_ = failsafe_from_;
    reason_code_ = why;
    entered_ = failsafe_from_entered_ + held;
    check_t_ += held;
    check_started_ += held;
    ++transitions_;
  }
  return false;
}

void ExplorationSequencer::hold_tick(const SequencerInput& in) {
  if (!in.pose_valid) return;
  const Eigen::Vector2d held_at(in.x, in.y);
  if (have_last_pose_) {
    travel_ += (held_at - last_pose_).norm();
    leg_blind_ += (held_at - last_pose_).norm();
  }
  last_pose_ = held_at;
  have_last_pose_ = true;
}

void ExplorationSequencer::finish(Outcome o, SequencerReason why, double t) {
  outcome_ = o;
  enter(Phase::kLanding, why, t);
}

// --- Named guards (each phase's end; public, tested one by one) ---------------

bool ExplorationSequencer::hover_done(double t) const { return t - entered_ >= p_.wall.hover_init_s; }

bool ExplorationSequencer::aligned(double yaw) const { return std::abs(wrap(heading_ - yaw)) < p_.yaw_tolerance; }

bool ExplorationSequencer::probe_found_no_wall(const Eigen::Vector2d& pos) const {
  // Only what was flown with fresh depth counts (not the drift while held).
  return (pos - leg_start_).norm() - leg_blind_ >= p_.probe_max_distance;
}

bool ExplorationSequencer::back_at_return_point(const Eigen::Vector2d& pos) const {
  // Tighter than target_radius: the next leg starts here.
  return return_leg_ == ReturnLeg::kAlongProbeLine && (return_to_ - pos).norm() < 0.5 * p_.target_radius;
}

bool ExplorationSequencer::wall_followed(double t) const { return t - entered_ >= p_.follow_time_s; }

bool ExplorationSequencer::surface_beside(const Eigen::Vector2d& pos, double yaw) const {
  return wall_.sub_state() == tactile_fsm::WallSubState::kFlySideways && rules().side_blocked(pos, yaw, wall_.side());
}

bool ExplorationSequencer::retreated(double t) const { return t - entered_ >= p_.retreat_time_s; }

bool ExplorationSequencer::reached_or_passed(const Eigen::Vector2d& point, const Eigen::Vector2d& pos) const {
  const Eigen::Vector2d dir(std::cos(heading_), std::sin(heading_));
  return (point - pos).norm() < p_.target_radius || (point - pos).dot(dir) < 0.0;
}

bool ExplorationSequencer::exit_confirmed(const Eigen::Vector2d& pos) const {
  // exit_distance_ contact-free (fresh depth) past exit_from_, and beyond every
  // known surface along the heading, or probe_max_distance further still.
  const double flown = (pos - exit_from_).norm() - leg_blind_;
  return flown >= exit_distance_ &&
         (rules().beyond_known_surface(pos, heading_) || flown >= exit_distance_ + p_.probe_max_distance);
}

void ExplorationSequencer::for_test_enter(Phase p, const SequencerInput& in, const TestEntry& e) {
  if (p == Phase::kRefit || p == Phase::kFailsafeHover || p == Phase::kCheckAhead) {
    throw std::invalid_argument(std::string("ExplorationSequencer::for_test_enter: ") + to_string(p) +
                                (p == Phase::kFailsafeHover ? " is the SafetyRunner's, entered by a stale input"
                                                            : " is entered by its guards only"));
  }
  const Eigen::Vector2d pos(in.x, in.y);
  if (!started_) {
    started_ = true;
    start_ = pos;
    start_yaw_ = in.yaw;
    explorer_.centre_grid(pos.x(), pos.y());
  }
  safety_.reset();  // a nominal phase: the fail-safe's state with it
  round_ = e.round;
  heading_ = std::isfinite(e.heading) ? e.heading : in.yaw;
  leg_start_ = line_origin_ = exit_from_ = pos;
  leg_blind_ = 0.0;
  if (e.target) {
    has_target_ = true;
    target_ = *e.target;
  }
  last_pose_ = pos;
  have_last_pose_ = true;
  switch (p) {
    case Phase::kFollowWall:
      start_follow(in);  // its entry action: the side from the contact, as on a leg
      return;
    case Phase::kReturn:
      begin_return(pos, e.return_to ? *e.return_to : start_, ReturnFor::kNextProbe, SequencerReason::kNone, in.t);
      return;
    case Phase::kTurn:
      after_turn_ = e.after_turn;
      break;
    case Phase::kGoToStaging:
      has_staging_ = true;
      staging_ = e.target ? *e.target : pos;
      break;
    case Phase::kExitThrough:
      exit_distance_ = p_.exit_confirm_distance;
      exit_kind_ = ExitKind::kBeyondTarget;
      break;
    default:
      break;
  }
  enter(p, SequencerReason::kNone, in.t);
}

tactile_fsm::Setpoint ExplorationSequencer::hover() const {
  tactile_fsm::Setpoint s;
  s.height = p_.wall.flight_height;
  return s;
}

double ExplorationSequencer::yaw_rate_to(double heading, double yaw) const {
  return std::clamp(p_.yaw_gain * wrap(heading - yaw), -p_.wall.omega_max, p_.wall.omega_max);
}

double ExplorationSequencer::fast_yaw_rate(double err, double limit) {
  whisking_ = true;  // may exceed omega_max: the tick's rate is bounded by whisk_rate instead
  return std::clamp(p_.yaw_gain * 4.0 * err, -limit, limit);
}

ExplorationSequencer::Leg ExplorationSequencer::leg() const {
  Leg l;
  l.whisk = whisk_leg();
  l.corner_abort = phase_ == Phase::kGoToStaging || phase_ == Phase::kGoToTarget;
  return l;
}

bool ExplorationSequencer::fly_leg(const SequencerInput& in, bool contact, tactile_fsm::Setpoint* sp) {
  // Forward along heading_ on its line (000 Methods "Flying Forward" at V_max;
  // whisked at whisk_speed); a contact ends every leg the same way: unwhisked
  // a wall follow, whisked a stop to check (a whisk beside the corridor lets
  // the leg go on); on the GPIS legs a penalised corner 0.1 m ahead a retreat
  // (000: never fly into a corner).
  const Leg l = leg();
  whisking_ = leg_motion(in, l.whisk ? p_.whisk_speed : forward_speed(in), l.whisk, sp);
  if (contact) {
    if (!whisking_) {
      start_follow(in);
      return true;
    }
    if (whisk_blocked(in)) {
      start_check(in);
      return true;
    }
  }
  const Eigen::Vector2d pos(in.x, in.y);
  if (l.corner_abort && rules().near_corner(pos + Eigen::Vector2d(std::cos(in.yaw), std::sin(in.yaw)) * 0.1)) {
    ++corner_aborts_;
    follow_points_.clear();
    enter(Phase::kRetreat, SequencerReason::kCornerAhead, in.t);
    return true;
  }
  return false;
}

LineFit fit_line(const std::vector<Eigen::Vector2d>& pts) {
  LineFit f;
  const std::size_t n = pts.size();
  if (n < 2) return f;
  for (const auto& q : pts) f.mean += q;
  f.mean /= static_cast<double>(n);
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - f.mean) * (q - f.mean).transpose();
  C /= static_cast<double>(n);
  const double tr = C.trace(), det = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
  const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  const double l1 = 0.5 * tr + disc, l2 = std::max(0.0, 0.5 * tr - disc);
  f.spread = 2.0 * std::sqrt(l1);
  f.thickness = 2.0 * std::sqrt(l2);
  f.dir = std::abs(C(0, 1)) > 1e-12 ? Eigen::Vector2d(l1 - C(1, 1), C(0, 1))
                                    : (C(0, 0) >= C(1, 1) ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1));
  f.dir.normalize();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& q : pts) {
    lo = std::min(lo, (q - f.mean).dot(f.dir));
    hi = std::max(hi, (q - f.mean).dot(f.dir));
  }
  f.a = f.mean + lo * f.dir;
  f.b = f.mean + hi * f.dir;
  f.ok = true;
  return f;
}

double ray_to_wall_line(const Eigen::Vector2d& from, const Eigen::Vector2d& dir, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b, double extension) {
  const double miss = std::numeric_limits<double>::infinity();
  if ((b - a).norm() < 1e-9) return miss;
  const Eigen::Vector2d u = (b - a).normalized();
  if (std::abs(dir.dot(u)) > std::sqrt(0.5)) return miss;  // < 45 deg to the ray: beside it, not across
  const Eigen::Vector2d a0 = a - extension * u;
  const Eigen::Vector2d e = (b + extension * u) - a0;
  const double den = dir.x() * e.y() - dir.y() * e.x();
  const Eigen::Vector2d ap = a0 - from;
  const double r = (ap.x() * e.y() - ap.y() * e.x()) / den;    // along the ray
  const double v = (ap.x() * dir.y() - ap.y() * dir.x()) / den;  // along the extended span, 0..1
  return (r > 0.0 && v >= 0.0 && v <= 1.0) ? r : miss;
}

void ExplorationSequencer::add_wall_line() {
  // One wall: the follow's contact points spread >= 5 cm along their line
  // (2 sigma; short follows beside an exit's jamb count) and <= 2 cm across
  // (not two walls of a corner).
  const LineFit f = fit_line(follow_points_);
  if (!f.ok || f.spread < 0.05 || f.thickness > 0.02) return;
  if (wall_lines_.size() >= 64) wall_lines_.erase(wall_lines_.begin());
  wall_lines_.push_back({f.a, f.b});
}

std::vector<Eigen::Vector2d> confirmed_corners(const Gpis& g, const std::vector<Eigen::Vector2d>& corners,
                                               double radius) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& c : corners) {
    if (surface_distance(g, c, c) <= radius) out.push_back(c);
  }
  return out;
}

std::size_t point_to_replace(const Gpis& g, const Eigen::Vector2d& q, double label) {
  double new_gap = std::numeric_limits<double>::infinity();
  double pair_gap = std::numeric_limits<double>::infinity();
  std::size_t victim = g.size();
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.label(i) == label) new_gap = std::min(new_gap, (g.point(i) - q).squaredNorm());
    for (std::size_t j = i + 1; j < g.size(); ++j) {
      if (g.label(i) != g.label(j)) continue;
      const double d = (g.point(i) - g.point(j)).squaredNorm();
      if (d < pair_gap) {
        pair_gap = d;
        victim = i;  // the older of the pair
      }
    }
  }
  return new_gap <= pair_gap ? g.size() : victim;
}

void ExplorationSequencer::add(const Eigen::Vector2d& q, double label) {
  const AddStatus st = explorer_.add_point(q, label);
  if (st == AddStatus::kAdded) return;
  if (st != AddStatus::kBudgetFull || !p_.replace_when_full) {
    ++points_rejected_;
    return;
  }
  const std::size_t victim = point_to_replace(explorer_.gpis(), q, label);
  if (victim >= explorer_.gpis().size()) {
    ++points_rejected_;
    return;
  }
  explorer_.remove(victim);
  ++points_replaced_;
  if (explorer_.add_point(q, label) != AddStatus::kAdded) ++points_rejected_;
}

double ExplorationSequencer::line_correction(const SequencerInput& in) const {
  // Lateral (body y) velocity back onto the leg's line: a probe's line is
  // known free of walls, a head-on leg is the one checked for clearance.
  const Eigen::Vector2d nrm(-std::sin(heading_), std::cos(heading_));
  const double e = (Eigen::Vector2d(in.x, in.y) - line_origin_).dot(nrm);
  const double lim = 0.5 * p_.wall.v_max;
  return std::clamp(-p_.line_gain * e, -lim, lim);
}

double ExplorationSequencer::retreat_lateral(const SequencerInput& in) const {
  // Body-y speed back toward where the wall follow began (retreat_toward_follow_start).
  if (!p_.retreat_toward_follow_start || retreat_kind_ != RetreatKind::kAfterFollow) return 0.0;
  const double off = (Eigen::Vector2d(in.x, in.y) - follow_start_).dot(Eigen::Vector2d(-std::sin(in.yaw), std::cos(in.yaw)));
  return std::clamp(-off / p_.retreat_time_s, -p_.retreat_speed, p_.retreat_speed);
}

bool ExplorationSequencer::whisk_leg() const {
  if (!(p_.whisk_amplitude > 0.0)) return false;
  switch (phase_) {
    case Phase::kProbe:
    case Phase::kGoToStaging:
    case Phase::kGoToTarget: return true;
    case Phase::kExitThrough: return exit_kind_ == ExitKind::kBeyondTarget;
    default: return false;
  }
}

bool ExplorationSequencer::whisk_blocked(const SequencerInput& in) {
  // A whisk contact blocks the leg when a touched point lies in the guard's
  // corridor ahead (or its position is unknown); a point beside the corridor
  // (a wall end or a wall along the leg, touched by a whisker yawed toward it)
  // leaves the leg free: the leg goes on and the first such point of the leg
  // becomes a surface point.
  const Eigen::Vector2d pos(in.x, in.y);
  bool blocked = false, beside = false;
  Eigen::Vector2d q_beside{0, 0};
  auto look = [&](bool c, const Eigen::Vector2d& q) {
    if (!c) return;
    if (!q.allFinite() || rules().in_corridor(q, pos, heading_)) {
      blocked = true;
    } else {
      beside = true;
      q_beside = q;
    }
  };
  look(in.contact_left, in.point_left);
  look(in.contact_right, in.point_right);
  if (!blocked && beside) {
    if (!beside_added_) add(q_beside, kSurfaceLabel);
    beside_added_ = true;
    ++beside_contacts_;
  }
  return blocked;
}

void ExplorationSequencer::start_check(const SequencerInput& in) {
  check_from_ = phase_;
  check_stage_ = CheckStage::kWhiskBack;
  check_t_ = in.t;
  check_started_ = in.t;
  check_points_.clear();
  each_touched_point(in, [&](const Eigen::Vector2d& q) { check_points_.push_back(q); });
  ++whisk_contacts_;
  enter(Phase::kCheckAhead, SequencerReason::kWhiskContact, in.t);
}

void ExplorationSequencer::check_ahead(const SequencerInput& in, tactile_fsm::Setpoint* sp) {
  // Stop; whisk back to the leg's heading; dwell; then decide from where the
  // whisk touched (the points of the first check_sample_s after the contact,
  // while the whisker still points where it touched; later ones re-project a
  // held depth along the turning axis): the nearest touched point in the
  // corridor at least follow_min_forward ahead -> a wall far enough to be
  // followed (wall follow, as on an unwhisked leg; a wall end beside the axis
  // is then passed outside the guard); nearer -> back off along the leg (its
  // corridor was whisked), the touched points become surface points and the
  // GPIS is refitted (a wall end near an opening: the opening beside it stays
  // open; 000: the exit "emerges").
  const Eigen::Vector2d pos(in.x, in.y);
  if (in.depth_valid && in.t - check_started_ <= p_.check_sample_s && check_points_.size() < 64) {
    each_touched_point(in, [&](const Eigen::Vector2d& q) { check_points_.push_back(q); });
  }
  const double err = wrap(heading_ - in.yaw);
  if (check_stage_ == CheckStage::kWhiskBack) {
    sp->yaw_rate = fast_yaw_rate(err, p_.whisk_rate);  // the whisk back
    if (std::abs(err) < p_.yaw_tolerance) {
      check_stage_ = CheckStage::kDwell;
      check_t_ = in.t;
    }
    return;
  }
  sp->yaw_rate = yaw_rate_to(heading_, in.yaw);
  if (in.t - check_t_ < p_.check_dwell_s) return;
  switch (check_ahead_decision(check_points_, pos, heading_, rules(), p_.follow_min_forward)) {
    case CheckDecision::kFollowUnknown:  // contact without a position estimate: as an unwhisked leg
    case CheckDecision::kFollowWall:
      ++whisk_walls_;
      start_follow(in);
      return;
    case CheckDecision::kLegGoesOn:
      enter(check_from_, SequencerReason::kBesideCorridor, in.t);
      return;
    case CheckDecision::kBackOff:
      break;
  }
  ++whisk_jambs_;
  if (round_ == Round::kTargets && has_target_ && visited_.size() < 1000) visited_.push_back(target_);
  follow_points_ = check_points_;
  wall_.begin(wall_.side());  // no wall followed: align_to_wall() finds no both-touched heading
  enter(Phase::kRetreat, SequencerReason::kTooNearTheGuard, in.t);
}

bool ExplorationSequencer::leg_motion(const SequencerInput& in, double speed, bool whisk, tactile_fsm::Setpoint* sp) {
  const double c = line_correction(in);
  if (!whisk || p_.whisk_amplitude <= 0.0) {
    sp->vx = speed;
    sp->vy = c;
    sp->yaw_rate = yaw_rate_to(heading_, in.yaw);
    return false;
  }
  // Triangle-wave yaw about the leg's heading (bang-bang on the measured yaw).
  const double d = wrap(in.yaw - heading_);
  if (d > p_.whisk_amplitude) whisk_dir_ = -1;
  else if (d < -p_.whisk_amplitude) whisk_dir_ = 1;
  sp->yaw_rate = whisk_dir_ * p_.whisk_rate;
  // The motion stays on the leg's line whatever the yaw: world velocity
  // speed * heading + c * normal, expressed in the body frame.
  sp->vx = speed * std::cos(d) + c * std::sin(d);
  sp->vy = -speed * std::sin(d) + c * std::cos(d);
  return true;
}

double ExplorationSequencer::forward_speed(const SequencerInput& in) const {
  const Eigen::Vector2d tips = Eigen::Vector2d(in.x, in.y) + 0.19 * Eigen::Vector2d(std::cos(in.yaw), std::sin(in.yaw));
  return rules().surface_clearance(tips, tips) < p_.slow_distance ? p_.slow_fraction * p_.wall.v_max : p_.wall.v_max;
}

void ExplorationSequencer::align_to_wall(const SequencerInput& in) {
  // The wall of the first contact: principal direction of the contact points
  // of its wall follow (>= 8 cm spread), else the heading the wall follow
  // settled to with both whiskers on the wall (it faces the wall's normal).
  double facing = NAN;
  const LineFit f = fit_line(follow_points_);
  if (f.ok && f.spread >= 0.08) {  // spread (2 sigma along the wall) >= 8 cm
    Eigen::Vector2d nrm(-f.dir.y(), f.dir.x());
    if (nrm.dot(f.mean - Eigen::Vector2d(in.x, in.y)) < 0.0) nrm = -nrm;
    facing = std::atan2(nrm.y(), nrm.x());
  }
  if (!std::isfinite(facing) && wall_.both_touched()) facing = in.yaw;
  if (!std::isfinite(facing)) return;
  start_yaw_ = facing - 2.0 * M_PI * probe_ / p_.probe_directions;
  aligned_ = true;
}

void ExplorationSequencer::begin_return(const Eigen::Vector2d& pos, const Eigen::Vector2d& to, ReturnFor what,
                                        SequencerReason why, double t) {
  // First across to the probe's line (leg_start_ along heading_), then along it.
  return_for_ = what;
  return_to_ = to;
  const Eigen::Vector2d h(std::cos(heading_), std::sin(heading_));
  return_via_ = leg_start_ + h * (pos - leg_start_).dot(h);
  return_leg_ = p_.return_via_probe_line && (pos - return_via_).norm() > kOnProbeLine ? ReturnLeg::kToProbeLine
                                                                                       : ReturnLeg::kAlongProbeLine;
  enter(Phase::kReturn, why, t);
}

void ExplorationSequencer::start_follow(const SequencerInput& in) {
  const bool probing = round_ == Round::kProbes;
  follow_points_.clear();
  tactile_fsm::Side side = p_.wall.follow_side;
  // Slide toward the side where the wall is nearer (the whisker that touched
  // first, or the smaller depth): along an oblique wall that is toward the
  // foot of the perpendicular from the drone, away from the nearer corner.
  // Workspace rule; 000 does not say which way the 2 s wall follow goes.
  if (in.contact_left != in.contact_right) {
    side = in.contact_left ? tactile_fsm::Side::kLeft : tactile_fsm::Side::kRight;
  } else if (in.contact_left && in.contact_right && std::abs(in.depth_left - in.depth_right) > 0.005) {
    side = in.depth_left < in.depth_right ? tactile_fsm::Side::kLeft : tactile_fsm::Side::kRight;
  }
  if (!probing && has_target_) {
    // Follow toward the target's side (as tactile_fsm's side_toward_target).
    const Eigen::Vector2d d = target_ - Eigen::Vector2d(in.x, in.y);
    const double lateral = -std::sin(in.yaw) * d.x() + std::cos(in.yaw) * d.y();  // body y (left)
    if (std::abs(lateral) > p_.wall.side_deadband) side = lateral > 0 ? tactile_fsm::Side::kLeft : tactile_fsm::Side::kRight;
  }
  wall_.begin(side);
  if (!probing && has_target_ && visited_.size() < 1000) visited_.push_back(target_);
  follow_start_ = Eigen::Vector2d(in.x, in.y);
  enter(Phase::kFollowWall, SequencerReason::kContact, in.t);
}

void ExplorationSequencer::commit_points(const SequencerInput& in) {
  // 4 surface points per wall follow, evenly spaced in time (000 downsampling).
  if (p_.wall_extension > 0.0) add_wall_line();
  const std::size_t n = follow_points_.size();
  const auto k = static_cast<std::size_t>(p_.surface_points_per_follow);
  if (n > 0) {
    for (std::size_t j = 0; j < std::min(k, n); ++j) {
      const std::size_t idx = (k >= n) ? j : (j * (n - 1)) / (k - 1 > 0 ? k - 1 : 1);
      add(follow_points_[std::min(idx, n - 1)], kSurfaceLabel);
    }
  }
  follow_points_.clear();
  // 1 interior point per retreat: where the drone is (000).
  if (p_.interior_points_per_retreat > 0) add({in.x, in.y}, kInteriorLabel);
}

bool ExplorationSequencer::choose_target(const Eigen::Vector2d& from) {
  const UpdateResult& r = explorer_.last();
  const PathRules rules = this->rules();
  has_target_ = false;
  has_staging_ = false;
  const GridSpec& g = explorer_.grid();
  // Candidates: contour points by penalised uncertainty a~ (000 eq. 46), best first.
  struct Candidate {
    double acq, var;
    Eigen::Vector2d q;
  };
  std::vector<Candidate> cands;
  for (const auto& info : r.contours) {
    const auto& P = info.contour.points;
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (!std::isfinite(info.acquisition[i])) continue;
      if ((P[i] - from).norm() < p_.min_target_distance) continue;
      if (!g.contains(P[i])) continue;
      if (rules.near_corner(P[i])) continue;  // never into a penalised corner
      bool visited = false;  // a target already touched (its points may not fit in the budget)
      for (const auto& v : visited_) visited = visited || (P[i] - v).norm() < p_.visited_radius;
      if (visited) continue;
      cands.push_back({info.acquisition[i], info.variance[i], P[i]});
    }
  }
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) { return x.acq > y.acq; });
  auto take = [&](const Candidate& c) {
    has_target_ = true;
    target_ = c.q;
    target_acq_ = c.acq;
    target_var_ = c.var;
  };
  // 1. The best target that can be approached head-on through a staging
  //    point with clear legs (workspace rule, see SequencerParams).
  if (p_.approach_standoff > 0.0) {
    for (const auto& c : cands) {
      if (rules.staging_for(from, c.q, &staging_, &approach_heading_)) {
        take(c);
        has_staging_ = true;
        ++staged_targets_;
        return true;
      }
    }
  }
  // 2. Otherwise the best target whose straight path keeps away from corners.
  for (const auto& c : cands) {
    if (!rules.corner_clear(from, c.q)) continue;
    take(c);
    ++direct_targets_;
    return true;
  }
  return false;
}

void ExplorationSequencer::update_map() {
  explorer_.update();  // GPIS fit is incremental; grid, contours, corners, acquisition (000 eq. 31-46)
  corners_ = explorer_.last().corners;
}

bool ExplorationSequencer::can_exit_via_open_probe() const {
  // A probe flew probe_max_distance without touching anything where other
  // probes met walls, and no target has been chosen yet: an opening.
  return open_probe_ >= 0 && explorer_.gpis().surface_count() > 0 && explorer_.updates() == 0;
}

bool ExplorationSequencer::can_land_in_open_space() const { return explorer_.gpis().surface_count() == 0; }

bool ExplorationSequencer::reached_update_limit() const {
  return static_cast<int>(explorer_.updates()) >= p_.max_updates;
}

void ExplorationSequencer::enter_refit(const SequencerInput& in, SequencerReason why, SequencerOutput* out) {
  enter(Phase::kRefit, why, in.t);
  // Entry action: the probes are over; update the GPIS, then the first
  // transition whose guard holds:
  //   open probe, walls elsewhere, first update -> RETURN to its origin, then out along it
  //   no surface point at all                   -> LANDING (open_space)
  //   max_updates reached                       -> LANDING (update_limit)
  //   a target with a staging point              -> TURN toward the staging point
  //   a target                                  -> TURN toward it (or its normal)
  //   none                                      -> LANDING (no_target)
  round_ = Round::kTargets;
  if (can_exit_via_open_probe()) {
    update_map();  // the map is not published: the exit is flown along the probe
    begin_return({in.x, in.y}, open_origin_, ReturnFor::kOpenProbeExit, SequencerReason::kOpenProbeReturn,
                 in.t);
    return;
  }
  out->gpis_updated = true;
  if (can_land_in_open_space()) {
    update_map();
    finish(Outcome::kOpenSpace, SequencerReason::kOpenSpace, in.t);
    return;
  }
  refit_and_choose(in);
}

void ExplorationSequencer::refit_and_choose(const SequencerInput& in) {
  update_map();
  if (reached_update_limit()) {
    finish(Outcome::kUpdateLimit, SequencerReason::kUpdateLimit, in.t);
    return;
  }
  bool chosen = choose_target({in.x, in.y});
  if (!chosen && p_.corner_confirm_radius > 0.0) {
    // No target left: set aside the corners no touched point confirms (an
    // untouched gap the fit bends across) and choose again. The training
    // points are a budget (replaced when full), so a corner touched long ago
    // may have lost its points: it is then set aside too, for this choice.
    std::vector<Eigen::Vector2d> confirmed = confirmed_corners(explorer_.gpis(), corners_, p_.corner_confirm_radius);
    if (confirmed.size() < corners_.size()) {
      corners_ = std::move(confirmed);
      chosen = choose_target({in.x, in.y});
      if (chosen) ++unconfirmed_corner_targets_;
    }
  }
  if (!chosen) {
    finish(Outcome::kNoTarget, SequencerReason::kNoTarget, in.t);
    return;
  }
  if (has_staging_ && (staging_ - Eigen::Vector2d(in.x, in.y)).norm() > p_.target_radius) {
    heading_ = std::atan2(staging_.y() - in.y, staging_.x() - in.x);
    after_turn_ = Phase::kGoToStaging;
    enter(Phase::kTurn, SequencerReason::kTargetViaStaging, in.t);
    return;
  }
  heading_ = has_staging_ ? approach_heading_ : std::atan2(target_.y() - in.y, target_.x() - in.x);
  after_turn_ = Phase::kGoToTarget;
  enter(Phase::kTurn, SequencerReason::kTargetChosen, in.t);
}

SequencerOutput ExplorationSequencer::step(const SequencerInput& in) {
  SequencerOutput out;
  out.setpoint = hover();
  const Phase before = phase_;
  const uint32_t tr = transitions_;
  if (!started_) {
    started_ = true;
    entered_ = in.t;
  }
  if (phase_ == Phase::kDone) {
    out.setpoint.height = 0.0;
    out.setpoint.land = true;
    return out;
  }
  if (phase_ == Phase::kLanding) {
    out.setpoint.height = 0.0;
    out.setpoint.land = true;
    if (in.t - entered_ >= p_.landing_duration_s) enter(Phase::kDone, SequencerReason::kLanded, in.t);
    out.transitioned = transitions_ != tr;
    return out;
  }
  // The shared fail-safe: a phase that moves needs fresh depth and odometry.
  // With stale depth a leg would fly blind and a probe end as "no wall"
  // (issue 33); with stale odometry every leg, turn and distance is wrong.
  if (apply_safety(in, &out)) {
    out.transitioned = transitions_ != tr;
    return out;
  }
  if (!in.pose_valid) return out;  // HOVER_INIT without odometry: hover in place (counted by the node logic)
  const Eigen::Vector2d pos(in.x, in.y);
  if (have_last_pose_) travel_ += (pos - last_pose_).norm();
  last_pose_ = pos;
  have_last_pose_ = true;
  if (in.t - last_traj_t_ >= 0.1 && trajectory_.size() < kMaxTrajectory) {
    trajectory_.push_back(pos);
    last_traj_t_ = in.t;
  }
  const bool contact = in.depth_valid && (in.contact_left || in.contact_right);
  if (in.depth_valid && contacts_.size() < kMaxContacts) {
    each_touched_point(in, [&](const Eigen::Vector2d& q) { contacts_.push_back({in.t, q}); });
  }
  if (phase_ != Phase::kHoverInit && in.t - entered_ >= 0.0 && in.t >= p_.max_time_s) {
    finish(Outcome::kTimeLimit, SequencerReason::kTimeLimit, in.t);
    out.transitioned = true;
    return out;
  }
  const double v = p_.wall.v_max;
  auto& sp = out.setpoint;
  switch (phase_) {
    case Phase::kHoverInit:
      if (hover_done(in.t)) {
        start_ = pos;
        start_yaw_ = in.yaw;
        explorer_.centre_grid(pos.x(), pos.y());
        probe_ = 0;
        heading_ = start_yaw_;
        after_turn_ = Phase::kProbe;
        enter(Phase::kTurn, SequencerReason::kHoverDone, in.t);
      }
      break;
    case Phase::kTurn: {
      const double err = wrap(heading_ - in.yaw);
      sp.yaw_rate = p_.turn_rate > 0.0 ? fast_yaw_rate(err, p_.turn_rate) : yaw_rate_to(heading_, in.yaw);
      if (aligned(in.yaw)) {
        leg_start_ = pos;
        // The leg's line: from here along the heading, except the head-on leg
        // (from the staging point along the normal) and the exit along an open
        // probe (that probe's own line, flown without contact).
        line_origin_ = pos;
        if (after_turn_ == Phase::kGoToTarget && has_staging_) line_origin_ = staging_;
        if (after_turn_ == Phase::kExitThrough && exit_kind_ == ExitKind::kAlongOpenProbe) line_origin_ = open_origin_;
        beside_added_ = false;
        leg_blind_ = 0.0;
        enter(after_turn_, SequencerReason::kAligned, in.t);
      }
      break;
    }
    case Phase::kProbe:
      if (fly_leg(in, contact, &sp)) break;
      // The end: probe_max_distance flown with fresh depth and no contact.
      if (probe_found_no_wall(pos)) {
        add(pos, kInteriorLabel);  // free all the way (flown with fresh depth)
        if (open_probe_ < 0) {
          open_probe_ = probe_;
          open_heading_ = heading_;
          open_origin_ = leg_start_;
        }
        begin_return(pos, leg_start_, ReturnFor::kNextProbe, SequencerReason::kProbeFoundNoWall, in.t);  // back along its own line
      }
      break;
    case Phase::kReturn: {
      if (return_leg_ == ReturnLeg::kToProbeLine && (return_via_ - pos).norm() < kOnProbeLine) {
        return_leg_ = ReturnLeg::kAlongProbeLine;
      }
      const Eigen::Vector2d d = (return_leg_ == ReturnLeg::kToProbeLine ? return_via_ : return_to_) - pos;
      if (back_at_return_point(pos)) {
        ++probe_;
        if (return_for_ == ReturnFor::kOpenProbeExit) {
          // Through the opening along the probe's own line (flown without
          // contact), not a parallel line from wherever the last probe ended.
          return_for_ = ReturnFor::kNextProbe;
          heading_ = open_heading_;
          exit_from_ = pos;
          leg_blind_ = 0.0;
          exit_distance_ = p_.probe_max_distance + p_.exit_confirm_distance;
          after_turn_ = Phase::kExitThrough;
          exit_kind_ = ExitKind::kAlongOpenProbe;  // its corridor was whisked by the probe
          enter(Phase::kTurn, SequencerReason::kOpenProbeExit, in.t);
          break;
        }
        if (probe_ >= p_.probe_directions && p_.diagonal_probes && probe_set_ == ProbeSet::kOrthogonal &&
            explorer_.gpis().surface_count() == 0) {
          // No wall in any direction: the diagonals before open_space.
          probe_set_ = ProbeSet::kDiagonal;
          start_yaw_ += M_PI / p_.probe_directions;
          probe_ = 0;
          open_probe_ = -1;
        }
        if (probe_ < p_.probe_directions) {
          heading_ = start_yaw_ + 2.0 * M_PI * probe_ / p_.probe_directions;
          after_turn_ = Phase::kProbe;
          enter(Phase::kTurn, SequencerReason::kNextProbe, in.t);
        } else {
          enter_refit(in, SequencerReason::kProbesDone, &out);
        }
        break;
      }
      const Eigen::Vector2d w = d.normalized() * std::min(v, d.norm());
      sp.vx = std::cos(in.yaw) * w.x() + std::sin(in.yaw) * w.y();  // world -> body
      sp.vy = -std::sin(in.yaw) * w.x() + std::cos(in.yaw) * w.y();
      break;
    }
    case Phase::kFollowWall: {
      if (in.depth_valid) {
        each_touched_point(in, [&](const Eigen::Vector2d& q) { follow_points_.push_back(q); });
      }
      const bool lv = in.depth_valid && in.contact_left && std::isfinite(in.depth_left);
      const bool rv = in.depth_valid && in.contact_right && std::isfinite(in.depth_right);
      // The shared wall following (tactile_fsm::WallFollowing): the 000 Fig. S4e
      // sub-state rule and its motion, V_sideway = V_max, V_forward =
      // V_backward = V_max / 2, turns at omega_max.
      wall_.touched(lv, rv);
      wall_.set_sub_state(wall_.rule(in.depth_left, lv, in.depth_right, rv, p_.wall));
      if (!wall_.both_touched() && lv != rv) {
        // The sequencer's own rule, one whisker on an oblique wall: turn toward
        // it until both touch instead of the approach's forward flight, which at
        // a steep angle brings the frame's corner to the wall first (workspace
        // rule; the whisker FSM meets walls head-on from FLY_FORWARD).
        const double d = lv ? in.depth_left : in.depth_right;
        sp.yaw_rate = lv ? p_.wall.omega_max : -p_.wall.omega_max;
        if (d < p_.wall.t_min) sp.vx = -0.5 * v;
      } else {
        wall_.motion(p_.wall, &sp);
      }
      if (wall_followed(in.t)) {
        enter(Phase::kRetreat, SequencerReason::kWallFollowed, in.t);
      } else if (surface_beside(pos, in.yaw)) {
        ++side_stops_;
        sp.vy = 0.0;
        enter(Phase::kRetreat, SequencerReason::kSurfaceBeside, in.t);
      }
      break;
    }
    case Phase::kRetreat:
      // 000: "flies backward for 1 second"; hover instead where that would
      // bring the frame near a known surface point behind it (a corner).
      if (rules().retreat_blocked(pos, in.yaw, retreat_lateral(in))) {
        if (!retreat_held_) ++retreats_held_;
        retreat_held_ = true;
      } else {
        sp.vx = -p_.retreat_speed;
        sp.vy = retreat_lateral(in);
      }
      if (retreated(in.t)) {
        const bool probing = round_ == Round::kProbes;
        if (p_.align_probes && probing && !aligned_) align_to_wall(in);
        commit_points(in);
        if (probing && probe_ + 1 < p_.probe_directions) {
          // Back to the start, then the next probe.
          begin_return({in.x, in.y}, leg_start_, ReturnFor::kNextProbe, SequencerReason::kRetreatedNextProbe, in.t);
          break;
        }
        enter_refit(in, SequencerReason::kRetreatedRefit, &out);
      }
      break;
    case Phase::kGoToStaging: {
      if (fly_leg(in, contact, &sp)) break;
      if (reached_or_passed(staging_, pos)) {
        heading_ = approach_heading_;  // face the wall along its normal: head-on
        after_turn_ = Phase::kGoToTarget;
        enter(Phase::kTurn, SequencerReason::kAtStaging, in.t);
      }
      break;
    }
    case Phase::kGoToTarget: {
      if (fly_leg(in, contact, &sp)) break;
      // Past the target along the leg (or within the radius): free space there.
      if (reached_or_passed(target_, pos)) {
        add(target_, kInteriorLabel);
        exit_from_ = pos;
        leg_blind_ = 0.0;
        exit_distance_ = p_.exit_confirm_distance;
        exit_kind_ = ExitKind::kBeyondTarget;  // beyond the target: unexplored, whisked
        enter(Phase::kExitThrough, SequencerReason::kTargetReached, in.t);
      }
      break;
    }
    case Phase::kExitThrough:
      if (fly_leg(in, contact, &sp)) break;
      // The end: the exit's contact-free distance, past every known wall.
      if (exit_confirmed(pos)) {
        finish(Outcome::kExitFound, SequencerReason::kExitFlownThrough, in.t);
        out.gpis_updated = true;  // publish the final target with exit_found
      }
      break;
    case Phase::kCheckAhead:
      check_ahead(in, &sp);
      break;
    case Phase::kRefit:          // left in the tick it is entered (enter_refit)
    case Phase::kFailsafeHover:  // handled above
    case Phase::kLanding:
    case Phase::kDone:
      break;
  }
  const double whisk_rate = whisking_ ? out.setpoint.yaw_rate : 0.0;
  out.setpoint = tactile_fsm::saturate(out.setpoint, p_.wall);
  if (whisking_) out.setpoint.yaw_rate = std::clamp(whisk_rate, -p_.whisk_rate, p_.whisk_rate);
  whisking_ = false;
  out.transitioned = transitions_ != tr || phase_ != before;
  return out;
}

}  // namespace gpis_explorer
