// XPLORER tactile behaviours (paper 001 Sec. III-B, IV): the admittance
// controller of eq. 8, the exploration state machine Gamma in {Exploration,
// Tactile-turning, Tactile-traversal} with the contact direction C_n and the
// move direction lambda (right-hand traversal), static-wrench application,
// and ricocheting (collision-inclusive waypoint flight, Gamma = 4) with its
// collision-recovery controller, next to conventional waypoint flight.
//
// Outputs position + yaw setpoints for the vehicle's cascaded P-PID
// controller (001 Fig. 2). World ENU, body FLU. Core layer: no ROS, no
// messages.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>

#include <Eigen/Geometry>

#include "tactile_common/body_direction.hpp"

namespace tactile_fsm {

using XVec2 = Eigen::Vector2d;
using XVec3 = Eigen::Vector3d;

// ---------------------------------------------------------------------------
// 001 eq. 8: admittance controller

struct AdmittanceParams {
  double virtual_mass = 1.0;     ///< m_v (001 Sec. V-A3)
  double virtual_inertia = 1.0;  ///< I_v,z (001 Sec. V-A3)
  /// diag(D), diag(K) over (x, y, z, yaw) (001 Sec. V-A3: 24.5, 24.5, 0, 1).
  std::array<double, 4> damping = {24.5, 24.5, 0.0, 1.0};
  std::array<double, 4> stiffness = {24.5, 24.5, 0.0, 1.0};
  void validate() const;  ///< throws std::invalid_argument "AdmittanceParams.<field>: <reason>"
};

/// m_v r_d'' + D r_d' + K (r_d - r*) = delta_f - delta_f_des (x, y);
/// I_v psi_d'' + D psi_d' + K (psi_d - psi*) = tau_z - tau_des (yaw).
/// An axis with D = K = 0 (z in 001) is not in admittance: r_d = r* there.
/// Semi-implicit Euler.
class AdmittanceController {
 public:
  explicit AdmittanceController(const AdmittanceParams& p = AdmittanceParams{});
  void reset(const XVec3& r, double yaw);
  /// Restarts the yaw row alone at `yaw`, at rest (the position row keeps its state).
  void reset_yaw(double yaw);
  /// One step; returns r_d (yaw: yaw()).
  const XVec3& update(const XVec3& force, const XVec3& force_des, const XVec3& r_star, double torque_z,
                      double torque_des, double yaw_star, double dt);
  const XVec3& position() const { return r_; }
  const XVec3& velocity() const { return v_; }
  double yaw() const { return yaw_; }

