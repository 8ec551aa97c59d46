// Exploration sequencing of the whiskered drone (paper 000, Methods "Active
// aerial tactile exploration implementation", Extended Data Fig. 1d):
//   1. probe in four orthogonal directions (90 deg apart): turn, fly forward
//      until a whisker touches;
//   2. on contact follow the wall for 2 s collecting surface points, then fly
//      backward for 1 s; keep 4 surface points per wall follow and 1 interior
//      point per retreat (the onboard downsampling of 000);
//   3. refit the GPIS (eq. 31-46), turn toward the target and fly to it;
//      contact -> 2.; target reached without contact -> it is free space
//      (interior point) and the drone keeps going: still no contact after
//      exit_confirm_distance -> the exit has "emerged" and is flown through.
// Legs into unexplored space are whisked (yaw +-whisk_amplitude about the
// heading while moving along the leg's line) so that the two forward whiskers
// sweep the guard's corridor; a whisk contact in it stops the leg
// (CHECK_AHEAD: wall follow, or back off when touched close to the guard).
// The drone never heads into a penalised corner: targets near corners are
// excluded (GpisExplorer), targets whose straight path passes a corner are
// skipped, and approaching a corner centroid aborts the leg (retreat, refit).
//
// Every phase that moves needs fresh inputs. The shared fail-safe
// (tactile_fsm::SafetyRunner, the one every behaviour runs) watches the tactile
// depth and the odometry (wall.max_input_age_s): one stale -> FAILSAFE_HOVER
// (zero velocity, flight height, nothing recorded); both fresh again -> the
// interrupted phase, its timers paused; stale for wall.failsafe_land_after_s
// -> LANDING (outcome inputs_stale). Its reason codes are the runner's
// REASON_FAILSAFE_*, as the other behaviours publish.
//
// Core layer: no ROS, no messages. The wall follow is tactile_fsm's wall
// following component (tactile_fsm::WallFollowing, 000 Fig. S4e), the one the
// whisker FSM's WALL_FOLLOWING runs.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gpis_explorer/explorer.hpp"
#include "gpis_explorer/path_rules.hpp"
#include "tactile_fsm/safety_runner.hpp"
#include "tactile_fsm/whisker_wall_follower.hpp"

