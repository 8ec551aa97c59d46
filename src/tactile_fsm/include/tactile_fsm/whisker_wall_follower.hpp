// Whisker wall-following finite-state machine (paper 000, Methods "Whisker-based
// aerial tactile navigation strategy" and Supplementary Fig. S4e).
//
// Core layer: no ROS, no message types, no allocation per tick. One call of
// WhiskerWallFollower::step() per control tick (50 Hz in 000) turns the
// latest tactile depths, whisker contact flags and odometry into a
// velocity-mode hover setpoint (body vx, vy, yaw rate, height, land).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "tactile_fsm/safety_runner.hpp"

namespace tactile_fsm {

/// Top-level states (000 Methods: hover -> fly forward -> wall following ->
/// resume forward -> landing) plus the workspace's terminal and fail-safe states.
enum class FsmState : uint8_t {
  kHoverInit,      ///< hover while TDORC initialises (000 Methods "Hovering")
  kFlyForward,     ///< forward at V_max (000 Methods "Flying Forward")
  kWallFollowing,  ///< Fig. S4e sub-states, see WallSubState
  kResumeForward,  ///< obstacle cleared: side-step the clearance margin, then FlyForward
  kLanding,        ///< target reached (000 Methods "Landing")
  kLanded,         ///< terminal
  kFailsafeHover,  ///< stale input: hold position
  kFailsafeLand,   ///< stale input for failsafe_land_after_s: land (terminal)
};

/// Wall-following sub-states of 000 Fig. S4e.
enum class WallSubState : uint8_t {
  kNone,          ///< not wall following
  kFlySideways,   ///< along the wall at V_max (000 Fig. S4e, V_sideway = V_max)
  kFlyForward,    ///< toward the wall at V_max / 2 (000 Fig. S4e, V_forward)
  kFlyBackward,   ///< away from the wall at V_max / 2 (000 Fig. S4e, V_backward)
  kTurnLeft,      ///< counter-clockwise at omega_max
  kTurnRight,     ///< clockwise at omega_max
};

/// Side the wall is followed to (direction of the sideways flight).
enum class Side : uint8_t { kRight, kLeft };

/// Why the follower's last transition, sub-state change or override rule's
/// onset happened: the values of tactile_msgs/FsmState's REASON_WHISKER_*
/// codes (block 30-49, static_asserts in whisker_fsm_logic.cpp). The
/// fail-safe's transitions carry the SafetyRunner's SafetyReason (1-7).
enum class WhiskerReason : uint8_t {
  kNone = 0,                  ///< REASON_NONE: no transition yet
  kHoverDone = 30,            ///< HOVER_INIT -> FLY_FORWARD (hover_done)
  kContact = 31,              ///< FLY_FORWARD -> WALL_FOLLOWING (contact), side chosen
  kContactSameObstacle = 32,  ///< FLY_FORWARD -> WALL_FOLLOWING (contact_same_obstacle), side kept
  kContactBaffleEnd = 33,     ///< FLY_FORWARD -> WALL_FOLLOWING (contact_at_baffle_end), passing it as an edge
  kContactWhileClearing = 34, ///< RESUME_FORWARD -> WALL_FOLLOWING (contact_while_clearing)
  kObstacleCleared = 35,      ///< WALL_FOLLOWING -> RESUME_FORWARD (obstacle_cleared)
  kClearedByMargin = 36,      ///< RESUME_FORWARD -> FLY_FORWARD (cleared_by_margin)
  kTargetReached = 37,        ///< a flying state -> LANDING (target_reached)
  kLandingDone = 38,          ///< LANDING -> LANDED (landing_done)
  kSubStateRule = 39,         ///< inside WALL_FOLLOWING: the Fig. S4e rule changed the sub-state
  kHeadingLimit = 40,         ///< override rule HeadingLimitRule began (or changed the sub-state)
  kTurnAnchor = 41,           ///< override rule TurnAnchorRule began (or changed the sub-state)
  kStepAndScan = 42,          ///< override rule StepAndScanRule began
  kYawOffset = 43,            ///< override rule YawOffsetRule began
};
/// "hover_done", "contact", ... (the guard's or rule's name; "none").
const char* to_string(WhiskerReason r);

const char* to_string(FsmState s);
const char* to_string(WallSubState s);
const char* to_string(Side s);
/// "right" / "left"; throws std::invalid_argument otherwise.
Side side_from_string(const char* s);

/// The defaults are what the whisker FSM node ships (config/tactile_fsm.yaml),
/// one default per key. gpis_explorer's wall follows start from
/// gpis_explorer::gpis_wall_params(): these with hold_heading_trailing_lost
/// and wall_end_depth off (its rooms were measured without them).
struct WallFollowerParams {
  // --- paper 000 values ---
  double v_max = 0.2;                          ///< V_max [m/s] (000 Results: "V_max = 20 cm/s")
  double omega_max = 25.0 * M_PI / 180.0;      ///< omega_max [rad/s]; symbolic in 000 Fig. S4e, 25 deg/s our value
  double t_min = 0.060;                        ///< T_min [m] (000 Results, Fig. 4c: band 60-100 mm)
  double t_max = 0.100;                        ///< T_max [m]
  double whisker_spacing = 0.05;               ///< s, lateral distance of the whisker bases [m] (000 eq. 21)
  double hover_init_s = 2.0;                   ///< hover for TDORC initialisation [s] (000 Methods "Hovering")
  double flight_height = 0.4;                  ///< height setpoint [m]
  // --- workspace choices (the paper does not give them) ---
  /// Heading alignment inside the band: start turning when the wall angle
  /// estimate |atan((d_l - d_r)/s)| (000 eq. 21) exceeds align_enter, stop
  /// below align_exit (hysteresis against depth noise).
  double align_enter = 3.0 * M_PI / 180.0;     ///< [rad]
  double align_exit = 1.0 * M_PI / 180.0;      ///< [rad]
  /// First-order low-pass for the rule: of the depths, and of the wall's
  /// world-frame normal heading yaw - theta (constant for a straight wall, so
  /// turning adds no filter lag). 0 = off.
  double depth_filter_tau_s = 0.08;
  Side follow_side = Side::kRight;             ///< default side (000 data collection sweeps right)
  bool side_toward_target = true;              ///< follow toward the target's lateral offset if > side_deadband
  double side_deadband = 0.10;                 ///< [m]
  double clear_confirm_s = 0.2;                ///< both whiskers off the wall this long = obstacle cleared [s]
  /// Extra side-step after clearing, so the frame passes the edge [m]. 0.30 m
  /// (was 0.15): in the SITL the tactile contact flags can drop up to ~0.2 m
  /// before the whiskers really leave a baffle's end (depth estimate drifting
  /// past the whisker's reach), and 0.15 m then put the frame into the tip.
  double clear_margin = 0.30;
  /// Heading realignment outside wall following (RESUME_FORWARD, FLY_FORWARD):
  /// yaw_rate = realign_gain * (course heading - yaw), saturated at omega_max;
  /// the course heading is the heading at the end of HOVER_INIT. After a
  /// tilted baffle the drone turns back to the course, so the next baffle is
  /// met head-on (000 Fig. 4h: -1 / 24.3 / -1 deg). 0 = off. [1/s]
  double realign_gain = 1.5;
  /// Trailing whisker lost after both touched (issue 17, docs/tuning/tactile_fsm.md "Random baffle
  /// courses"): hold the heading and translate on the remaining depth instead of
  /// turning toward the lost whisker. On rigid baffles TDORC can drop a pressed
  /// whisker (stick-slip) and not see it again; turning toward it then yawed the
  /// drone 40-50 deg into the wall (seeds 1001, 1043 of the tuning block). false =
  /// the previous rule (missing depth counts as beyond T_max, turn).
  /// gpis_explorer's wall follows keep it off (gpis_wall_params()).
  bool hold_heading_trailing_lost = true;
  /// One whisker left beyond this depth after both touched: the wall ends
  /// (issue 17, docs/tuning/tactile_fsm.md "Round 7"; our choice, 000 Fig. S4e has no case for a
  /// lost depth). With one depth missing after both whiskers touched, a
  /// remaining depth > wall_end_depth asks for FLY_SIDEWAYS (keep passing
  /// the edge, as for the leading whisker lost) instead of FLY_FORWARD at
  /// V_max / 2 toward a wall ahead. In the SITL bags this case is a whisker
  /// held by TDORC (105-120 mm estimated, truly free) past a baffle's end
  /// after the other whisker was released there: FLY_FORWARD drove the guard
  /// into that end (mocap 3019: 1.0 s at 0.1 m/s, the end 4 cm left of the
  /// axis) before the phantom gate's RMS window had quietened. A wall
  /// the other whisker just lost is not ahead; if the drone had only drifted
  /// off, the next touch brings it back to the rule of both depths. 0 = off
  /// (the previous rule); otherwise >= t_max. 105 mm: tuning blocks 413 ->
  /// 415 of 450 (tied with 110 / 115 mm), seen blocks 5000-8000 1068 -> 1088
  /// of 1200. gpis_explorer's wall follows keep it off (gpis_wall_params()). [m]
  double wall_end_depth = 0.105;
  /// A contact in FLY_FORWARD less than this far ahead (along the course
  /// heading) of where the side-step after a clearing ended is the same
  /// obstacle: keep the side (issue 17, docs/tuning/tactile_fsm.md "Random baffle courses": on rigid
  /// baffles both contact flags dropped together mid-wall, the drone "cleared",
  /// re-touched 8 cm further on and re-chose the side toward the target, going
  /// back along the baffle; flow-deck seed 1001 did so three times). 0.15 m:
  /// with 0.25 m the next baffle of the shipped tilted-30 course, 0.25-0.3 m
  /// ahead, counted as the same one (seed 2: heading error 12 deg). 0 = off. [m]
  double same_obstacle_distance = 0.15;
  /// Wall following never turns the heading further than this from the course
  /// heading (heading at the end of HOVER_INIT); a turn that would is replaced
  /// by the translation the depths ask for (issue 17, docs/tuning/tactile_fsm.md "Random baffle
  /// courses": with contact flags held after a whisker left a baffle, the drone
  /// followed a phantom wall, turning 95-120 deg off the course, and wrapped round
  /// the baffle's tip into the guard, 8 of 24 failures of tuning block 2000-2049).
  /// A baffle square to the course +- 25 deg (000 Fig. 4: up to 24.3 deg) needs at
  /// most 25 deg plus the alignment overshoot (45 deg: 35/50 on block 2000,
  /// 60 deg: 33/50). 0 = off. [rad]
  double max_heading_offset = 45.0 * M_PI / 180.0;
  /// Turn anchor (issue 17, docs/tuning/tactile_fsm.md "Round 13"; our choice, not in 000): in one
  /// wall following the heading turns at most turn_anchor_tolerance beyond an
  /// anchor, unless |theta| >= turn_anchor_theta; a turn that would is replaced
  /// by the translation the depths ask for (as max_heading_offset). The anchor
  /// is the wall heading (yaw - theta, 000 eq. 21) read at the first tick both
  /// whiskers touched, replaced by the one read whenever |theta| >=
  /// turn_anchor_theta while not turning, and moved toward the one read at
  /// most turn_anchor_rate while not turning. Readings in a turn never move it.
  /// On a textile baffle (friction 0.9) the tips stick while the drone turns
  /// in place: both depths read near 80 mm, biased 3-7 deg toward the turn
  /// whatever the true angle, and the turn ran on to the 45 deg limit until
  /// the guard met the baffle (a rigid / textile / glass course of three
  /// 1.3 m baffles: 4 of 10 trials). The first two-whisker reading (one tick,
  /// often during the approach's turn) comes before the tips have slid (3-4
  /// deg from the truth in those trials). Made for straight baffles: a wall
  /// that bends by more than 20 deg within one turn (a concave corner met
  /// gradually) is aligned to at the creep rate (45 deg: ~12 s) unless a clear
  /// angle is read outside a turn (a whisker touching again).
  /// turn_anchor_tolerance 0 = off. 10 deg, 10 deg, 2 deg/s: held-out block
  /// 27000-27299 857 -> 874 of 900 (docs/tuning/tactile_fsm.md "Round 13").
  double turn_anchor_tolerance = 10.0 * M_PI / 180.0;  ///< [rad]
  double turn_anchor_theta = 10.0 * M_PI / 180.0;      ///< [rad]
  double turn_anchor_rate = 2.0 * M_PI / 180.0;        ///< [rad/s]
  /// Pressed past the depth model (issue 17, docs/whisker_fsm.md "Pressed whisker"): a
  /// whisker pressed and sliding along a baffle is friction-limited, its input
  /// (sum of the three S_c, 000 eq. 5) stops growing below ~70 mm and the
  /// depth estimate reads ~70 mm (inside the band) at any true depth down to
  /// the guard. A whisker whose S_c sum was >= press_sum_pa within the last
  /// press_hold_s is taken at min(depth, press_depth) in the sub-state rule:
  /// the reading is only an upper bound, press_depth the depth such loads
  /// come from in the SITL (20-50 mm). Below T_min (band 60-100 mm) the drone
  /// backs off or turns away until the load is in the range the model
  /// resolves; inside the band (darkness, 40-100 mm) the rule does nothing.
  /// press_sum_pa 0 = off (the paper). 900 Pa, no hold: tuning blocks
  /// (docs/tuning/tactile_fsm.md "Round 3"). [Pa]
  double press_sum_pa = 900.0;
  double press_hold_s = 0.0;   ///< [s]
  double press_depth = 0.05;   ///< [m]
  double whisker_base_x = 0.05;  ///< whisker bases ahead of the odometry origin [m] (000 frame, tactile_sim); end_contact_lateral
  /// Phantom hold gated by odometry (issue 17, docs/tuning/tactile_fsm.md "Round 4"): the gel
  /// hysteresis (000 eq. 1, N_h) can leave a whisker held "in contact" by
  /// TDORC after it left a baffle, its S_c frozen on a slowly decaying offset.
  /// A whisker pressed by a moving drone follows every millimetre of the
  /// motion (stick-slip), so its S_c sum changes; a free one only shows the
  /// barometer noise. A whisker in contact whose S_c sum has stayed quiet
  /// (RMS of its sample-to-sample changes < phantom_quiet_rms, computed by the
  /// node logic over its last phantom_quiet_samples signals) while the drone
  /// moved more than phantom_travel [m] (odometry) since the sum last moved,
  /// or since the contact began, is not on a wall: the FSM ignores its depth
  /// and contact flag. Unlike tdorc_filter's hold_quiet_rms it does not end
  /// the filter's hold (no window learns pressed samples) and a pressed
  /// whisker of a hovering or turning drone is never dropped.
  /// phantom_quiet_rms 0 = off (the paper). 6.5 Pa over 25 samples, 0.03 m:
  /// tuning blocks (docs/tuning/tactile_fsm.md "Round 4"). [Pa]
  double phantom_quiet_rms = 6.5;
  double phantom_travel = 0.03;  ///< [m]
  /// RESUME_FORWARD keeps side-stepping past clear_margin while a whisker is
  /// still held as a phantom, up to this distance from the clearing [m].
  double phantom_resume_max = 2.0;
  /// Latch (issue 17, docs/tuning/tactile_fsm.md "Round 4" and "4b", with
  /// phantom_resume_max 2 m: tuning 269 -> 279 of 300, held out 10000-10099
  /// 252 -> 268): a whisker taken for a phantom stays one until its contact
  /// ends or the RMS of its sum's changes reaches 2 * phantom_quiet_rms.
  bool phantom_latch = true;
  /// Yaw-rate limit of the first-approach scan (first_scan_step), not
  /// omega_max (the wall-following turn rate). [rad/s]
  double whisk_rate_max = 3.0;
  /// Hold the scan's yaw (first_scan_step) while either whisker's S_c sum
  /// moves (RMS of its changes >= whisk_pause_rms, the node's phantom
  /// window): a touch starts 0.2-0.3 s before TDORC flags it, and a scan
  /// continuing through that sweeps the whisker into the wall. 0 = never
  /// hold. [Pa]
  double whisk_pause_rms = 13.0;
  /// Yaw offset after a clearing (issue 17, docs/tuning/tactile_fsm.md "Round 9", choice): the
  /// two forward whiskers (bases 25 mm off the axis, tips 0.191 m ahead) leave
  /// a band 25-80 mm beside the axis, inside the guard's radius, where a
  /// baffle's end meets the guard without a whisker touching. After a
  /// clearing such an end lies on the side the drone side-stepped away from
  /// (the next baffle's outer end, whose baffle lies on that side; an end on
  /// the side-step side has its baffle across the axis, where the whiskers
  /// touch it). In the FLY_FORWARD after a clearing the body's yaw is held
  /// clear_yaw_offset away from the side-step side of the heading the drone
  /// would otherwise fly (realigning to the course as before), and the
  /// velocity setpoint is turned back into that heading, so the track is
  /// unchanged and only the whiskers turn: that side's whisker tip then
  /// reaches 0.191 sin(a) + 0.025 cos(a) beside the axis (20 deg: 89 mm,
  /// beyond the guard). 0 = off (the paper: no offset). 14 deg with the
  /// release at 13 Pa: tuning 415 -> 433 of 450, seen 1088 -> 1123 of 1200
  /// (docs/tuning/tactile_fsm.md "Round 9"). [rad]
  double clear_yaw_offset = 0.2443;
  /// Back to the track's heading (until the next clearing) once either
  /// whisker's S_c sum moves (RMS of its changes >= this, the node's phantom
  /// window): a touch TDORC has not flagged yet, so that the wall following
  /// starts at the heading it has without the offset. 0 = never. [Pa]
  double clear_yaw_release_rms = 13.0;
  /// The first approach (issue 17, docs/tuning/tactile_fsm.md "Round 10",
  /// "Round 12", choice): the first baffle is met with no clearing before it,
  /// so clear_yaw_offset has no side to turn to; its end can lie in the blind
  /// band (25-80 mm beside the axis) on either side. In the FLY_FORWARD before
  /// the flight's first contact the whiskers are scanned by
  /// first_whisk_amplitude about the course heading (step and scan, below).
  /// 0 = off (the paper's straight approach at V_max; the darkness scenarios,
  /// 000 Fig. 6). 0.44 rad: held out 16000-17299, docs/tuning/tactile_fsm.md
  /// "Round 12". [rad]
  double first_whisk_amplitude = 0.44;
  /// Step and scan on the first approach (issue 17, docs/tuning/tactile_fsm.md "Round 12", our
  /// choice; first_whisk_amplitude 0 turns it off): the first approach alternates steps of first_scan_step along the
  /// course (yaw on the course, the speed brought down to 0 at the step's end)
  /// and scans in place (yaw course -> +A -> -A -> course at first_scan_rate,
  /// A = first_whisk_amplitude, held while a whisker's sum moves,
  /// whisk_pause_rms). Yawed in place the whisker tips lie nearer than when
  /// straight, so a wall ahead is met in a step at the course heading and only
  /// an end beside the axis in a scan (round 10's continuous whisk while
  /// flying met walls ahead at a whisked yaw; removed, see the tuning history).
  /// >= 0.02 (the step ends 15 mm before its end). [m]
  double first_scan_step = 0.08;
  double first_scan_rate = 2.0;  ///< [rad/s], at most whisk_rate_max
  /// A baffle's end met by one whisker (issue 17, docs/tuning/tactile_fsm.md "Round 10", choice):
  /// a first touch in FLY_FORWARD by exactly one whisker whose contact point
  /// (the depth along the whisker, turned by the yaw off the course heading)
  /// lies more than end_contact_lateral beside the course axis on that
  /// whisker's side is taken for a baffle's end lying on that side (the
  /// whisked whisker reaching into the blind band): the wall following
  /// starts as when passing an edge (both touched), side-stepping away from
  /// it, instead of approaching it (which drove the guard into the end 65-75
  /// mm beside the axis). 0 = off. [m]
  double end_contact_lateral = 0.045;
  double target_radius = 0.15;                 ///< land within this distance of the target [m]
  bool land_past_target = true;                ///< also land once past the target along the course direction
  double landing_duration_s = 2.0;             ///< LANDING -> LANDED after this [s]
  double max_input_age_s = 0.2;                ///< depth/odometry older than this is stale [s] (10 ticks at 50 Hz)
  double failsafe_land_after_s = 2.0;          ///< FAILSAFE_HOVER -> FAILSAFE_LAND after this [s]