 private:
  AdmittanceParams p_;
  XVec3 r_ = XVec3::Zero(), v_ = XVec3::Zero();
  double yaw_ = 0.0, yaw_rate_ = 0.0;
};

// ---------------------------------------------------------------------------
// The behaviours

enum class XplorerMission { kExplore, kStaticWrench, kRicochet, kWaypoint };
const char* to_string(XplorerMission m);
XplorerMission mission_from_string(const std::string& s);  ///< "explore" | "static_wrench" | "ricochet" | "waypoint"

/// Gamma of 001 (1-4) plus take-off, hold and done.
enum class XplorerState {
  kTakeoff = 0,
  kExploration = 1,       ///< Gamma = 1
  kTactileTurning = 2,    ///< Gamma = 2
  kTactileTraversal = 3,  ///< Gamma = 3
  kRicocheting = 4,       ///< Gamma = 4
  kStaticWrench = 5,      ///< reaction mode 1 (001 Sec. III-B1)
  kGoTo = 6,              ///< flying to / regulating at a waypoint
  kDone = 7,              ///< loop closed: hold position
};
const char* to_string(XplorerState s);

/// Contact / move direction in the body frame: b1, -b1, b2, -b2 (001 Sec. IV-A), with
/// unit(), right_hand() (lambda: C_n turned by -90 deg) and contact_direction(), shared with
/// mapping_pcl's contact mapper (tactile_common/body_direction.hpp).
using tactile_common::BodyDirection;
using tactile_common::contact_direction;
using tactile_common::right_hand;
using tactile_common::unit;

/// Why the last transition happened (reason()'s text is for people; this is what programs
/// key on). The values are tactile_msgs/msg/FsmState's REASON_XPLORER_* (the node logic
/// checks that at compile time); kNewContact changes C_n inside Tactile-traversal without a
/// state change.
enum class XplorerReason : uint8_t {
  kNone = 0,                 ///< no transition yet
  kHoverHeightReached = 10,  ///< takeoff -> the mission's first state
  kContact = 11,             ///< Exploration -> Tactile-traversal / static wrench (delta_0)
  kContactSquareUp = 12,     ///< ... Tactile-traversal, squaring up to a face slid along first (square_*)
  kNewContact = 13,          ///< inside Tactile-traversal: a contact along lambda (concave corner) is the new C_n
  kYawRatePeak = 14,         ///< Tactile-traversal -> Tactile-turning (psi_dot_0, convex corner)
  kContactLostTurn = 15,     ///< Tactile-traversal -> Tactile-turning about the face's end (turn_on_contact_lost)
  kContactLost = 16,         ///< Tactile-traversal -> Exploration
  kContactLostSquaring = 17, ///< Tactile-traversal (squaring up) -> Exploration
  kReContact = 18,           ///< Tactile-turning -> Tactile-traversal (delta_psi0)
  kTurnLimit = 19,           ///< Tactile-turning -> Exploration: no re-contact
  kLoopClosed = 20,          ///< -> done (001 Sec. V-C2)
  kCollisionRecovered = 21,  ///< Ricocheting -> goto (001 Sec. IV-C)
  kGoalPassed = 22,          ///< Ricocheting -> goto: no collision
};
const char* to_string(XplorerReason r);  ///< snake-case name: "contact_lost_turn", ...

struct XplorerParams {
  XplorerMission mission = XplorerMission::kExplore;
  double hover_height = 0.7;         ///< [m] (001 Sec. V-C: "hover height of 0.7 m")
  double takeoff_tolerance = 0.05;   ///< [m] (choice)
  double explore_speed = 0.3;        ///< forward speed in Exploration [m/s] (choice)
  double traverse_speed = 0.15;      ///< speed along lambda in Tactile-traversal [m/s] (choice)
  double position_gain = 1.5;        ///< P gain of the vehicle's position loop [1/s]: turns speeds into setpoint leads (choice, SITL controller)
  int force_average_samples = 50;    ///< moving average of the body force (001 Sec. V-C)
  double delta_0 = 1.5;              ///< contact threshold [N] (001 Sec. V-C)
  double delta_psi0 = 1.6;           ///< re-contact threshold ending Tactile-turning [N] (> delta_0, 001 Sec. IV-A; value a choice)
  double yaw_rate_trigger = 0.4;     ///< psi_dot_0 [rad/s] (001 Sec. V-C)
  double yaw_rate_lowpass_hz = 2.0;  ///< low-pass of the yaw rate (choice; 001 Sec. V-C)
  double turn_rate = 0.26;           ///< controlled yaw rate in Tactile-turning [rad/s] (001 Sec. V-C)
  double turn_limit = M_PI;          ///< |yaw change| limit of one turn [rad] (001: 180 deg)
  double turn_push = 0.05;           ///< setpoint lead towards C_n while turning [m] (choice; turn_pivot false)
  /// true: Tactile-turning pivots about the corner (001 Sec. IV-A "turning around a point"):
  /// the face (its normal C_n and yaw) is taken from before the release, the pivot on the
  /// face in front of the vehicle, and the setpoint orbits the pivot at turn_radius while
  /// the yaw setpoint turns at turn_rate, so the contact torque of the guard sliding off
  /// the edge and the push stored in the position loop no longer spin the vehicle into the
  /// next face. false: the previous rule (push turn_push along C_n, lead along lambda,
  /// C_n turning with the measured yaw) (choice; docs/tuning/tactile_fsm.md "Convex corners").
  bool turn_pivot = true;
  double contact_reach = 0.21;       ///< centre -> edge of the vehicle along a body axis [m] (001 Sec. IV-B: 0.21 m)
  double turn_radius = 0.15;         ///< orbit radius about the pivot [m] (< contact_reach: the guards meet the next face) (choice)
  /// While turning, the vehicle also moves along lambda at traverse_speed, from where it
  /// is (behind the corner) to turn_slide past the pivot: the pivot ends at the trailing
  /// guard, so both front guards meet the next face (a single guard pressed alone
  /// yaws the vehicle back round the corner) (choice).
  double turn_slide = 0.2;           ///< [m] (choice)
  /// The orbit starts turn_backoff further out and closes to turn_radius with time
  /// constant turn_backoff_tau: the push the position loop stored against the face
  /// (its velocity integrator) is released at the corner; a setpoint behind the vehicle
  /// takes it out instead of letting it carry the vehicle into the corner (choice).
  double turn_backoff = 0.2;         ///< [m] (choice)
  double turn_backoff_tau = 1.5;     ///< [s] (choice)
  double corner_lookback = 0.6;      ///< the face pose is taken this long before the yaw-rate trigger [s] (choice)
  double contact_force = 1.25;       ///< |delta_f_des| in traversal [N] (choice: 001 gives no value)
  /// r* along C_n is "reshaped according to the external wrench" (001 Sec.
  /// III-B1): r*_n += reshape_gain (delta_f - delta_f_des).n dt, so the force
  /// error integrates to zero whatever the contact stiffness [m/(N s)] (choice).
  double reshape_gain = 0.1;
  double reshape_limit = 0.3;        ///< |r*_n - p_n| limit [m] (choice)
  /// false: r* is a world point whose coordinate along C_n is reshaped (fine
  /// while C_n keeps its direction: planar faces, the box); true: only the
  /// offset along C_n is kept and carried with the vehicle as C_n turns with
  /// the yaw, which a curved surface (pipe, bin) needs: there a stale world
  /// point projected onto the turning C_n drives r* into the surface and the
  /// force up until contact breaks. Default true since the corner pivot: the
  /// box then does as well as with false, so one setting serves faces and
  /// cylinders (choice; docs/tuning/tactile_fsm.md "Convex corners").
  bool reshape_follows_contact = true;
  double release_force = 0.3;        ///< averaged |force| below which contact is lost [N] (choice)
  double release_time = 1.0;         ///< ... for this long -> Exploration [s] (choice)
  double settle_time = 1.0;          ///< no turning trigger this long after a contact / turn [s] (choice)
  double loop_closure_radius = 0.25; ///< back within this of the first contact point -> done [m] (choice)
  double loop_min_path = 2.0;        ///< ... after at least this much traversed path [m] (choice)
  /// ... and after the vehicle's yaw has wound by at least this much since the first
  /// contact, counted in the right-hand traversal's sense (counter-clockwise): going once
  /// round a convex object turns the heading by 2 pi; wobbling at one corner does not
  /// (issue 17: a false closure after 3.8 m round one corner wound by -235 deg, true
  /// closures 261-383 deg) [rad] (choice; 0: off).
  double loop_min_winding = M_PI;
  /// Loop closure also inside Tactile-turning once the heading has wound by at least this
  /// much (issue 17: a first contact next to a convex corner is passed again inside the
  /// turn at that corner, the closure tested only in traversal misses it and the next lap
  /// runs out of time, 13020: within 0.25 m for 5 s at 305 deg). Below a full circuit it
  /// keeps the earlier turns' orbits from closing early [rad] (choice, on at 5.5 = 315 deg
  /// since 2026-11-27, docs/tuning/tactile_fsm.md "Open loops on the held-out blocks"; 0: off, closure only in
  /// traversal).
  double loop_turn_min_winding = 5.5;
  /// Right-hand traversal round a convex object turns counter-clockwise at every convex
  /// corner. A clockwise yaw-rate peak starts a clockwise Tactile-turning (001 Sec. IV-A:
  /// "in the direction of the peak") only while fewer than this many clockwise turns came
  /// since the last counter-clockwise one; otherwise the traversal goes on. One such turn
  /// re-aligns the vehicle after an oblique contact (issue 17: seeds 2031, 1024, 2002 close
  /// their loops through one); two in a row cycle round one corner point (seeds 1036: 7,
  /// 2028: 3 clockwise turns of 130-142 deg, open or a false closure) (choice; 0: never,
  /// a large number: always).
  int max_clockwise_turns_in_a_row = 1;
  /// Contact lost (release_force for release_time) in a traversal that has lasted at least
  /// contact_lost_turn_min_s: the face ended without a yaw-rate peak (an obtuse convex
  /// corner the admittance yaw followed slowly), so Tactile-turning counter-clockwise about
  /// the face's end (the pivot from the pose when the force went) instead of Exploration
  /// along the lost C_n, which flies past a convex corner (issue 17: seed 1036 flew 20 m
  /// off, 2007 hit the next face at 5-15 N and stuck). Contact lost 2.4-3.1 s into a
  /// traversal (the contact never settled after an impact: 16 of 20 losses on the tuning
  /// seeds) still goes back to Exploration (choice; false: always Exploration). The turn
  /// orbits a pivot, so it needs turn_pivot; without it a lost contact always goes back to
  /// Exploration.
  bool turn_on_contact_lost = true;
  double contact_lost_turn_min_s = 4.0;  ///< [s]
  /// Back-off on contact from Exploration (entering Tactile-traversal or the static wrench):
  /// the collision-recovery reaction of 001 Sec. III-B3 ("a setpoint away from the collision
  /// direction, proportional to the collision intensity", ref. [12]) applied to the impact
  /// that ends Exploration. For contact_backoff_time s the setpoint is the vehicle's position
  /// at the contact plus contact_backoff_gain |delta_f| (the fused force of the contact tick)
  /// along the measured force (out of the obstacle), capped at contact_backoff_max, at hover
  /// height with the yaw held; then the traversal (or the wrench) starts from where the
  /// vehicle is. Using it at first contact is our choice: it takes out the approach momentum
  /// the position loop carries into the face (issue 17; docs/tuning/tactile_fsm.md "Transition ticks and the
  /// contact back-off"). contact_backoff_time 0: off (the traversal starts at once).
  double contact_backoff_gain = 0.04;  ///< [m/N] (choice, tuned; recovery_gain is 0.02)
  double contact_backoff_max = 0.15;   ///< [m] (choice)
  double contact_backoff_time = 0.3;   ///< [s] (choice, as recovery_time; 0: off)
  /// Square up to a face slid along in Exploration (issue 17, class B open loops; docs/tuning/tactile_fsm.md
  /// "Oblique first face: squaring up to the face slid along"). 001 keeps the yaw in
  /// admittance "ensuring two arms of the UAV are in contact with the obstacle" (Sec. V-C1);
  /// on a face at ~40-50 deg to the approach the force on the leading arm points nearly
  /// through the centre, gives no yaw torque, and the vehicle slides along the face with the
  /// approach yaw until the per-axis average crosses delta_0 (both axes read ~1 N). The
  /// traversal, C_n and the turn at the next corner then work in body axes 40 deg off the
  /// face and the turn orbits in the wrong frame. Rule (our choice): on the contact that
  /// ends Exploration, if the vehicle's path over the last square_window s deviates from the
  /// Exploration direction by at least square_min_deflection (it was deflected along the
  /// face: its direction is the face's tangent, to 0.4-2.5 deg on the class B seeds, where the
  /// averaged force, tilted by friction, was 1-25 deg off the normal), C_n is the body axis
  /// nearest to the face normal (the normal perpendicular to the path on the force's side)
  /// and the traversal first yaws at turn_rate (001's controlled yaw rate, Sec. V-C) to put
  /// that axis on the normal, holding the contact along the face's normal without moving
  /// along it; then the traversal goes on as before. square_min_deflection 0: off.
  double square_min_deflection = 0.35;  ///< [rad] (choice, 20 deg, on since 2026-11-27; 0: off)
  double square_window = 1.0;          ///< path window before the contact [s] (choice; the force average's 1 s)
  double square_min_path = 0.1;        ///< ... at least this long [m] (choice)
  double square_hold = 1.0;            ///< after the yaw ramp, hold the squared yaw setpoint this long before the traversal [s] (choice)
  /// true: C_n is body +X, the Exploration axis (the frame of a square first contact, 001
  /// Sec. V-C2: move along body +x, contact, traverse along -y), up to 90 deg of yaw; false:
  /// the body axis nearest to the normal (at most 45 deg) (choice).
  bool square_to_x = true;
  double static_force = 1.0;         ///< static-wrench reference |delta_f_ref| [N] (001 Sec. V-B)
  XVec2 goal = XVec2(1.0, 0.0);      ///< ricochet / waypoint goal, world [m]
  double ricochet_speed = 1.5;       ///< approach speed [m/s] ("maximum velocity", 001 Sec. IV-C; the SITL controller's limit)
  double collision_force = 2.5;      ///< |delta_f| that marks a collision [N] (choice)
  double restitution = 0.2;          ///< post-collision normal speed / pre-collision (001 Fig. 7: 0-1.5 m/s -> ~0.3 m/s) (choice)
  double recovery_gain = 0.02;       ///< recovery setpoint distance per N of collision peak [m/N] (choice, after 001 ref. [12])
  double recovery_time = 0.3;        ///< hold the recovery setpoint this long [s] (choice)
  AdmittanceParams admittance;
  void validate() const;
};

/// One control tick's input (50 Hz).
struct XplorerInput {
  double t = 0.0;                    ///< [s]
  XVec3 position = XVec3::Zero();    ///< world [m]
  XVec3 velocity = XVec3::Zero();    ///< world [m/s]
  double yaw = 0.0;                  ///< [rad]
  double yaw_rate = 0.0;             ///< [rad/s]
  XVec3 force = XVec3::Zero();       ///< fused external force estimate, world [N] (001 eq. 7)
  double torque_z = 0.0;             ///< external yaw torque estimate [N m]
};

struct XplorerOutput {
  XVec3 position = XVec3::Zero();  ///< setpoint, world [m]
  double yaw = 0.0;                ///< setpoint [rad]
  XplorerState state = XplorerState::kTakeoff;
  bool transitioned = false;
};

/// Post-collision velocity model for ricocheting (001 Sec. IV-C, Fig. 7):
/// the normal component is reversed and scaled by e, the tangential kept.
XVec2 post_collision_velocity(const XVec2& v_pre, const XVec2& normal, double restitution);

class XplorerExplorer {
 public:
  explicit XplorerExplorer(const XplorerParams& p);
  XplorerOutput update(const XplorerInput& in, double dt);
  /// Puts the FSM directly into state s at the input's pose and runs its entry action, as
  /// its transitions would (tests: each state's transitions alone). `contact` is C_n for
  /// Tactile-traversal, Tactile-turning and the static wrench (lambda its right-hand
  /// move direction); a Tactile-turning turns counter-clockwise about the corner of a
  /// face at the input's pose. Entered as from Exploration, so a traversal or static
  /// wrench starts with its contact back-off (contact_backoff_time) as after a first
  /// contact. Returns the entry tick's output.
  XplorerOutput for_test_enter(XplorerState s, const XplorerInput& in, BodyDirection contact = BodyDirection::kPlusX);