namespace gpis_explorer {

enum class Phase : uint8_t {
  kHoverInit,   ///< hover at the start (000 Methods "Hovering")
  kTurn,        ///< yaw toward the next heading
  kProbe,       ///< one of the four orthogonal probes: forward until contact
  kReturn,      ///< a probe found no wall: back to the start point
  kFollowWall,  ///< 2 s of wall following (000 Fig. S4e rule), collecting surface points
  kRetreat,     ///< 1 s backward, then an interior point
  kGoToStaging, ///< forward to the staging point inside the target's wall (head-on approach)
  kGoToTarget,  ///< forward toward the GPIS target
  kExitThrough, ///< target reached without contact: keep going through the opening
  kCheckAhead,  ///< a whisk touched the corridor: stop, face the leg's heading: wall to follow, or back off?
  /// GPIS update (000 eq. 31-46) and the next target: its entry action
  /// decides and leaves it in the same tick (the state a program sees after
  /// a step is never REFIT; FsmState's previous_state is). Entered after the
  /// last probe's return and after every retreat of the target round.
  kRefit,
  /// The shared fail-safe's FAILSAFE_HOVER (tactile_fsm::SafetyRunner): tactile
  /// depth or odometry stale: hover (zero velocity, flight height), record
  /// nothing; inputs fresh again -> the interrupted phase (its timers paused),
  /// stale for wall.failsafe_land_after_s -> LANDING (inputs_stale).
  kFailsafeHover,
  kLanding,     ///< land (exit flown through, open space, or gave up)
  kDone,        ///< terminal
};
const char* to_string(Phase p);

// The phases' sub-states, explicit (each a state of its own phase; to_string
// gives the snake-case name ExplorationSequencer::sub_state() reports).

/// Which round of the exploration the contact episodes belong to: the probes
/// (000: four orthogonal directions) or the GPIS targets after the first refit.
enum class Round : uint8_t {
  kProbes,   ///< the probes (their follows return to the start for the next probe)
  kTargets,  ///< GPIS targets (each follow / back-off ends in a refit)
};
const char* to_string(Round r);

/// The set of probe headings flying (diagonal_probes).
enum class ProbeSet : uint8_t {
  kOrthogonal,  ///< start heading (or the first wall's normal) + k * 360 / probe_directions
  kDiagonal,    ///< no wall in any of those: turned by half their spacing
};
const char* to_string(ProbeSet s);

/// CHECK_AHEAD: first the whisk back to the leg's heading, then the dwell that decides.
enum class CheckStage : uint8_t {
  kWhiskBack,  ///< yaw back to the leg's heading at up to whisk_rate
  kDwell,      ///< hover check_dwell_s on the heading, then decide
};
const char* to_string(CheckStage s);

/// RETURN: across to the probe's line first (return_via_probe_line), then along it.
enum class ReturnLeg : uint8_t {
  kToProbeLine,     ///< to the foot of the perpendicular on the probe's line
  kAlongProbeLine,  ///< to the probe's origin (straight there when already on the line)
};
const char* to_string(ReturnLeg l);

/// What the RETURN is for (decided when it begins).
enum class ReturnFor : uint8_t {
  kNextProbe,      ///< the next probe (or, after the last one, the refit)
  kOpenProbeExit,  ///< out through the opening along the probe that found no wall
};
const char* to_string(ReturnFor r);

/// What the RETREAT ends (decided on entry from the phase it leaves).
enum class RetreatKind : uint8_t {
  kAfterFollow,  ///< after a wall follow: also sideways back toward its start (retreat_toward_follow_start)
  kBackOff,      ///< after a touch too near the guard (CHECK_AHEAD) or a penalised corner ahead: straight back
};
const char* to_string(RetreatKind k);

/// EXIT_THROUGH: along the open probe's line (its corridor whisked by the
/// probe: V_max, no whisking) or beyond a contact-free GPIS target (unexplored: whisked).
enum class ExitKind : uint8_t {
  kAlongOpenProbe,
  kBeyondTarget,
};
const char* to_string(ExitKind k);

/// Why the last transition happened (reason() is the text for people; this is
/// what programs key on). The values are tactile_msgs/msg/FsmState's
/// REASON_FAILSAFE_* (1-6, the shared fail-safe's) and REASON_GPIS_* (block
/// 50-79); the node logic checks both at compile time.
enum class SequencerReason : uint8_t {
  kNone = 0,  ///< no transition yet
  // The shared fail-safe's (tactile_fsm::SafetyReason, REASON_FAILSAFE_*):
  kFailsafeDepthStale = 1,     ///< -> FAILSAFE_HOVER: tactile depth older than wall.max_input_age_s
  kFailsafeOdometryStale = 2,  ///< -> FAILSAFE_HOVER: odometry older than wall.max_input_age_s
  kFailsafeInputsFresh = 5,    ///< FAILSAFE_HOVER -> the interrupted phase (resumed, its clocks paused)
  kFailsafeStaleTooLong = 6,   ///< FAILSAFE_HOVER -> LANDING (inputs_stale)
  // The sequencer's own (REASON_GPIS_*):
  kHoverDone = 50,  ///< HOVER_INIT -> TURN: hover_init_s hovered, the first probe
  kAligned = 51,  ///< TURN -> PROBE / GO_TO_STAGING / GO_TO_TARGET / EXIT_THROUGH: heading within yaw_tolerance
  kProbeFoundNoWall = 52,  ///< PROBE -> RETURN: probe_max_distance flown with fresh depth, no contact
  kWhiskContact = 53,  ///< PROBE / GO_TO_* / EXIT_THROUGH -> CHECK_AHEAD: a whisk contact in the guard's corridor
  kContact = 54,  ///< a leg or CHECK_AHEAD -> FOLLOW_WALL: a wall ahead to follow
  kBesideCorridor = 55,  ///< CHECK_AHEAD -> the leg it stopped: no touched point in the corridor
  kTooNearTheGuard = 56,  ///< CHECK_AHEAD -> RETREAT: nearest point in the corridor < follow_min_forward ahead
  kCornerAhead = 57,  ///< GO_TO_STAGING / GO_TO_TARGET -> RETREAT: a corner centroid 0.1 m ahead (000 eq. 45)
  kWallFollowed = 58,  ///< FOLLOW_WALL -> RETREAT: follow_time_s (000: 2 s)
  kSurfaceBeside = 59,  ///< FOLLOW_WALL -> RETREAT: a known surface point or wall line across the slide
  kRetreatedNextProbe = 60,  ///< RETREAT -> RETURN: probes left
  kNextProbe = 61,  ///< RETURN -> TURN: at the start, the next probe heading
  kProbesDone = 62,  ///< RETURN -> REFIT: the last probe (no wall) back at the start
  kRetreatedRefit = 63,  ///< RETREAT -> REFIT: retreat_time_s, no probe left
  kOpenProbeReturn = 64,  ///< REFIT -> RETURN: a probe found no wall where others met walls
  kOpenProbeExit = 65,  ///< RETURN -> TURN: back at the open probe's origin, out along it
  kTargetViaStaging = 66,  ///< REFIT -> TURN: a target approached head-on through its staging point
  kTargetChosen = 67,  ///< REFIT -> TURN: a target flown at directly (or from its staging point)
  kAtStaging = 68,  ///< GO_TO_STAGING -> TURN: at the staging point, face the target's normal
  kTargetReached = 69,  ///< GO_TO_TARGET -> EXIT_THROUGH: target reached or passed, no contact
  kUpdateLimit = 74,  ///< REFIT -> LANDING (update_limit): max_updates
  kNoTarget = 75,  ///< REFIT -> LANDING (no_target)
  kOpenSpace = 76,  ///< REFIT -> LANDING (open_space)
  kExitFlownThrough = 77,  ///< EXIT_THROUGH -> LANDING (exit_found)
  kTimeLimit = 78,  ///< any moving phase -> LANDING (time_limit): max_time_s
  kLanded = 79,  ///< LANDING -> DONE: landing_duration_s
};
const char* to_string(SequencerReason r);  ///< snake case: "hover_done", "probe_found_no_wall", ...
/// reason()'s text: the code's, and for a stale input at the end of
/// HOVER_INIT (`from`) "... at end of hover".
const char* reason_text(SequencerReason r, Phase from);

/// Why the exploration ended.
enum class Outcome : uint8_t {
  kRunning,
  kExitFound,      ///< flew through an opening (probe or GPIS target)
  kOpenSpace,      ///< no contact in any probe direction: no surface to explore
  kNoTarget,       ///< GPIS gave no reachable target (status in last_update)
  kUpdateLimit,    ///< max_updates GPIS updates without an exit
  kTimeLimit,      ///< max_time_s without an exit
  kInputsStale,    ///< depth or odometry stale for wall.failsafe_land_after_s (FAILSAFE_HOVER)
};
const char* to_string(Outcome o);

/// The wall follows' parameters: the whisker FSM's (tactile_fsm defaults) with
/// its two issue-17 rules for baffle courses off, hold_heading_trailing_lost
/// and wall_end_depth: the GPIS rooms were tuned and measured without them
/// (a choice; they are not node parameters of gpis_explorer).
inline tactile_fsm::WallFollowerParams gpis_wall_params() {
  tactile_fsm::WallFollowerParams w;
  w.hold_heading_trailing_lost = false;
  w.wall_end_depth = 0.0;
  return w;
}

struct SequencerParams {
  ExplorerParams explorer;
  /// Wall-following band and speeds (000 Fig. S4e; gpis_wall_params());
  /// also the input staleness of every phase: wall.max_input_age_s (the node
  /// logic's freshness of depth and odometry) and wall.failsafe_land_after_s
  /// (FAILSAFE_HOVER -> LANDING), the shared fail-safe's.
  tactile_fsm::WallFollowerParams wall = gpis_wall_params();
  int probe_directions = 4;             ///< 000: "four orthogonal directions (90 deg apart)"
  /// No wall within probe_max_distance in any probe direction: probe once
  /// more, turned by half the probes' spacing (the diagonals), before landing
  /// with open_space. In a room turned ~45 deg to the start heading whose
  /// corners lie beyond probe_max_distance (3.4 m square: 2.4 m), every probe
  /// flies at a corner (issue 17, rooms 1379, 1383, 1467). (choice)
  bool diagonal_probes = true;
  double follow_time_s = 2.0;           ///< 000: "follows the wall for 2 seconds"
  double retreat_time_s = 1.0;          ///< 000: "flies backward for 1 second"
  int surface_points_per_follow = 4;    ///< 000: "storing four data points per wall-follow"
  int interior_points_per_retreat = 1;  ///< 000: "and one per retreat"
  /// Backward speed of the retreat [m/s]; workspace choice: V_max / 2 as the
  /// FSM's FLY_BACKWARD (000 Fig. S4e).
  double retreat_speed = 0.1;
  /// The retreat after a wall follow also moves sideways back toward where
  /// the follow started (body-y = -offset / retreat_time_s, at most
  /// retreat_speed): back over the band the follow's slide swept, away from
  /// what the slide ran into. Straight back, the guard's side grazed the
  /// other wall of a corner the slide had ended beside (issue 17: 8 of 24
  /// first guard touches on rooms 1000-1599, all side or rear-side).
  /// retreat_clearance checks the path with the sideways part. (choice)
  bool retreat_toward_follow_start = true;
  /// A probe with no contact after this distance found an opening [m] (choice).
  double probe_max_distance = 2.0;
  /// Yaw control: rate = gain * error, |rate| <= omega_max; aligned below tolerance.
  double yaw_gain = 2.0;                ///< [1/s] (choice)
  double yaw_tolerance = 0.05;          ///< [rad] (choice, ~3 deg)
  /// TURN (in place, hovering) at most this yaw rate, at gain 4 * yaw_gain
  /// (as the whisk back of CHECK_AHEAD). 0 = the wall follower's omega_max
  /// (25 deg/s) at yaw_gain, the previous turn. Turning in place moves no
  /// part of the round guard; issue 17: in the rooms that time out, a third
  /// of the flight was TURN. [rad/s] (choice, <= whisk_rate: the yaw rate the
  /// vehicle is flown at while whisking, also bounding it with whisking off)
  double turn_rate = 2.0;
  double target_radius = 0.10;          ///< target reached [m] (choice)
  /// Beyond a contact-free target, this much more contact-free flight = exit
  /// flown through [m] (choice). 0.8 m (about the whisker-to-frame margin plus
  /// a room wall) reported exits from inside rooms whose far wall no probe had
  /// touched (the GPIS contour then lies inside the room; issue 17: 11 of 600
  /// rooms 1000-1599 ended 0.2-0.4 m short of that wall); 1.2 m.
  double exit_confirm_distance = 1.2;
  /// ... and every known surface point at least this far behind the drone
  /// along the leg (else it keeps going, at most probe_max_distance more). [m]
  double exit_beyond = 0.3;
  double min_target_distance = 0.3;     ///< targets closer than this to the drone are skipped [m] (choice)
  /// Sideways wall following ends early when a known surface point (an
  /// earlier contact) lies within this distance ahead of the frame in the
  /// sideways direction: the frame has no side whiskers, so a wall met
  /// sideways in a corner would be hit (000 Results: corners "risk
  /// collisions"). [m] (choice)
  double side_clearance = 0.25;
  /// ... or when the line of a wall touched before, extended this far beyond
  /// the touched span on either end, crosses the sideways path within
  /// side_clearance of the centre (at >= 45 deg to it). Each wall follow (or
  /// back-off after a whisk contact: its touched points) whose contact points
  /// lie on a line (spread >= 5 cm along it, <= 2 cm across, 2 sigma) gives
  /// one wall line (the last 64 are kept). A short span's direction is
  /// uncertain (up to ~20 deg at 5 cm and 2 cm), so an extended line may stop
  /// a slide it does not cross: a wall follow ends early, no collision; a wall continues beyond where it was touched, and in
  /// a room corner the wall met sideways is the line of a wall touched in its
  /// middle (issue 17: 6 of 14 first guard touches on rooms 1000-1299 were
  /// the frame's side meeting a corner's other wall in a wall follow). 0 = off
  /// (known points only). [m] (choice)
  double wall_extension = 3.0;
  /// When no target is left, corner centroids (000 eq. 42-43) with no surface
  /// training point within this radius are not taken for corners and the
  /// choice is made again: such a "corner" is where the fit bends across a
  /// gap nothing has touched, often an exit beside a room corner, whose
  /// contour points the corner exclusion and the path rules otherwise refuse
  /// (issue 17: `no_target` with both exits 0.2-0.3 m from a corner). Only
  /// then, so the paper's corner penalty (eq. 45) rules every other choice.
  /// 0.15 m: a corner the drone touched has points within ~0.1 m of the
  /// centroid. 0 = off. [m] (choice)
  double corner_confirm_radius = 0.15;
  // --- Collision avoidance of the sequencing (workspace rules; 000 gives the
  // corner penalty eq. 45 and "discourage entry into concave, high-risk
  // areas" but no path rule). The whiskers see only what is ahead within
  // +-2.5 cm of the axis, the guard is 16 cm wide: walls met at grazing
  // incidence or wall ends beside the axis are not felt before the guard.
  /// Approach each target head-on: fly first to a staging point this far
  /// inside along the GPIS normal at the target (-grad f / |grad f|, 000
  /// eq. 36), turn to face the normal, then go forward to the target. 0 = fly
  /// straight to the target (the previous behaviour). [m]
  double approach_standoff = 0.4;
  /// Legs to a staging point keep this distance from every known surface
  /// point (training points labelled 0); from a start already closer, they
  /// must not get closer. [m]
  double path_clearance = 0.25;
  /// The head-on leg (staging point -> target, shortened by this much) keeps
  /// approach_clearance from known surface points: a wall end beside the leg
  /// would meet the guard, not the whiskers. [m]
  double approach_clearance = 0.14;
  /// Forward legs fly at slow_fraction * V_max while a known surface point is
  /// within slow_distance of the whisker tips (more time for the contact to
  /// be detected before the guard reaches the wall). [m], [-]
  double slow_distance = 0.3;
  double slow_fraction = 0.5;
  /// After the first probe's wall follow, the remaining probes are turned to
  /// be orthogonal to that wall (four orthogonal directions, 000, aligned with
  /// the first wall so that in a rectangular room every probe meets its wall
  /// head-on). false: the probes keep the start heading.
  bool align_probes = true;
  /// Forward legs hold their line: body-y velocity -line_gain * lateral
  /// offset (at most V_max / 2). An exit is flown out along the line that was
  /// checked (the open probe's, or the head-on leg's), not a parallel line
  /// up to target_radius beside it. [1/s]
  double line_gain = 1.0;
  /// RETURN after a probe's wall follow first moves across to the probe's
  /// line (the foot of the perpendicular, back along the wall follow's slide)
  /// and then along the line to its origin, instead of straight to the
  /// origin across space no leg swept (issue 17: 3 of 14 first guard touches
  /// on rooms 1000-1299 were a straight return meeting a pillar or a wall end
  /// beside the probe's line). Offsets below 3 cm go straight; the first leg
  /// ends within 3 cm of the line.
  bool return_via_probe_line = true;
  /// A target whose leg ended in a contact is visited: contour points within
  /// this distance of it are not chosen again. Without it the drone re-flies
  /// the same target once the onboard budget (50 points) is full and the
  /// GPIS stops changing. [m]
  double visited_radius = 0.3;
  /// Whisking (000 Fig. 1d: "similar to how a rat uses rhythmic whisking to
  /// scan"; our choice, 000 flies straight): on legs into unexplored space
  /// (probes, staging and target legs, the exit after a target) the drone yaws back and
  /// forth by +-whisk_amplitude about the leg's heading at whisk_rate while it
  /// moves along the leg at whisk_speed. The two forward whiskers (+-2.5 cm)
  /// then sweep the guard's corridor (+-8 cm): a wall end 2.5-8 cm beside the
  /// axis (an exit's jamb) is touched by a whisker shaft before the guard
  /// reaches it. 0 = no whisking (straight legs at V_max). [rad], [rad/s], [m/s]
  double whisk_amplitude = 0.5;
  double whisk_rate = 2.5;
  double whisk_speed = 0.1;
  /// A whisk contact whose point lies within corridor_half_width of the leg's
  /// axis (guard radius 8 cm + 3 cm) stops the leg; one beside it does not.
  /// After a stop the drone whisks back to the leg's heading and hovers
  /// check_dwell_s. The points touched in the first check_sample_s decide:
  /// the nearest in the corridor at least follow_min_forward ahead of the
  /// centre (the near edge of the wall-following band, whisker base 5 cm +
  /// t_min 6 cm) -> wall follow; nearer -> retreat along the leg (a wall end
  /// beside the axis close to the guard: a wall follow toward it would slide
  /// the guard into it; seen in the SITL). [m], [s], [s], [m]
  double corridor_half_width = 0.11;
  /// A retreat (backward, blind) hovers instead when it would bring the
  /// centre closer than this to a known surface point behind or beside it
  /// (guard 8 cm + 6 cm; retreats into the other wall of a corner). [m]
  double retreat_clearance = 0.14;
  double check_dwell_s = 0.4;
  double check_sample_s = 0.06;
  double follow_min_forward = 0.11;
  /// With the training budget full (gpis.max_points, 50 onboard), a new
  /// point replaces the most redundant one instead of being dropped: of the
  /// closest pair of same-label points the older goes, or the new point is
  /// dropped when it is itself the closest to a point of its label (our
  /// choice; 000 gives the budget, not what happens when it is full). Dropped,
  /// the map froze after ~6 updates, and the path rules, which read the
  /// training points, stayed blind to walls touched since (issue 17).
  bool replace_when_full = true;
  int max_updates = 40;                 ///< give up after this many GPIS updates (choice)
  double max_time_s = 600.0;            ///< give up after this long [s] (choice)
  double landing_duration_s = 2.0;      ///< LANDING -> DONE [s]
  /// Throws std::invalid_argument "SequencerParams.<field>: <reason>".
  void validate() const;
};

/// replace_when_full's choice for a new point (q, label) with the budget full:
/// of the closest pair of training points with the same label (000's labels:
/// 0 surface, -1 interior) the older (lower index) is replaced; when q is at
/// least as close to a point of its own label, q is the redundant one and
/// g.size() is returned (drop q). Our rule; 000 gives the budget, not what
/// happens when it is full. O(n^2).
std::size_t point_to_replace(const Gpis& g, const Eigen::Vector2d& q, double label);

/// corner_confirm_radius: the corner centroids with a surface training point
/// (label 0) within `radius` of them, in their order. Our rule.
std::vector<Eigen::Vector2d> confirmed_corners(const Gpis& g, const std::vector<Eigen::Vector2d>& corners,
                                               double radius);

/// Principal line of a set of points (a wall follow's contacts): the mean,
/// the unit direction of the larger covariance eigenvalue, the 2-sigma spread
/// along it and across it (thickness), and the span's ends on the line.
/// ok = false for fewer than 2 points.
struct LineFit {
  bool ok = false;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero(), dir{1, 0}, a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  double spread = 0.0, thickness = 0.0;
};
LineFit fit_line(const std::vector<Eigen::Vector2d>& pts);

/// Distance along the ray from `from` in the unit direction `dir` to the
/// segment a-b extended by `extension` beyond both ends; infinity when the
/// ray misses it or meets its line at less than 45 deg (a wall beside the
/// path, not across it). wall_extension's test.
double ray_to_wall_line(const Eigen::Vector2d& from, const Eigen::Vector2d& dir, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b, double extension);

/// CHECK_AHEAD's transition table after the dwell, on the points `touched`
/// in its first check_sample_s, the first guard that holds:
///   no touched point with a known position            -> kFollowUnknown (FOLLOW_WALL, as an unwhisked leg)
///   none of them in the guard's corridor              -> kLegGoesOn (the leg it stopped)
///   the nearest in the corridor >= follow_min_forward -> kFollowWall (FOLLOW_WALL)
///   else (a wall end close to the guard)              -> kBackOff (RETREAT, the points become surface points)
enum class CheckDecision : uint8_t { kFollowUnknown, kLegGoesOn, kFollowWall, kBackOff };
const char* to_string(CheckDecision d);
CheckDecision check_ahead_decision(const std::vector<Eigen::Vector2d>& touched, const Eigen::Vector2d& pos,
                                   double heading, const PathRules& rules, double follow_min_forward);

/// One control tick of input (odometry frame). Fresh: tactile_fsm::input_is_fresh
/// with wall.max_input_age_s (the node logic decides it from the stamps).
struct SequencerInput {
  double t = 0.0;
  bool pose_valid = false;  ///< odometry fresh
  double x = 0.0, y = 0.0, yaw = 0.0;
  bool depth_valid = false;  ///< tactile depth fresh (stale: FAILSAFE_HOVER once flying)
  bool contact_left = false, contact_right = false;
  double depth_left = 0.0, depth_right = 0.0;  ///< [m], used while in contact
  /// Estimated contact points (odometry frame); NaN when unknown.
  Eigen::Vector2d point_left{NAN, NAN}, point_right{NAN, NAN};
};

struct SequencerOutput {
  tactile_fsm::Setpoint setpoint;
  bool transitioned = false;
  bool gpis_updated = false;  ///< update() ran this tick (publish map and target)
};

/// One contact point seen by the whiskers (all of them, for mapping metrics).
struct ContactSample {
  double t;
  Eigen::Vector2d p;
};

class ExplorationSequencer {
 public:
  explicit ExplorationSequencer(const SequencerParams& params);