  /// Throws std::invalid_argument "WallFollowerParams.<field>: <reason>".
  void validate() const;
};

/// One tick of input. Stamps are on the same clock as t; NaN = never received.
struct WallFollowerInput {
  double t = 0.0;  ///< current time [s]
  // Tactile depth (TactileDepth, 000 eq. 12-30).
  double depth_stamp = NAN;
  bool left_valid = false;   ///< d_l measured (whisker in contact, finite)
  bool right_valid = false;
  double depth_left = NAN;   ///< d_l along body x from the whisker base to the wall [m]
  double depth_right = NAN;  ///< d_r [m]
  // TDORC contact flags (S_p over T_c, 000 eq. 4-11); false when stale.
  bool tdorc_contact_left = false;
  bool tdorc_contact_right = false;
  // Sum of the three S_c of each whisker (TDORC, 000 eq. 5) [Pa]; NaN = unknown/stale.
  double input_sum_left = NAN;
  double input_sum_right = NAN;
  // RMS of the sample-to-sample changes of that sum over the node's window [Pa]; NaN = unknown.
  double input_change_rms_left = NAN;
  double input_change_rms_right = NAN;
  // Odometry pose (world frame, REP-103).
  double odom_stamp = NAN;
  double x = 0.0, y = 0.0, yaw = 0.0;
  // Target position (world frame).
  bool has_target = false;
  double target_x = 0.0, target_y = 0.0;
};

/// Velocity-mode setpoint (Crazyflie hover setpoint).
struct Setpoint {
  double vx = 0.0;        ///< forward, body-yaw frame [m/s]
  double vy = 0.0;        ///< left [m/s]
  double yaw_rate = 0.0;  ///< counter-clockwise [rad/s]
  double height = 0.0;    ///< [m]
  bool land = false;
};

// --- Whisker ----------------------------------------------------------------
//
// One per side (issue 33): the per-whisker perception of the follower, in the
// order it runs on each tick: validity (fresh depth message, flagged valid,
// finite), the phantom gate, the low-pass of the depth and the pressed cap. It
// produces one WhiskerReading per tick, which the guards, the sub-state rule
// and the override rules read.

/// One whisker's side of a WallFollowerInput.
struct WhiskerSample {
  bool depth_fresh = false;       ///< the TactileDepth message is fresh (input_is_fresh, safety_runner.hpp)
  bool valid = false;             ///< its depth measured (whisker in contact)
  double depth = NAN;             ///< [m]
  bool tdorc_contact = false;     ///< TDORC contact flag (000 eq. 4-11)
  double input_sum = NAN;         ///< sum of the three S_c (000 eq. 5) [Pa]; NaN = unknown
  double input_change_rms = NAN;  ///< RMS of its sample-to-sample changes [Pa]; NaN = unknown
};

/// What one whisker reads on one tick.
struct WhiskerReading {
  bool held_raw = false;    ///< in contact as reported (valid depth or TDORC flag), before the phantom gate
  bool phantom = false;     ///< held but taken for a phantom: its depth and flag ignored
  bool valid = false;       ///< depth valid: fresh, flagged, finite and not a phantom
  bool contact = false;     ///< valid or TDORC-flagged, not a phantom (000 Methods: triggers wall following)
  double depth = NAN;       ///< the depth read, when valid (000 eq. 21's d) [m]
  double filtered = NAN;    ///< low-passed depth (depth_filter_tau_s), NaN when not valid [m]
  bool pressed = false;     ///< valid and its S_c sum >= press_sum_pa within press_hold_s
  double rule_depth = NAN;  ///< the sub-state rule's depth: filtered, at most press_depth when pressed [m]
};

/// One whisker's perception (the left or the right one; both run the same code).
class Whisker {
 public:
  explicit Whisker(const WallFollowerParams& p) : p_(p) {}
  /// One tick at time t, dt after the last. (x, y): the odometry position,
  /// `pose_ok` when it is fresh and finite (else the phantom gate is off
  /// this tick and no whisker is a phantom).
  const WhiskerReading& update(const WhiskerSample& s, double t, double dt, bool pose_ok, double x, double y);
  void reset();
  const WhiskerReading& reading() const { return reading_; }

