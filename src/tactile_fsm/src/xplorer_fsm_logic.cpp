#include "tactile_fsm/xplorer_fsm_logic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace tactile_fsm {

using tactile_common::ParamMap;
using tactile_msgs::msg::FsmState;

// The core's codes are the message's (FsmState.msg documents them): a cast publishes them.
static_assert(static_cast<uint8_t>(XplorerReason::kNone) == FsmState::REASON_NONE);
static_assert(static_cast<uint8_t>(XplorerReason::kHoverHeightReached) == FsmState::REASON_XPLORER_HOVER_HEIGHT_REACHED);
static_assert(static_cast<uint8_t>(XplorerReason::kContact) == FsmState::REASON_XPLORER_CONTACT);
static_assert(static_cast<uint8_t>(XplorerReason::kContactSquareUp) == FsmState::REASON_XPLORER_CONTACT_SQUARE_UP);
static_assert(static_cast<uint8_t>(XplorerReason::kNewContact) == FsmState::REASON_XPLORER_NEW_CONTACT);
static_assert(static_cast<uint8_t>(XplorerReason::kYawRatePeak) == FsmState::REASON_XPLORER_YAW_RATE_PEAK);
static_assert(static_cast<uint8_t>(XplorerReason::kContactLostTurn) == FsmState::REASON_XPLORER_CONTACT_LOST_TURN);
static_assert(static_cast<uint8_t>(XplorerReason::kContactLost) == FsmState::REASON_XPLORER_CONTACT_LOST);
static_assert(static_cast<uint8_t>(XplorerReason::kContactLostSquaring) == FsmState::REASON_XPLORER_CONTACT_LOST_SQUARING);
static_assert(static_cast<uint8_t>(XplorerReason::kReContact) == FsmState::REASON_XPLORER_RE_CONTACT);
static_assert(static_cast<uint8_t>(XplorerReason::kTurnLimit) == FsmState::REASON_XPLORER_TURN_LIMIT);
static_assert(static_cast<uint8_t>(XplorerReason::kLoopClosed) == FsmState::REASON_XPLORER_LOOP_CLOSED);
static_assert(static_cast<uint8_t>(XplorerReason::kCollisionRecovered) == FsmState::REASON_XPLORER_COLLISION_RECOVERED);
static_assert(static_cast<uint8_t>(XplorerReason::kGoalPassed) == FsmState::REASON_XPLORER_GOAL_PASSED);
static_assert(static_cast<uint8_t>(BodyDirection::kNone) == FsmState::DIRECTION_NONE);
static_assert(static_cast<uint8_t>(BodyDirection::kPlusX) == FsmState::DIRECTION_PLUS_X);
static_assert(static_cast<uint8_t>(BodyDirection::kMinusX) == FsmState::DIRECTION_MINUS_X);
static_assert(static_cast<uint8_t>(BodyDirection::kPlusY) == FsmState::DIRECTION_PLUS_Y);
static_assert(static_cast<uint8_t>(BodyDirection::kMinusY) == FsmState::DIRECTION_MINUS_Y);

void XplorerFsmLogic::Params::validate() const {
  fsm.validate();
  if (frame_id.empty()) throw std::invalid_argument("XplorerFsmLogic.frame_id: must not be empty");
  safety.validate("XplorerFsmLogic");  // max_input_age_s finite > 0, failsafe_land_after_s finite >= 0
  if (!(failsafe_land_speed > 0.0) || !std::isfinite(failsafe_land_speed)) {
    throw std::invalid_argument("XplorerFsmLogic.failsafe_land_speed: must be finite and > 0, got " +
                                std::to_string(failsafe_land_speed));
  }
}