  SequencerOutput step(const SequencerInput& in);

  Phase phase() const { return phase_; }
  Phase previous_phase() const { return previous_; }
  /// Why the last transition happened: text for people (may be reworded) ...
  const char* reason() const { return reason_text(reason_code_, previous_); }
  /// ... and the code programs key on (FsmState.reason_code).
  SequencerReason reason_code() const { return reason_code_; }
  double phase_entered() const { return entered_; }
  uint32_t transitions() const { return transitions_; }
  Outcome outcome() const { return outcome_; }
  bool exit_found() const { return outcome_ == Outcome::kExitFound; }
  const GpisExplorer& explorer() const { return explorer_; }
  bool has_target() const { return has_target_; }
  Eigen::Vector2d target() const { return target_; }
  /// The current target is approached head-on from staging() along approach_heading().
  bool has_staging() const { return has_staging_; }
  Eigen::Vector2d staging() const { return staging_; }
  double approach_heading() const { return approach_heading_; }
  double target_acquisition() const { return target_acq_; }
  double target_variance() const { return target_var_; }
  /// Every contact point received (not downsampled), for maps and metrics.
  const std::vector<ContactSample>& contacts() const { return contacts_; }
  /// Every accepted pose at 10 Hz (trajectory for pictures).
  const std::vector<Eigen::Vector2d>& trajectory() const { return trajectory_; }
  double travel_distance() const { return travel_; }
  std::size_t points_rejected() const { return points_rejected_; }
  /// Training points removed to make room (replace_when_full).
  std::size_t points_replaced() const { return points_replaced_; }
  std::size_t corner_aborts() const { return corner_aborts_; }
  std::size_t side_stops() const { return side_stops_; }
  /// Targets approached head-on through a staging point / flown at directly.
  std::size_t staged_targets() const { return staged_targets_; }
  /// Targets chosen with the unconfirmed corners set aside (corner_confirm_radius).
  std::size_t unconfirmed_corner_targets() const { return unconfirmed_corner_targets_; }
  std::size_t direct_targets() const { return direct_targets_; }
  /// Legs stopped by a whisk contact; of these, walls ahead (wall follow) and
  /// wall ends in the corridor (retreat); whisk contacts beside the corridor (leg went on).
  std::size_t whisk_contacts() const { return whisk_contacts_; }
  std::size_t whisk_walls() const { return whisk_walls_; }
  std::size_t whisk_jambs() const { return whisk_jambs_; }
  std::size_t beside_contacts() const { return beside_contacts_; }
  /// Retreats held in place (a known surface point behind).
  std::size_t retreats_held() const { return retreats_held_; }
  /// FAILSAFE_HOVER entries (stale depth or odometry) and the phase the last one interrupted.
  std::size_t failsafe_hovers() const { return safety_.failsafe_hovers(); }
  Phase failsafe_from() const { return failsafe_from_; }
  /// The current phase's sub-state ("" for a phase without one), the
  /// sequencer's own in snake case:
  /// CHECK_AHEAD whisk_back / dwell, RETURN to_probe_line / along_probe_line,
  /// RETREAT after_follow / back_off, EXIT_THROUGH
  /// along_open_probe / beyond_target; FOLLOW_WALL the wall rule's
  /// (tactile_fsm::to_string(WallSubState), "FLY_SIDEWAYS", ...), TURN the
  /// phase it turns for ("PROBE", ...).
  std::string sub_state() const;
  /// Puts the sequencer directly into phase p at the input's pose, as its
  /// transitions would leave it (tests: each phase's guards alone). The pose is
  /// the start (first call), the leg's start and line origin; TestEntry gives the
  /// heading (NaN: the input's yaw), the round, a target (GO_TO_TARGET's, the
  /// staging point of GO_TO_STAGING), RETURN's point (default: the start) and
  /// the phase after a TURN. FOLLOW_WALL and RETURN run their entry actions
  /// (start_follow: the side; begin_return: the legs). REFIT, CHECK_AHEAD and
  /// FAILSAFE_HOVER are refused (std::invalid_argument): their guards enter them.
  struct TestEntry {
    double heading = NAN;
    Round round = Round::kProbes;
    std::optional<Eigen::Vector2d> target;
    std::optional<Eigen::Vector2d> return_to;
    Phase after_turn = Phase::kProbe;
  };
  void for_test_enter(Phase p, const SequencerInput& in, const TestEntry& e);