 private:
  WallFollowerParams p_;
  double filtered_ = NAN;
  double pressed_t_ = -INFINITY;  ///< last tick with the sum >= press_sum_pa
  double live_x_ = NAN, live_y_ = NAN;  ///< where the S_c sum last moved (or the whisker was free)
  bool phantom_ = false;
  WhiskerReading reading_;
};

struct WallFollowerOutput {
  Setpoint setpoint;
  FsmState state = FsmState::kHoverInit;
  WallSubState sub_state = WallSubState::kNone;
  bool transitioned = false;  ///< the top-level state or sub-state changed this tick
  /// An override rule (OverrideRules) began to fire this tick; reason() names it.
  bool override_started = false;
};

/// The wall-following sub-state rule (000 Fig. S4e; the exact conditions are
/// only in the figure, this is our rule, derived in docs/whisker_fsm.md):
///  - both depths valid:
///    * both < T_min                         -> FLY_BACKWARD
///    * both > T_max                         -> FLY_FORWARD
///    * in different intervals (one out of the band): TURN toward
///      perpendicular (d_l > d_r -> TURN_RIGHT, d_l < d_r -> TURN_LEFT) while
///      |theta| > align_exit, theta = atan((d_l - d_r)/s) (000 eq. 21);
///      when already aligned, translate: the out-of-band depth says
///      FLY_FORWARD (> T_max) or FLY_BACKWARD (< T_min)
///    * both in [T_min, T_max]: TURN when |theta| > align_enter (or, already
///      turning, > align_exit), else FLY_SIDEWAYS
///  - one depth missing:
///    * before both whiskers touched in this episode (approach): the missing
///      one counts as beyond T_max (the rule above)
///    * after (whisker lost the wall): the remaining depth > wall_end_depth
///      (when on) -> the wall ends: FLY_SIDEWAYS; the leading whisker (in the
///      sideways direction) lost -> passing the edge: FLY_SIDEWAYS, or
///      FLY_BACKWARD if the remaining depth < T_min; the trailing one lost ->
///      as approach (or, hold_heading_trailing_lost, translate)
///  - none: FLY_SIDEWAYS (clearing is decided by the top level).
/// theta: wall angle estimate to use when both depths are valid; NaN = compute
/// it from the depths (000 eq. 21).
WallSubState wall_sub_state(double d_l, bool l_valid, double d_r, bool r_valid, Side side, bool both_touched,
                            WallSubState current, const WallFollowerParams& p, double theta = NAN);

/// |(vx, vy)| <= v_max (scaled, direction kept), |yaw_rate| <= omega_max,
/// non-finite values -> 0.
Setpoint saturate(const Setpoint& s, const WallFollowerParams& p);

/// One wall-following episode (000 Fig. S4e), the component both behaviours
/// that follow a wall run: the whisker wall follower in WALL_FOLLOWING and the
/// GPIS sequencer in FOLLOW_WALL (issue 33: one wall following, not two). It
/// holds what an episode remembers -- the side it slides toward, whether both
/// whiskers have touched, the current sub-state -- and gives the sub-state
/// rule on those (wall_sub_state()) and the sub-state's motion. What starts an
/// episode (which side, on what contact) and what ends it stay the
/// behaviour's: begin() starts one.
class WallFollowing {
 public:
  /// A new episode toward `side`; both_touched: the episode counts as one in
  /// which both whiskers already touched (an edge being passed).
  void begin(Side side, bool both_touched = false) {
    side_ = side;
    both_touched_ = both_touched;
    sub_ = WallSubState::kNone;
  }
  /// Both whiskers on the wall this tick: the episode's both_touched.
  void touched(bool left, bool right) { both_touched_ = both_touched_ || (left && right); }
  /// The sub-state rule (wall_sub_state()) on this tick's depths and the
  /// episode's side, both_touched and current sub-state; does not change it.
  WallSubState rule(double d_l, bool l_valid, double d_r, bool r_valid, const WallFollowerParams& p,
                    double theta = NAN) const {
    return wall_sub_state(d_l, l_valid, d_r, r_valid, side_, both_touched_, sub_, p, theta);
  }
  /// The sub-state the behaviour flies (the rule's, or an override's).
  void set_sub_state(WallSubState s) { sub_ = s; }
  /// The sub-state's motion (000 Fig. S4e): FLY_SIDEWAYS at V_max toward the
  /// side, FLY_FORWARD / FLY_BACKWARD at V_max / 2, TURN_LEFT / TURN_RIGHT at
  /// omega_max; sets that one field of *sp (kNone: none).
  void motion(const WallFollowerParams& p, Setpoint* sp) const;