  // Named guards: the conditions of the transitions, in update()'s order within each
  // state (public: tested alone). t is the FSM's clock [s].
  /// Takeoff -> the mission's first state: |z - hover_height| < takeoff_tolerance.
  bool at_hover_height(const XplorerInput& in) const;
  /// Exploration -> Tactile-traversal / static wrench (001 Sec. IV-A): the averaged body
  /// force's direction beyond delta_0, BodyDirection::kNone below it.
  BodyDirection contact_detected() const;
  /// Tactile-traversal -> Tactile-turning (001 Sec. IV-A): |low-passed yaw rate| >
  /// yaw_rate_trigger, settle_time after the last contact or turn ...
  bool yaw_rate_peak(double t) const;
  /// ... unless it is a clockwise peak after max_clockwise_turns_in_a_row of them.
  bool peak_against_the_traversal() const;
  /// Contact lost (Tactile-traversal, squaring up): the averaged force below
  /// release_force for more than release_time.
  bool released(double t) const;
  /// ... in a traversal of at least contact_lost_turn_min_s with turn_on_contact_lost
  /// and turn_pivot: turn about the face's end instead of exploring on.
  bool turns_about_the_faces_end(double t) const;
  /// Tactile-turning -> Tactile-traversal (001 Sec. IV-A): |b_delta_f_x| or |b_delta_f_y| >
  /// delta_psi0, settle_time after the turn began.
  bool re_contact(double t) const;
  /// Tactile-turning -> Exploration: turn_limit / turn_rate + 3 s without a re-contact.
  bool turn_limit_passed(double t) const;
  /// Ricocheting -> GoTo (001 Sec. IV-C): recovery_time after the collision's peak began.
  bool recovered(double t) const;
  /// Ricocheting -> GoTo: 0.3 m past the goal along the line from the start, no collision.
  bool goal_passed(const XVec2& p2) const;
  /// Tactile-traversal (or a late turn) -> Done (001 Sec. V-C2): back within
  /// loop_closure_radius of the first contact after loop_min_path and the heading wound.
  bool loop_closes(const XVec2& p2) const;