  // Named guards: the end of each phase, in step()'s words (public: tested one
  // by one). Times t and positions pos in the odometry frame.
  /// HOVER_INIT -> TURN: hover_init_s hovered.
  bool hover_done(double t) const;
  /// TURN -> the phase after it: heading within yaw_tolerance.
  bool aligned(double yaw) const;
  /// PROBE -> RETURN: probe_max_distance flown with fresh depth (leg_blind_ not counted).
  bool probe_found_no_wall(const Eigen::Vector2d& pos) const;
  /// RETURN -> TURN / REFIT: on the probe's line, within target_radius / 2 of its origin.
  bool back_at_return_point(const Eigen::Vector2d& pos) const;
  /// FOLLOW_WALL -> RETREAT: follow_time_s (000: 2 s).
  bool wall_followed(double t) const;
  /// FOLLOW_WALL -> RETREAT: sliding sideways into a known surface (PathRules::side_blocked).
  bool surface_beside(const Eigen::Vector2d& pos, double yaw) const;
  /// RETREAT -> RETURN / REFIT: retreat_time_s (000: 1 s).
  bool retreated(double t) const;
  /// GO_TO_STAGING / GO_TO_TARGET -> TURN / EXIT_THROUGH: within target_radius of
  /// the point, or past it along the heading.
  bool reached_or_passed(const Eigen::Vector2d& point, const Eigen::Vector2d& pos) const;
  /// EXIT_THROUGH -> LANDING (exit_found): the exit's contact-free distance flown,
  /// beyond every known surface ahead (or probe_max_distance further).
  bool exit_confirmed(const Eigen::Vector2d& pos) const;