ParamMap XplorerFsmLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::closed;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  const Params d;
  const XplorerParams& f = d.fsm;
  ParamMap m(kNodeName, "defaults");
  // The node's parameter spec (config/xplorer_fsm.yaml, docs/xplorer_fsm.md): value,
  // description (from the XplorerParams comments; "choice" where 001 gives no value), unit
  // and the range params_from()/validate() accept for the key alone (delta_psi0 > delta_0 is
  // validate()'s relation, named in the text). Every key is read at start (ros2 param set:
  // read-only): the admittance state, the force average and the traversal's corner, loop and
  // contact bookkeeping are built from them.
  m.set("mission", std::string(to_string(f.mission)),
        {"explore (001 Sec. IV-A), static_wrench (Sec. III-B1 / V-B), ricochet (Sec. IV-C / V-E) or waypoint "
         "(the comparison)", "", {}, false,
         tactile_common::paper("001 Sec. IV-A (explore), III-B1 / V-B (static_wrench), IV-C / V-E (ricochet)")});
  m.set("hover_height", f.hover_height, {"take-off and hover height (001 Sec. V-C: 0.7 m)", "m", positive(), false,
        tactile_common::paper("001 Sec. V-C: 0.7 m")});
  m.set("takeoff_tolerance", f.takeoff_tolerance, {"take-off done within this of hover_height (choice)", "m",
                                                   positive(), false, tactile_common::choice()});
  m.set("explore_speed", f.explore_speed, {"Exploration speed along body +x (choice)", "m/s", positive(), false,
        tactile_common::choice()});
  m.set("traverse_speed", f.traverse_speed,
        {"Tactile-traversal speed along lambda (choice)", "m/s", positive(), false, tactile_common::choice()});
  m.set("position_gain", f.position_gain,
        {"P gain of the vehicle's position loop: turns speeds into setpoint leads (choice, SITL controller)", "1/s",
         positive(), false, tactile_common::choice("the SITL controller")});
  m.set("force_average_samples", static_cast<int64_t>(f.force_average_samples),
        {"moving average of the body force (001 Sec. V-C: 50)", "", closed(1, std::numeric_limits<int>::max()), false,
         tactile_common::paper("001 Sec. V-C: 50 samples")});
  m.set("delta_0", f.delta_0, {"delta_0, contact threshold on the averaged body force (001 Sec. V-C: 1.5 N)", "N",
                               positive(), false, tactile_common::paper("001 Sec. V-C: 1.5 N")});
  m.set("delta_psi0", f.delta_psi0,
        {"delta_psi0, re-contact threshold ending Tactile-turning (001 Sec. IV-A; value a choice); > delta_0", "N",
         positive(), false, tactile_common::choice("001 Sec. IV-A names delta_psi0, not its value")});
  m.set("yaw_rate_trigger", f.yaw_rate_trigger,
        {"psi_dot_0, low-passed yaw rate that starts Tactile-turning at a convex corner (001 Sec. V-C: 0.4 rad/s)",
         "rad/s", positive(), false, tactile_common::paper("001 Sec. V-C: 0.4 rad/s")});
  m.set("yaw_rate_lowpass_hz", f.yaw_rate_lowpass_hz,
        {"cut-off of the yaw-rate low-pass (choice; 001 Sec. V-C)", "Hz", positive(), false, tactile_common::choice()});
  m.set("turn_rate", f.turn_rate,
        {"controlled yaw rate in Tactile-turning (001 Sec. V-C: 0.26 rad/s)", "rad/s", positive(), false,
         tactile_common::paper("001 Sec. V-C: 0.26 rad/s")});
  m.set("turn_limit", f.turn_limit,
        {"|yaw change| limit of one turn (001 Sec. IV-A: 180 deg)", "rad", ParamRange{0.0, M_PI, true, false}, false,
         tactile_common::paper("001 Sec. IV-A: 180 deg")});
  m.set("turn_push", f.turn_push,
        {"setpoint lead towards C_n while turning, with turn_pivot false (choice)", "m", positive(), false,
         tactile_common::choice("with turn_pivot false")});
  m.set("turn_pivot", f.turn_pivot,
        {"Tactile-turning orbits a pivot on the corner (001 Sec. IV-A \"turning around a point\"; choice); false: "
         "push turn_push along C_n", "", {}, false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": corner pivot, the paper's box 4/5 -> 5/5 loops")});
  m.set("contact_reach", f.contact_reach,
        {"centre -> edge of the vehicle along a body axis (001 Sec. IV-B: 0.21 m)", "m", positive(), false,
         tactile_common::paper("001 Sec. IV-B: 0.21 m")});
  m.set("turn_radius", f.turn_radius,
        {"orbit radius about the corner pivot, < contact_reach so the guards meet the next face (choice)", "m",
         positive(), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": corner pivot, the paper's box 4/5 -> 5/5 loops")});
  m.set("turn_slide", f.turn_slide,
        {"while turning, move along lambda to this far past the pivot (choice)", "m", at_least(0.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": corner pivot, the paper's box 4/5 -> 5/5 loops")});
  m.set("turn_backoff", f.turn_backoff,
        {"the orbit starts this much further out, releasing the push stored against the face (choice)", "m",
         at_least(0.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": corner pivot, the paper's box 4/5 -> 5/5 loops")});
  m.set("turn_backoff_tau", f.turn_backoff_tau,
        {"... and closes to turn_radius with this time constant (choice)", "s", positive(), false,
         tactile_common::choice()});
  m.set("corner_lookback", f.corner_lookback,
        {"the face pose is taken this long before the yaw-rate trigger (choice)", "s", at_least(0.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": corner pivot, the paper's box 4/5 -> 5/5 loops")});
  m.set("contact_force", f.contact_force,
        {"|delta_f_des|, desired contact force in Tactile-traversal (choice: 001 gives no value; its delta_0 is "
         "limited to 1.5 N)", "N", positive(), false,
         tactile_common::choice("001 takes delta_map slightly above f_des, gives no value")});
  m.set("reshape_gain", f.reshape_gain,
        {"r* along C_n reshaped by the force error, r*_n += gain (delta_f - delta_f_des).n dt (001 Sec. III-B1; "
         "value a choice)", "m/(N s)", at_least(0.0), false,
         tactile_common::choice("001 Sec. III-B1 gives the rule, not the gain")});
  m.set("reshape_limit", f.reshape_limit, {"|r*_n - p_n| limit (choice)", "m", positive(), false,
        tactile_common::choice()});
  m.set("reshape_follows_contact", f.reshape_follows_contact,
        {"keep only r*'s offset along C_n and carry it with the vehicle as C_n turns (curved surfaces; choice)", "", {},
         false, tactile_common::choice("curved surfaces")});
  m.set("release_force", f.release_force,
        {"averaged |force| below which contact is lost (choice)", "N", positive(), false, tactile_common::choice()});
  m.set("release_time", f.release_time, {"... for this long -> Exploration (choice)", "s", positive(), false,
        tactile_common::choice()});
  m.set("settle_time", f.settle_time,
        {"no turning trigger this long after a contact or a turn (choice)", "s", at_least(0.0), false,
         tactile_common::choice()});
  m.set("loop_closure_radius", f.loop_closure_radius,
        {"back within this of the first contact point -> loop closed (choice)", "m", positive(), false,
         tactile_common::choice()});
  m.set("loop_min_path", f.loop_min_path, {"... after at least this much traversed path (choice)", "m", positive(),
                                           false, tactile_common::choice()});
  m.set("loop_min_winding", f.loop_min_winding,
        {"... and the heading wound counter-clockwise by at least this since the first contact (choice); 0: off",
         "rad", closed(0.0, 2.0 * M_PI), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": loop closes once round, false closures 1 -> 0 on blocks 1000/2000")});
  m.set("loop_turn_min_winding", f.loop_turn_min_winding,
        {"loop closure also inside Tactile-turning once wound by this much (choice, 315 deg); 0: off", "rad",
         closed(0.0, 2.0 * M_PI), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": closure inside the last turn, held out 13300-13599 280 -> 283")});
  m.set("max_clockwise_turns_in_a_row", static_cast<int64_t>(f.max_clockwise_turns_in_a_row),
        {"a clockwise yaw-rate peak starts a turn only while fewer clockwise turns came since the last "
         "counter-clockwise one (choice); 0: never", "", closed(0, 1000), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": one clockwise turn in a row, 46/50 and 43/50")});
  m.set("turn_on_contact_lost", f.turn_on_contact_lost,
        {"contact lost in a long traversal: turn counter-clockwise about the face's end instead of Exploration "
         "(choice; needs turn_pivot)", "", {}, false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": turn on contact lost, loops 49 -> 50, 48 -> 49 of 50")});
  m.set("contact_lost_turn_min_s", f.contact_lost_turn_min_s,
        {"... when the traversal lasted at least this long (choice)", "s", at_least(0.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": turn on contact lost, 4 s (2 s: 43 and 42 of 50)")});
  m.set("contact_backoff_gain", f.contact_backoff_gain,
        {"back-off on contact from Exploration: setpoint this far per N of force, along the force (001 Sec. III-B3 "
         "collision recovery; choice, tuned)", "m/N", at_least(0.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": contact back-off, tuning 128 -> 136 of 150")});
  m.set("contact_backoff_max", f.contact_backoff_max, {"... at most this far (choice)", "m", closed(0.0, 0.5), false,
        tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": contact back-off, tuning 128 -> 136 of 150")});
  m.set("contact_backoff_time", f.contact_backoff_time,
        {"... held this long, then the traversal or wrench starts (choice); 0: off", "s", closed(0.0, 2.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": contact back-off, tuning 128 -> 136 of 150")});
  m.set("square_min_deflection", f.square_min_deflection,
        {"square up to a face slid along in Exploration: path deflected by at least this from the Exploration "
         "direction (choice, 20 deg); 0: off", "rad", ParamRange{0.0, M_PI / 2, false, true}, false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": square up, 13000 286 -> 290, 12700 288 -> 290 of 300")});
  m.set("square_window", f.square_window,
        {"... path over this long before the contact (choice)", "s", positive(), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": square up, 13000 286 -> 290, 12700 288 -> 290 of 300")});
  m.set("square_min_path", f.square_min_path, {"... at least this long (choice)", "m", at_least(0.0), false,
        tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": square up, 13000 286 -> 290, 12700 288 -> 290 of 300")});
  m.set("square_hold", f.square_hold,
        {"... after the yaw ramp at turn_rate, hold the squared yaw this long before traversing (choice)", "s",
         closed(0.0, 10.0), false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": square up, 13000 286 -> 290, 12700 288 -> 290 of 300")});
  m.set("square_to_x", f.square_to_x,
        {"... C_n = body +X, the Exploration axis (001 Sec. V-C2); false: the body axis nearest to the face normal "
         "(choice)", "", {}, false,
         tactile_common::tuned("docs/xplorer_fsm.md \"Rules beyond 001\": square up, 13000 286 -> 290, 12700 288 -> 290 of 300")});
  m.set("static_force", f.static_force,
        {"|delta_f_ref|, static-wrench reference (001 Sec. V-B: 1 N)", "N", positive(), false,
         tactile_common::paper("001 Sec. V-B: 1 N")});
  m.set("goal", std::vector<double>{f.goal.x(), f.goal.y()},
        {"ricochet / waypoint goal [x, y] in the world frame; finite", "m", {}, false, tactile_common::choice()});
  m.set("ricochet_speed", f.ricochet_speed,
        {"ricochet approach speed (001 Sec. IV-C \"maximum velocity\": the SITL controller's limit)", "m/s", positive(),
         false, tactile_common::choice("001 Sec. IV-C: the maximum velocity, here the SITL controller's limit")});
  m.set("collision_force", f.collision_force, {"|delta_f| that marks a collision (choice)", "N", positive(), false,
        tactile_common::choice()});
  m.set("restitution", f.restitution,
        {"post-collision normal speed / pre-collision (001 Fig. 7; choice)", "", closed(0.0, 1.0), false,
         tactile_common::choice("001 Fig. 7 shows the rebound, not a coefficient")});
  m.set("recovery_gain", f.recovery_gain,
        {"recovery setpoint distance per N of collision peak (choice, after 001 ref. [12])", "m/N", at_least(0.0),
         false, tactile_common::choice("after 001 ref. [12]")});
  m.set("recovery_time", f.recovery_time, {"hold the recovery setpoint this long (choice)", "s", at_least(0.0), false,
        tactile_common::choice()});
  m.set("virtual_mass", f.admittance.virtual_mass,
        {"m_v of the admittance controller (001 eq. 8, Sec. V-A3: 1)", "kg", positive(), false,
         tactile_common::paper("001 eq. 8, Sec. V-A3: 1")});
  m.set("virtual_inertia", f.admittance.virtual_inertia,
        {"I_v,z of the admittance controller (001 eq. 8, Sec. V-A3: 1)", "kg m^2", positive(), false,
         tactile_common::paper("001 eq. 8, Sec. V-A3: 1")});
  m.set("damping", std::vector<double>(f.admittance.damping.begin(), f.admittance.damping.end()),
        {"diag(D) over x, y, z, yaw (001 Sec. V-A3: 24.5, 24.5, 0, 1); each >= 0, D = K = 0: axis not in "
         "admittance", "N s/m (yaw: N m s/rad)", {}, false, tactile_common::paper("001 Sec. V-A3: 24.5, 24.5, 0, 1")});
  m.set("stiffness", std::vector<double>(f.admittance.stiffness.begin(), f.admittance.stiffness.end()),
        {"diag(K) over x, y, z, yaw (001 Sec. V-A3: 24.5, 24.5, 0, 1); each >= 0", "N/m (yaw: N m/rad)", {}, false,
         tactile_common::paper("001 Sec. V-A3: 24.5, 24.5, 0, 1")});
  m.set("frame_id", d.frame_id,
        {"world frame of the setpoints and of the wrench taken (the odometry's frame, REP 105); not empty", "", {},
         false, tactile_common::choice("REP 105")});
  m.set("max_input_age_s", d.safety.max_input_age_s,
        {"older odometry or wrench: FAILSAFE_HOVER, the last setpoint held, until both are fresh again (choice)",
         "s", positive(), false, tactile_common::choice("10 ticks of the 50 Hz whisker FSM")});
  m.set("failsafe_land_after_s", d.safety.failsafe_land_after_s,
        {"FAILSAFE_HOVER this long -> FAILSAFE_LAND (choice: the whisker FSM's 2 s)", "s", at_least(0.0), false,
         tactile_common::choice("the whisker FSM's 2 s")});
  m.set("failsafe_land_speed", d.failsafe_land_speed,
        {"FAILSAFE_LAND: the height setpoint descends from the last setpoint at this speed, x, y and yaw held "
         "(choice: the Crazyflie bridge's land_speed)", "m/s", positive(), false,
         tactile_common::choice("the Crazyflie bridge's land_speed")});
  return m;
}