  Side side() const { return side_; }
  bool both_touched() const { return both_touched_; }
  WallSubState sub_state() const { return sub_; }

 private:
  Side side_ = Side::kRight;
  bool both_touched_ = false;
  WallSubState sub_ = WallSubState::kNone;
};

// --- Override rules --------------------------------------------------------
//
// After the state switch and the sub-state rule, an ordered list of named
// rules may override what the state asked for (issue 33): first the two that
// replace a turn of the sub-state rule by a translation (heading limit, turn
// anchor), then, on the setpoint of the state, the two first-approach and
// after-clearing yaw rules (step and scan, yaw offset). Each reads one
// TickSnapshot, fires when applies() holds, then apply() changes the
// snapshot's sub-state or setpoint; WhiskerWallFollower counts the ticks each
// fired and, when one begins to fire (or its override changes the sub-state),
// publishes its reason. A later rule sees what the earlier ones left.

/// What the guards of the transition tables (before the state switch) and the
/// override rules (after it) read on one tick, and what the rules override.
/// l_valid / d_left (and the right ones) repeat left.valid / left.rule_depth
/// for the rules.
struct TickSnapshot {
  WallFollowerInput in;  ///< this tick's input (t, pose, S_c change RMS)
  double dt = 0.0;       ///< since the last tick [s]
  FsmState state = FsmState::kHoverInit;  ///< after this tick's state switch
  WallSubState current = WallSubState::kNone;  ///< sub-state of the last tick (turning or not)
  Side side = Side::kRight;                    ///< the followed side
  bool l_valid = false, r_valid = false;       ///< depths valid after the phantom gate
  double d_left = NAN, d_right = NAN;          ///< depths of the sub-state rule (filtered, pressed-capped) [m]
  double theta = NAN;         ///< wall angle of the rule (NaN unless both valid) [rad]
  double wall_heading = NAN;  ///< filtered yaw - theta [rad]
  bool origin_set = false;    ///< the course was set at the end of HOVER_INIT
  double origin_x = 0.0, origin_y = 0.0, course_yaw = 0.0;
  bool after_clear = false;  ///< FLY_FORWARD entered from RESUME_FORWARD
  bool contacted = false;    ///< wall following entered in this flight
  // Read by the guards of the transition table (before this tick's switch).
  WhiskerReading left, right;  ///< this tick's readings of the two Whiskers
  double entered = 0.0;        ///< when `state` was entered [s]
  double last_contact_t = 0.0; ///< last tick with a contact in WALL_FOLLOWING [s]
  double clear_x = 0.0, clear_y = 0.0;    ///< where the obstacle was cleared (RESUME_FORWARD's start)
  double resume_x = 0.0, resume_y = 0.0;  ///< where the FLY_FORWARD after the clearing began
  /// Overridden by the sub-state rules: the Fig. S4e rule's sub-state (kNone
  /// outside WALL_FOLLOWING); by the setpoint rules: the state's setpoint
  /// (after saturate()).
  WallSubState sub_state = WallSubState::kNone;
  Setpoint setpoint;
};

/// The translation the depths ask for when a turn is refused: FLY_BACKWARD
/// if a valid depth is below T_min, FLY_FORWARD if one is above T_max, else
/// FLY_SIDEWAYS.
WallSubState translation_instead_of_turn(const TickSnapshot& s, const WallFollowerParams& p);
/// s.sub_state is a turn that goes on beyond `limit` from the heading `ref`.
bool turns_beyond(const TickSnapshot& s, double ref, double limit);

/// Heading limit (issue 17; docs/whisker_fsm.md "Heading limit"): in wall
/// following, a turn that would take the heading further than
/// max_heading_offset from the course heading becomes the translation the
/// depths ask for.
class HeadingLimitRule {
 public:
  static constexpr const char* kName = "heading_limit";
  static constexpr const char* kReason = "heading limit: a turn beyond max_heading_offset from the course, translating";
  explicit HeadingLimitRule(const WallFollowerParams& p) : p_(p) {}
  void observe(const TickSnapshot&) {}
  bool applies(const TickSnapshot& s) const;
  void apply(TickSnapshot& s) const { s.sub_state = translation_instead_of_turn(s, p_); }
  void idle() {}
  void reset() {}