  Round round() const { return round_; }
  ProbeSet probe_set() const { return probe_set_; }
  const SequencerParams& params() const { return p_; }

 private:
  void enter(Phase p, SequencerReason why, double t);
  /// The shared fail-safe's verdict on this tick, applied to the phases:
  /// FAILSAFE_HOVER from the current phase, held, resumed (the interrupted
  /// phase with its timers shifted by the time held: the hover does not
  /// count) or LANDING. True when the tick ends here (hover or landing).
  bool apply_safety(const SequencerInput& in, SequencerOutput* out);
  /// A tick held in FAILSAFE_HOVER: the odometry's drift counts as travel,
  /// and not as a contact-free part of the leg (leg_blind_).
  void hold_tick(const SequencerInput& in);
  void finish(Outcome o, SequencerReason why, double t);
  tactile_fsm::Setpoint hover() const;
  double yaw_rate_to(double heading, double yaw) const;
  /// Yaw rate 4 * yaw_gain * err within +-limit (TURN at turn_rate, the whisk
  /// back of CHECK_AHEAD at whisk_rate); marks the tick's rate as exceeding
  /// omega_max.
  double fast_yaw_rate(double err, double limit);
  /// FOLLOW_WALL from a contact on a leg (the round decides the side and whether the target is visited).
  void start_follow(const SequencerInput& in);
  void commit_points(const SequencerInput& in);
  /// GPIS update (000 eq. 31-46) and its corner centroids as corners_.
  void update_map();
  /// REFIT: enter it and run its entry action (transition table in sequencer.cpp).
  void enter_refit(const SequencerInput& in, SequencerReason why, SequencerOutput* out);
  /// REFIT's guards, in the order its table tries them.
  bool can_exit_via_open_probe() const;
  bool can_land_in_open_space() const;
  bool reached_update_limit() const;
  void refit_and_choose(const SequencerInput& in);
  bool choose_target(const Eigen::Vector2d& from);
  /// The path rules on the current map (training points, corners_, wall_lines_).
  PathRules rules() const { return PathRules(p_, explorer_, corners_, wall_lines_); }
  double forward_speed(const SequencerInput& in) const;
  double line_correction(const SequencerInput& in) const;
  void align_to_wall(const SequencerInput& in);
  /// The forward leg being flown (PROBE, GO_TO_STAGING, GO_TO_TARGET,
  /// EXIT_THROUGH): its line passes line_origin_ along heading_ (from
  /// leg_start_ / exit_from_); whether it is whisked and whether a penalised
  /// corner ahead aborts it; its end is the phase's (probe_max_distance, the
  /// staging point, the target, the exit's confirmation distance).
  struct Leg {
    bool whisk = false;         ///< whisk_leg(): probes, GPIS legs, the exit beyond a target
    bool corner_abort = false;  ///< GO_TO_STAGING / GO_TO_TARGET: a corner centroid 0.1 m ahead -> RETREAT
  };
  Leg leg() const;
  /// One tick of the current forward leg, the same for every leg: setpoint
  /// into *sp; true when a contact (or, corner_abort, a penalised corner
  /// ahead) left the leg's phase. The caller then checks the leg's end.
  bool fly_leg(const SequencerInput& in, bool contact, tactile_fsm::Setpoint* sp);
  /// Forward motion along heading_ (its line held); whisking when asked and
  /// enabled. Returns true when the yaw rate is a whisk (beyond omega_max).
  bool leg_motion(const SequencerInput& in, double speed, bool whisk, tactile_fsm::Setpoint* sp);
  /// Whisking on the current forward leg (probe, GPIS legs, exit after a target).
  bool whisk_leg() const;
  void start_check(const SequencerInput& in);
  void check_ahead(const SequencerInput& in, tactile_fsm::Setpoint* sp);
  /// A whisk contact in the guard's corridor (see corridor_half_width).
  bool whisk_blocked(const SequencerInput& in);
  void add(const Eigen::Vector2d& p, double label);