XplorerFsmLogic::Params XplorerFsmLogic::params_from(const ParamMap& m) {
  Params p;
  XplorerParams& f = p.fsm;
  const std::string mission = m.get_string("mission");
  try {
    f.mission = mission_from_string(mission);
  } catch (const std::invalid_argument&) {
    throw m.error("mission", "must be explore, static_wrench, ricochet or waypoint, got \"" + mission + "\"");
  }
  f.hover_height = m.get_double("hover_height");
  f.takeoff_tolerance = m.get_double("takeoff_tolerance");
  f.explore_speed = m.get_double("explore_speed");
  f.traverse_speed = m.get_double("traverse_speed");
  f.position_gain = m.get_double("position_gain");
  f.force_average_samples = m.get_int("force_average_samples", 1, std::numeric_limits<int>::max());
  f.delta_0 = m.get_double("delta_0");
  f.delta_psi0 = m.get_double("delta_psi0");
  f.yaw_rate_trigger = m.get_double("yaw_rate_trigger");
  f.yaw_rate_lowpass_hz = m.get_double("yaw_rate_lowpass_hz");
  f.turn_rate = m.get_double("turn_rate");
  f.turn_limit = m.get_double("turn_limit");
  f.turn_push = m.get_double("turn_push");
  f.turn_pivot = m.get_bool("turn_pivot");
  f.contact_reach = m.get_double("contact_reach");
  f.turn_radius = m.get_double("turn_radius");
  f.turn_slide = m.get_double("turn_slide");
  f.turn_backoff = m.get_double("turn_backoff");
  f.turn_backoff_tau = m.get_double("turn_backoff_tau");
  f.corner_lookback = m.get_double("corner_lookback");
  f.contact_force = m.get_double("contact_force");
  f.reshape_gain = m.get_double("reshape_gain");
  f.reshape_limit = m.get_double("reshape_limit");
  f.reshape_follows_contact = m.get_bool("reshape_follows_contact");
  f.release_force = m.get_double("release_force");
  f.release_time = m.get_double("release_time");
  f.settle_time = m.get_double("settle_time");
  f.loop_closure_radius = m.get_double("loop_closure_radius");
  f.loop_min_path = m.get_double("loop_min_path");
  f.loop_min_winding = m.get_double("loop_min_winding");
  f.loop_turn_min_winding = m.get_double("loop_turn_min_winding");
  f.max_clockwise_turns_in_a_row = m.get_int("max_clockwise_turns_in_a_row", 0, 1000);
  f.turn_on_contact_lost = m.get_bool("turn_on_contact_lost");
  f.contact_lost_turn_min_s = m.get_double("contact_lost_turn_min_s");
  f.contact_backoff_gain = m.get_double("contact_backoff_gain");
  f.contact_backoff_max = m.get_double("contact_backoff_max");
  f.contact_backoff_time = m.get_double("contact_backoff_time");
  f.square_min_deflection = m.get_double("square_min_deflection");
  f.square_window = m.get_double("square_window");
  f.square_min_path = m.get_double("square_min_path");
  f.square_hold = m.get_double("square_hold");
  f.square_to_x = m.get_bool("square_to_x");
  f.static_force = m.get_double("static_force");
  const auto g = m.get_double_array("goal");
  if (g.size() != 2) throw m.error("goal", "must be [x, y], got " + std::to_string(g.size()) + " elements");
  f.goal = XVec2(g[0], g[1]);
  f.ricochet_speed = m.get_double("ricochet_speed");
  f.collision_force = m.get_double("collision_force");
  f.restitution = m.get_double("restitution");
  f.recovery_gain = m.get_double("recovery_gain");
  f.recovery_time = m.get_double("recovery_time");
  f.admittance.virtual_mass = m.get_double("virtual_mass");
  f.admittance.virtual_inertia = m.get_double("virtual_inertia");
  for (const char* key : {"damping", "stiffness"}) {
    const auto v = m.get_double_array(key);
    if (v.size() != 4) throw m.error(key, "must have 4 elements (x, y, z, yaw), got " + std::to_string(v.size()));
    auto& dst = std::string(key) == "damping" ? f.admittance.damping : f.admittance.stiffness;
    for (size_t i = 0; i < 4; ++i) dst[i] = v[i];
  }
  p.frame_id = m.get_string("frame_id");
  p.safety.max_input_age_s = m.get_double("max_input_age_s");
  p.safety.failsafe_land_after_s = m.get_double("failsafe_land_after_s");
  p.failsafe_land_speed = m.get_double("failsafe_land_speed");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw m.error_from(e);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

XplorerFsmLogic::XplorerFsmLogic(const Params& params)
    : params_((params.validate(), params)),
      fsm_(params.fsm),
      safety_(params.safety, {SafetyInput::kOdometry, SafetyInput::kForce}) {}

void XplorerFsmLogic::on_wrench(const geometry_msgs::msg::WrenchStamped& msg) {
  ++stats_.received_wrench;
  const auto& f = msg.wrench.force;
  if (!std::isfinite(f.x) || !std::isfinite(f.y) || !std::isfinite(f.z) || !std::isfinite(msg.wrench.torque.z)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  // The world-frame wrench, in the frame the FSM's setpoints are in (frame_id: odom, or
  // cf1/odom with a prefix); the body wrench (base_link, cf1/base_link) or any other
  // frame would push the admittance controller the wrong way.
  if (msg.header.frame_id != params_.frame_id) {
    ++stats_.dropped_wrong_frame;
    return;
  }
  if (wrench_ && tactile_common::from_stamp(msg.header.stamp) < tactile_common::from_stamp(wrench_->header.stamp)) {
    ++stats_.dropped_out_of_order;
    return;
  }
  wrench_ = msg;
}

void XplorerFsmLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.received_odom;
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(q.w) ||
      !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(msg.twist.twist.angular.z) ||
      (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z) < 1e-12) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (odom_ && tactile_common::from_stamp(msg.header.stamp) < tactile_common::from_stamp(odom_->header.stamp)) {
    ++stats_.dropped_out_of_order;
    return;
  }
  odom_ = msg;
}