 private:
  WallFollowerParams p_;
};

/// Turn anchor (issue 17, docs/tuning/tactile_fsm.md "Round 13"): the wall
/// heading read at the first tick both whiskers touched, replaced by a clear
/// angle (|theta| >= turn_anchor_theta) read while not turning and crept
/// toward the heading read while not turning (turn_anchor_rate); a turn asked
/// for by a small angle that goes on beyond turn_anchor_tolerance from it
/// becomes the translation the depths ask for. observe() keeps the anchor
/// (NaN outside wall following: each wall following reads its own).
class TurnAnchorRule {
 public:
  static constexpr const char* kName = "turn_anchor";
  static constexpr const char* kReason = "turn anchor: a turn beyond turn_anchor_tolerance from the wall heading, translating";
  explicit TurnAnchorRule(const WallFollowerParams& p) : p_(p) {}
  void observe(const TickSnapshot& s);
  bool applies(const TickSnapshot& s) const;
  void apply(TickSnapshot& s) const { s.sub_state = translation_instead_of_turn(s, p_); }
  void idle() {}
  void reset() { anchor_ = NAN; }
  double anchor() const { return anchor_; }  ///< [rad]; NaN: none

 private:
  bool tracks(const TickSnapshot& s) const;  ///< the rule is on and both depths give a wall heading
  WallFollowerParams p_;
  double anchor_ = NAN;
};

/// Step and scan (issue 17, docs/tuning/tactile_fsm.md "Round 10", "Round
/// 12"): in the FLY_FORWARD before the flight's first contact (no clearing
/// yet), steps of first_scan_step along the course alternate with scans in
/// place (course -> +A -> -A -> course at first_scan_rate, A =
/// first_whisk_amplitude, held while a whisker's sum moves, whisk_pause_rms).
/// A tick it does not apply ends the scan: the next first approach starts
/// afresh.
class StepAndScanRule {
 public:
  static constexpr const char* kName = "step_and_scan";
  static constexpr const char* kReason = "step and scan on the first approach (first_whisk_amplitude, first_scan_step)";
  explicit StepAndScanRule(const WallFollowerParams& p) : p_(p) {}
  void observe(const TickSnapshot&) {}
  bool applies(const TickSnapshot& s) const;
  void apply(TickSnapshot& s);
  void idle() { goal_ = NAN; }
  void reset() { goal_ = NAN; }
  bool scanning() const { return scanning_; }