  XplorerState state() const { return state_; }
  BodyDirection contact() const { return contact_; }
  BodyDirection move() const { return move_; }
  const XVec2& body_force() const { return f_body_avg_; }  ///< 50-sample moving average
  double filtered_yaw_rate() const { return yaw_rate_f_; }
  const std::string& reason() const { return reason_; }  ///< human readable; programs use reason_code()
  XplorerReason reason_code() const { return reason_code_; }
  double time_in_state(double t) const { return t - t_enter_; }
  uint32_t transitions() const { return transitions_; }
  bool loop_closed() const { return loop_closed_; }
  double loop_closure_time() const { return loop_closure_t_; }
  double first_contact_time() const { return first_contact_t_; }
  double traversed_path() const { return path_; }
  double winding() const { return winding_; }  ///< yaw turned since the first contact, counter-clockwise positive [rad]
  uint32_t turns_against() const { return turns_against_; }  ///< clockwise yaw-rate peaks ignored (max_clockwise_turns_in_a_row)
  uint32_t turns() const { return turns_; }
  const XVec2& pivot() const { return pivot_; }  ///< corner pivot of the last Tactile-turning (turn_pivot)
  uint32_t collisions() const { return collisions_; }
  uint32_t backoffs() const { return backoffs_; }  ///< contact back-offs flown (contact_backoff_*)
  uint32_t squarings() const { return squarings_; }  ///< squarings up to a face slid along (square_*)
  bool squaring() const { return squaring_; }
  double square_target_yaw() const { return square_yaw_; }
  bool backing_off(double t) const { return t < backoff_until_; }
  double collision_peak() const { return collision_peak_; }
  const XplorerParams& params() const { return p_; }