tactile_msgs::msg::FsmState XplorerFsmLogic::state_message(int64_t now_ns) const {
  FsmState s;
  tactile_common::to_stamp(now_ns, s.header.stamp);
  s.header.frame_id = params_.frame_id;
  s.behaviour = kBehaviour;
  s.contact_direction = static_cast<uint8_t>(fsm_.contact());
  s.move_direction = static_cast<uint8_t>(fsm_.move());
  s.transitions = fsm_.transitions() + safety_transitions_;
  return s;
}

XplorerFsmLogic::Outputs XplorerFsmLogic::on_timer(int64_t now_ns) {
  ++stats_.ticks;
  Outputs out;
  const double dt = last_tick_ns_ < 0 ? tactile_common::to_seconds(kTimerPeriodNs)
                                      : tactile_common::to_seconds(now_ns - last_tick_ns_);
  last_tick_ns_ = now_ns;
  const double t = tactile_common::to_seconds(now_ns);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double odom_stamp = odom_ ? tactile_common::to_seconds(tactile_common::from_stamp(odom_->header.stamp)) : nan;
  const double wrench_stamp =
      wrench_ ? tactile_common::to_seconds(tactile_common::from_stamp(wrench_->header.stamp)) : nan;
  // Guarded from the first tick the FSM flew on (before it nothing is commanded and the
  // vehicle stays where it is): every state moves the vehicle on the odometry and the wrench.
  const SafetyVerdict v = safety_.step(t, {odom_stamp, wrench_stamp}, have_hold_);
  geometry_msgs::msg::PoseStamped sp;
  tactile_common::to_stamp(now_ns, sp.header.stamp);
  sp.header.frame_id = params_.frame_id;
  if (!v.nominal()) {
    // FAILSAFE_HOVER: the last setpoint held; FAILSAFE_LAND: its height descends. Neither
    // reads the odometry (it may be the stale input): the vehicle's position loop flies them.
    ++stats_.ticks_stale;
    double z = hold_.z();
    if (v.landing()) {
      z = std::max(kLandFloorZ, hold_.z() - params_.failsafe_land_speed * (t - safety_.entered()));
    }
    if (v.entered) {
      ++safety_transitions_;
      if (v.state == SafetyState::kFailsafeHover) ++stats_.failsafe_hovers;
      if (v.landing()) ++stats_.failsafe_landings;
    }
    if (v.entered || now_ns - last_state_ns_ >= kStatePeriodNs) {
      FsmState s = state_message(now_ns);
      s.state = to_string(v.state);
      if (v.entered) previous_state_ = v.state == SafetyState::kFailsafeHover ? to_string(last_state_) : "FAILSAFE_HOVER";
      s.previous_state = previous_state_;
      s.reason = v.text;
      s.reason_code = static_cast<uint8_t>(v.reason);
      s.time_in_state = t - safety_.entered();
      out.state = s;
      last_state_ns_ = now_ns;
      ++stats_.state_messages;
    }
    sp.pose.position.x = hold_.x();
    sp.pose.position.y = hold_.y();
    sp.pose.position.z = z;
    sp.pose.orientation.w = std::cos(0.5 * hold_yaw_);
    sp.pose.orientation.z = std::sin(0.5 * hold_yaw_);
    out.setpoint = sp;
    return out;
  }
  const double max_age = params_.safety.max_input_age_s;
  if (!input_is_fresh(t, odom_stamp, max_age) || !input_is_fresh(t, wrench_stamp, max_age)) {
    // Before the first flown tick (not guarded yet): nothing to hold.
    ++stats_.ticks_stale;
    return out;
  }
  if (v.resumed) {
    ++safety_transitions_;
    show_resume_ = true;
    resume_transitions_ = fsm_.transitions();
    resume_reason_ = fsm_.reason_code();
    resume_t_ = t;
  }
  const auto& o = *odom_;
  XplorerInput in;
  in.t = fsm_clock(t);  // the FSM's timers do not run in a fail-safe hover
  in.position = XVec3(o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z);
  in.yaw = tactile_common::yaw_of(o.pose.pose.orientation);
  in.yaw_rate = o.twist.twist.angular.z;  // body z rate ~ yaw rate near hover
  in.force = XVec3(wrench_->wrench.force.x, wrench_->wrench.force.y, wrench_->wrench.force.z);
  in.torque_z = wrench_->wrench.torque.z;
  const XplorerOutput r = fsm_.update(in, dt);
  hold_ = r.position;
  hold_yaw_ = r.yaw;
  have_hold_ = true;
  if (show_resume_ && (fsm_.transitions() != resume_transitions_ || fsm_.reason_code() != resume_reason_)) {
    show_resume_ = false;  // the FSM's own transition (or new contact) since the resume
  }
  if (v.resumed || r.transitioned || last_state_ns_ < 0 || now_ns - last_state_ns_ >= kStatePeriodNs) {
    FsmState s = state_message(now_ns);
    s.state = to_string(r.state);
    if (r.transitioned) previous_state_ = to_string(last_state_);
    if (v.resumed && !r.transitioned) previous_state_ = "FAILSAFE_HOVER";
    s.previous_state = previous_state_;
    if (show_resume_) {
      s.reason = v.text;  // the runner's last change: "inputs fresh again"
      s.reason_code = static_cast<uint8_t>(SafetyReason::kInputsFresh);
      s.time_in_state = t - resume_t_;
    } else {
      s.reason = fsm_.reason();
      s.reason_code = static_cast<uint8_t>(fsm_.reason_code());
      s.time_in_state = fsm_.time_in_state(in.t);
    }
    out.state = s;
    last_state_ns_ = now_ns;
    ++stats_.state_messages;
  }
  last_state_ = r.state;
  sp.pose.position.x = hold_.x();
  sp.pose.position.y = hold_.y();
  sp.pose.position.z = hold_.z();
  sp.pose.orientation.w = std::cos(0.5 * hold_yaw_);
  sp.pose.orientation.z = std::sin(0.5 * hold_yaw_);
  out.setpoint = sp;
  return out;
}

}  // namespace tactile_fsm