 private:
  void begin_scan(int leg);
  WallFollowerParams p_;
  // The step's end along the course [m] (NaN: not started; the rest is set when
  // it starts), scanning (else stepping), the scan's yaw reference off the
  // course [rad] and its leg (0: to +A, 1: to -A, 2: back to the course, 3: settling).
  double goal_ = NAN;
  bool scanning_ = false;
  double ref_ = 0.0;
  int leg_ = 0;
  double hold_s_ = 0.0;    ///< time this scan was held on a moving sum [s]
  double settle_s_ = 0.0;  ///< time in this scan's last leg [s]
};

/// Yaw offset after a clearing (issue 17, docs/tuning/tactile_fsm.md "Round
/// 9"): in the FLY_FORWARD after a clearing the body yaw is held
/// clear_yaw_offset away from the side-step side of the heading the drone
/// would otherwise fly (track unchanged); back to that heading once a
/// whisker's sum moves (clear_yaw_release_rms). A tick it does not apply
/// ends it.
class YawOffsetRule {
 public:
  static constexpr const char* kName = "yaw_offset";
  static constexpr const char* kReason = "yaw offset after a clearing (clear_yaw_offset)";
  explicit YawOffsetRule(const WallFollowerParams& p) : p_(p) {}
  void observe(const TickSnapshot&) {}
  bool applies(const TickSnapshot& s) const;
  void apply(TickSnapshot& s);
  void idle() { reset(); }
  void reset() {
    track_yaw_ = NAN;
    released_ = false;
  }
  bool released() const { return released_; }