 private:
  /// The transition to `s`: the common bookkeeping, then `s`'s entry action (its set-up and
  /// the setpoint of this tick, written to `out`). Entering Tactile-traversal or the static
  /// wrench from Exploration starts the contact back-off, and the traversal may square up
  /// first (why becomes kContactSquareUp); Tactile-turning needs pivot_, face_*, phi0_ and
  /// turn_sign_ set before (plan_turn).
  void enter(XplorerState s, XplorerReason why, const XplorerInput& in, XplorerOutput& out);
  std::string reason_text(XplorerReason why) const;
  /// The Tactile-turning's corner from the face pose (yaw, position) before the release.
  void plan_turn(double sign, double face_yaw, const XVec2& face_p, const XplorerInput& in);
  // One control tick of each state: its setpoint in `out`, or a transition (enter()).
  void tick_takeoff(const XplorerInput& in, XplorerOutput& out);
  void tick_exploration(const XplorerInput& in, XplorerOutput& out);
  void tick_traversal(const XplorerInput& in, double dt, XplorerOutput& out);
  /// Tactile-traversal's squaring-up phase (square_*); false once squared (the traversal goes on this tick).
  bool tick_squaring(const XplorerInput& in, double dt, XplorerOutput& out);
  void tick_turning(const XplorerInput& in, XplorerOutput& out);
  void tick_static_wrench(const XplorerInput& in, double dt, XplorerOutput& out);
  void tick_ricochet(const XplorerInput& in, XplorerOutput& out);
  double reshape(const XVec2& n, const XVec2& p, const XVec3& force, const XVec3& f_des, double dt);
  void start_backoff(const XplorerInput& in);
  bool plan_square(const XplorerInput& in);  ///< square_*: sets contact_, move_ and the squaring's yaw
  void hold_backoff(const XplorerInput& in, XplorerOutput& out);  ///< publishes backoff_sp_, holds the traversal state
  XVec3 turning_setpoint(const XplorerInput& in, double* yaw) const;