  SequencerParams p_;
  GpisExplorer explorer_;
  Phase phase_ = Phase::kHoverInit;
  Phase previous_ = Phase::kHoverInit;
  Phase after_turn_ = Phase::kProbe;
  SequencerReason reason_code_ = SequencerReason::kNone;
  Outcome outcome_ = Outcome::kRunning;
  bool started_ = false;
  double entered_ = 0.0;
  uint32_t transitions_ = 0;
  Eigen::Vector2d start_{0, 0};
  double start_yaw_ = 0.0;
  int probe_ = 0;  ///< index of the current probe direction
  Round round_ = Round::kProbes;
  double heading_ = 0.0;  ///< heading of the current turn / leg [rad]
  Eigen::Vector2d leg_start_{0, 0};
  int open_probe_ = -1;  ///< a probe that found no wall
  ProbeSet probe_set_ = ProbeSet::kOrthogonal;
  Eigen::Vector2d follow_start_{0, 0};  ///< where the last wall follow began
  RetreatKind retreat_kind_ = RetreatKind::kBackOff;
  double retreat_lateral(const SequencerInput& in) const;
  /// The wall follow's episode: the whisker FSM's wall following component
  /// (side, both touched, sub-state), begun by start_follow().
  tactile_fsm::WallFollowing wall_;
  std::vector<Eigen::Vector2d> follow_points_;
  std::vector<WallLine> wall_lines_;  ///< at most 64 (the oldest dropped)
  void add_wall_line();
  bool has_target_ = false;
  bool has_staging_ = false;
  bool aligned_ = false;  ///< probes aligned to the first wall
  Eigen::Vector2d staging_{0, 0};
  double approach_heading_ = 0.0;
  double open_heading_ = 0.0;  ///< heading of the probe that found no wall
  ReturnFor return_for_ = ReturnFor::kNextProbe;
  Eigen::Vector2d open_origin_{0, 0};  ///< where the open probe started
  /// RETURN's first leg ends within this of the probe's line; a smaller
  /// offset goes straight (return_via_probe_line). [m]
  static constexpr double kOnProbeLine = 0.03;
  Eigen::Vector2d return_via_{0, 0};  ///< RETURN's first leg ends here (return_via_probe_line)
  ReturnLeg return_leg_ = ReturnLeg::kAlongProbeLine;
  void begin_return(const Eigen::Vector2d& pos, const Eigen::Vector2d& to, ReturnFor what, SequencerReason why,
                    double t);
  Eigen::Vector2d return_to_{0, 0};    ///< RETURN goes here: the probe's origin (back along its line)
  Eigen::Vector2d line_origin_{0, 0};  ///< the current forward leg's line passes here along heading_
  Eigen::Vector2d target_{0, 0};
  double target_acq_ = 0.0, target_var_ = 0.0;
  Eigen::Vector2d exit_from_{0, 0};
  double exit_distance_ = 0.8;  ///< contact-free distance from exit_from_ that confirms the exit
  int whisk_dir_ = 1;  ///< current whisk direction (+1 left, -1 right)
  bool whisking_ = false;  ///< this tick's yaw rate is a whisk
  ExitKind exit_kind_ = ExitKind::kBeyondTarget;  ///< of the EXIT_THROUGH flying or turned to
  Phase check_from_ = Phase::kProbe;  ///< leg interrupted by the check
  CheckStage check_stage_ = CheckStage::kWhiskBack;
  double check_t_ = 0.0;
  double check_started_ = 0.0;
  std::vector<Eigen::Vector2d> check_points_;
  bool retreat_held_ = false;
  std::size_t retreats_held_ = 0;
  bool beside_added_ = false;  ///< this leg already added a point touched beside its corridor
  std::size_t whisk_contacts_ = 0, whisk_walls_ = 0, whisk_jambs_ = 0, beside_contacts_ = 0;
  std::vector<Eigen::Vector2d> visited_;  ///< targets whose leg ended in a contact
  std::vector<ContactSample> contacts_;
  std::vector<Eigen::Vector2d> trajectory_;
  double last_traj_t_ = -1.0;
  bool have_last_pose_ = false;
  Eigen::Vector2d last_pose_{0, 0};
  double travel_ = 0.0;
  std::size_t points_rejected_ = 0;
  std::size_t points_replaced_ = 0;
  std::size_t corner_aborts_ = 0;
  std::size_t side_stops_ = 0;
  std::size_t staged_targets_ = 0;
  std::size_t unconfirmed_corner_targets_ = 0;
  /// The corner centroids the path rules keep away from: the last update's,
  /// or its confirmed ones after a choice that needed corner_confirm_radius.
  std::vector<Eigen::Vector2d> corners_;
  std::size_t direct_targets_ = 0;
  // The shared fail-safe (inputs: tactile depth, then odometry) and, in
  // FAILSAFE_HOVER, the interrupted phase and its entry time.
  tactile_fsm::SafetyRunner safety_;
  Phase failsafe_from_ = Phase::kHoverInit;
  double failsafe_from_entered_ = 0.0;
  /// Odometry path length while held in FAILSAFE_HOVER since the current leg
  /// began (leg_start_ / exit_from_): a probe's "no wall" and an exit's
  /// contact-free distance count only what was flown with fresh depth. [m]
  double leg_blind_ = 0.0;
};

}  // namespace gpis_explorer