 private:
  WallFollowerParams p_;
  double track_yaw_ = NAN;  ///< the heading the drone would fly without the offset [rad]
  bool released_ = false;   ///< clear_yaw_release_rms reached since the clearing
};

/// The override rules in the order they run.
enum class OverrideRule : uint8_t { kHeadingLimit, kTurnAnchor, kStepAndScan, kYawOffset };
constexpr std::size_t kOverrideRuleCount = 4;
/// "heading_limit", "turn_anchor", "step_and_scan", "yaw_offset".
const char* to_string(OverrideRule r);

// --- States and their transition tables ---------------------------------------
//
// Each state has an entry action (WhiskerWallFollower::on_entry), a tick
// (on_tick: what it keeps up to date) and an ordered table of {guard, next
// state, reason code, reason text}: the first row whose guard holds is taken,
// at most one transition per tick. The guards are named predicates on the
// tick's snapshot (before the switch). The fail-safe (stale depth or
// odometry in a flying state or at the end of HOVER_INIT -> FAILSAFE_HOVER,
// fresh again -> FLY_FORWARD, failsafe_land_after_s -> FAILSAFE_LAND) is the
// shared SafetyRunner's and runs before the tables.
namespace guards {
/// HOVER_INIT lasted hover_init_s (000 Methods "Hovering").
bool hover_done(const TickSnapshot& s, const WallFollowerParams& p);
/// Either whisker in contact after the phantom gate (000 Methods: S_p > T_c triggers wall following).
bool contact(const TickSnapshot& s, const WallFollowerParams& p);
/// A contact in RESUME_FORWARD: the same obstacle's end (its flags dropped early).
bool contact_while_clearing(const TickSnapshot& s, const WallFollowerParams& p);
/// A contact in the FLY_FORWARD after a clearing less than same_obstacle_distance
/// (along the course) from where it began: the same obstacle.
bool contact_same_obstacle(const TickSnapshot& s, const WallFollowerParams& p);
/// Lateral offset (left > 0) from the course axis of the contact point of the one
/// whisker in contact, on that whisker's side; 0 otherwise [m].
double end_contact_offset(const TickSnapshot& s, const WallFollowerParams& p);
/// A contact by one whisker more than end_contact_lateral beside the course axis: a baffle's end.
bool contact_at_baffle_end(const TickSnapshot& s, const WallFollowerParams& p);
/// RESUME_FORWARD side-stepped clear_margin from the clearing, and no whisker is
/// held (not even as a phantom) or phantom_resume_max is reached.
bool cleared_by_margin(const TickSnapshot& s, const WallFollowerParams& p);
/// No contact for clear_confirm_s in WALL_FOLLOWING.
bool obstacle_cleared(const TickSnapshot& s, const WallFollowerParams& p);
/// Within target_radius of the target or (land_past_target) past it along the course.
bool target_reached(const TickSnapshot& s, const WallFollowerParams& p);
/// LANDING lasted landing_duration_s.
bool landing_done(const TickSnapshot& s, const WallFollowerParams& p);
}  // namespace guards

/// One row of a state's transition table.
struct Transition {
  const char* guard_name;  ///< the guard's name (docs, tests)
  bool (*guard)(const TickSnapshot&, const WallFollowerParams&);
  FsmState next;
  WhiskerReason code;
  const char* text;  ///< reason() of the transition
};
/// A state's transition table, in the order the rows are tried.
struct TransitionTable {
  const Transition* rows = nullptr;
  std::size_t size = 0;
  const Transition* begin() const { return rows; }
  const Transition* end() const { return rows + size; }
};
/// The table of `s` (empty for LANDED and the fail-safe states, which the SafetyRunner drives).
TransitionTable transition_table(FsmState s);

class WhiskerWallFollower {
 public:
  explicit WhiskerWallFollower(const WallFollowerParams& params);