  XplorerParams p_;
  AdmittanceController adm_;
  XplorerState state_ = XplorerState::kTakeoff;
  BodyDirection contact_ = BodyDirection::kNone, move_ = BodyDirection::kNone;
  std::deque<XVec2> forces_;
  XVec2 f_sum_ = XVec2::Zero(), f_body_avg_ = XVec2::Zero();
  double yaw_rate_f_ = 0.0;
  bool have_rate_ = false;
  double t_enter_ = 0.0, t_quiet_ = -1e9, low_force_since_ = -1.0;
  double yaw_enter_ = 0.0, turn_sign_ = 1.0;
  XVec2 explore_dir_ = XVec2(1, 0);
  XVec3 hold_ = XVec3::Zero();
  double hold_yaw_ = 0.0;
  std::string reason_;
  XplorerReason reason_code_ = XplorerReason::kNone;
  uint32_t transitions_ = 0, turns_ = 0, collisions_ = 0, turns_against_ = 0;
  int clockwise_in_a_row_ = 0;
  bool loop_closed_ = false, started_path_ = false, initialised_ = false, peak_against_ = false;
  double loop_closure_t_ = -1.0, first_contact_t_ = -1.0, path_ = 0.0, collision_peak_ = 0.0;
  double winding_ = 0.0, last_yaw_ = 0.0, lost_yaw_ = 0.0;
  XVec2 lost_p_ = XVec2::Zero();
  XVec2 first_contact_p_ = XVec2::Zero(), last_p_ = XVec2::Zero();
  XVec2 collision_normal_ = XVec2::Zero();
  XVec3 recovery_sp_ = XVec3::Zero();
  XVec2 r_star_ = XVec2::Zero();  ///< reshaped setpoint r* (x-y) in contact states
  XVec3 backoff_sp_ = XVec3::Zero();  ///< contact back-off setpoint (contact_backoff_*)
  double backoff_until_ = -1e9;
  uint32_t backoffs_ = 0;
  struct PoseSample {
    double t;
    XVec2 p;
    double yaw;
  };
  /// Appends `s` and drops the samples older than `window` s, keeping one at or beyond it.
  static void push_window(std::deque<PoseSample>& h, const PoseSample& s, double window);
  std::deque<PoseSample> traverse_history_;  ///< last corner_lookback s of Tactile-traversal
  std::deque<PoseSample> explore_history_;   ///< last square_window s of Exploration
  bool squaring_ = false;
  double square_yaw0_ = 0.0, square_yaw_ = 0.0, square_t0_ = 0.0;
  uint32_t squarings_ = 0;
  XVec2 pivot_ = XVec2::Zero(), face_n_ = XVec2(1, 0), face_t_ = XVec2(0, -1);
  double face_yaw_ = 0.0, phi0_ = 0.0;
};

}  // namespace tactile_fsm