  /// One control tick. Ticks must have non-decreasing t.
  WallFollowerOutput step(const WallFollowerInput& in);
  void reset();

  FsmState state() const { return state_; }
  FsmState previous_state() const { return previous_; }
  WallSubState sub_state() const { return wall_.sub_state(); }
  /// Why the last top-level transition, sub-state change or override rule's
  /// onset happened: a transition's or rule's text, or both ("<transition>;
  /// <rule>") when a rule begins on a transition's tick. Valid until the next step().
  const char* reason() const { return reason_composed_ ? reason_buf_.data() : reason_; }
  /// The same as a tactile_msgs/FsmState REASON_* code: a WhiskerReason (30-49)
  /// or, for the fail-safe's transitions, the SafetyRunner's SafetyReason (1-7).
  /// When a rule begins on a transition's tick the transition's code stays.
  uint8_t reason_code() const { return reason_code_; }
  /// Ticks on which each override rule fired (index: OverrideRule), since reset().
  uint64_t override_count(OverrideRule r) const { return override_count_[static_cast<std::size_t>(r)]; }
  bool started() const { return started_; }
  double state_entered() const { return entered_; }
  uint32_t transitions() const { return transitions_; }
  Side active_side() const { return wall_.side(); }
  /// The two Whiskers' readings of the last tick.
  const WhiskerReading& left() const { return left_.reading(); }
  const WhiskerReading& right() const { return right_.reading(); }
  /// Low-pass filtered depths used by the rule (NaN when invalid).
  double filtered_left() const { return left().filtered; }
  double filtered_right() const { return right().filtered; }
  /// Whisker held in contact but taken for a phantom (phantom_quiet_rms) on the last tick.
  bool phantom_left() const { return left().phantom; }
  bool phantom_right() const { return right().phantom; }
  /// The shared fail-safe (depth, then odometry).
  const SafetyRunner& safety() const { return safety_; }
  /// Tests: puts a started follower into `s` at in.t (course set from `in` if
  /// not yet), running the state's entry action as for an entry with `code`;
  /// counted as a transition, reason "test". Not the fail-safe states (the
  /// SafetyRunner's, entered by a stale input): std::invalid_argument.
  void for_test_enter(FsmState s, const WallFollowerInput& in, WhiskerReason code = WhiskerReason::kNone);
  /// Wall angle in the body frame used by the rule [rad] (NaN unless both valid).
  double wall_angle() const { return theta_; }
  const WallFollowerParams& params() const { return p_; }

 private:
  void enter(FsmState s, const char* reason, uint8_t code, double t);
  /// Entry action of `s`, entered for `code` (some depend on the transition taken).
  void on_entry(FsmState s, const TickSnapshot& snap, uint8_t code);
  /// What a state keeps up to date on each tick, before its table.
  void on_tick(const TickSnapshot& snap);
  /// The snapshot's copy of the follower's state (the guards' and rules' view).
  void fill_snapshot(TickSnapshot& snap) const;
  void set_origin(const WallFollowerInput& in);
  Setpoint command(const WallFollowerInput& in) const;
  double realign(const WallFollowerInput& in) const;
  double realign_rate(double yaw) const;  ///< realign()'s rate toward the course from `yaw` (unsaturated)
  /// Runs one override rule on the snapshot: observe, then apply (counted) or idle.
  template <typename Rule>
  void run_rule(Rule& rule, OverrideRule id, TickSnapshot& s, bool top_transition);
  /// reason_ for a rule that fired on a sub-state change or began to fire this tick.
  void note_rule(const char* rule_reason, WhiskerReason code, bool top_transition);

  WallFollowerParams p_;
  FsmState state_ = FsmState::kHoverInit;
  FsmState previous_ = FsmState::kHoverInit;
  const char* reason_ = "start";
  uint8_t reason_code_ = 0;
  bool started_ = false;
  double entered_ = 0.0;
  double last_t_ = 0.0;
  uint32_t transitions_ = 0;
  /// The episode in WALL_FOLLOWING (side, both touched, sub-state; the
  /// sub-state is kNone in every other state).
  WallFollowing wall_;
  double last_contact_t_ = 0.0;
  Whisker left_, right_;
  SafetyRunner safety_;
  double wall_heading_ = NAN;  ///< filtered yaw - theta [rad]
  double theta_ = NAN;
  bool origin_set_ = false;
  double origin_x_ = 0.0, origin_y_ = 0.0;  ///< course start (end of hover)
  double course_yaw_ = 0.0;                   ///< heading at the course start [rad]
  double clear_x_ = 0.0, clear_y_ = 0.0;    ///< where the obstacle was cleared
  bool after_clear_ = false;                 ///< FLY_FORWARD entered from RESUME_FORWARD
  double resume_x_ = 0.0, resume_y_ = 0.0;  ///< where that FLY_FORWARD began
  bool contacted_ = false;  ///< wall following entered at least once in this flight (first_whisk_amplitude)
  // The override rules, in the order they run, with their firing record.
  HeadingLimitRule heading_limit_;
  TurnAnchorRule turn_anchor_;
  StepAndScanRule step_and_scan_;
  YawOffsetRule yaw_offset_;
  std::array<uint64_t, kOverrideRuleCount> override_count_{};
  std::array<bool, kOverrideRuleCount> override_active_{};  ///< fired on the last tick
  bool override_started_ = false;                           ///< a rule began to fire this tick
  std::array<char, 192> reason_buf_{};                      ///< "<transition>; <rule>" (no allocation)
  bool reason_composed_ = false;                            ///< reason() is reason_buf_, else reason_
};

}  // namespace tactile_fsm
